// conformance.h - the harness shared by the vector generator and the conformance/robustness tests.
//
// It observes what libvff does with a file (validator report, open and read under each checksum
// policy) in a form that can be stored next to a vector and compared later. It uses the public API
// only; it is test scaffolding, not part of libvff.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "vff/vff.h"

namespace vff::conformance {

// A problem with the file's bytes (2xxx..8xxx), as opposed to I/O (1xxx), API usage (9xxx) or mesh
// input (10xxx).
inline bool isFileProblem(Code code) noexcept {
  const auto v = uint32_t(code);
  return v >= 2000 && v < 9000;
}

// The whole file at `path` (empty when it cannot be read; the callers compare against known bytes).
inline std::vector<uint8_t> readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline constexpr ChecksumPolicy kPolicies[] = {ChecksumPolicy::kVerifyAll, ChecksumPolicy::kLazy,
                                               ChecksumPolicy::kNone};

inline const char* policyName(ChecksumPolicy p) noexcept {
  switch (p) {
    case ChecksumPolicy::kVerifyAll:
      return "verify-all";
    case ChecksumPolicy::kLazy:
      return "lazy";
    case ChecksumPolicy::kNone:
      return "none";
  }
  return "unknown";
}

// Reads what an application would: every block and map of every present plane, then every packed
// slice (slices larger than maxSliceBytes are skipped so that a hostile layout cannot make the
// harness allocate without bound). Returns the first error, or an Error with code kOk.
inline Error readEverything(const File& f, uint64_t maxSliceBytes = uint64_t{64} << 20) {
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    const PlaneInfo& pi = f.plane(p);
    if (!pi.present) continue;
    for (uint32_t b = 0; b < pi.blocks.size(); ++b) {
      auto data = f.blockData(p, b);
      if (!data) return data.error();
      if (data->size() != pi.blocks[b].rawSize)
        return makeError(Code::kBadState, "blockData size differs from rawSize");
    }
    for (uint32_t m = 0; m < f.field().mapCount; ++m) {
      auto data = f.mapData(p, m);
      if (!data) return data.error();
      if (data->size() != pi.mapBytes) return makeError(Code::kBadState, "mapData size differs from mapBytes");
    }
  }
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (!f.plane(p).present) continue;
    const uint64_t n = f.sliceBytes(p);
    if (n == 0 || n > maxSliceBytes) continue;
    std::vector<uint8_t> slice(n);
    for (uint32_t s = 0; s < f.layout().sliceCount; ++s) {
      Status st = f.readSlice(p, s, slice);
      if (!st) return st.error();
    }
  }
  return {};
}

inline nlohmann::json issueJson(const Issue& i) {
  nlohmann::json j;
  j["code"] = uint32_t(i.code);
  j["name"] = codeName(i.code);
  j["severity"] = severityName(i.severity);
  j["section"] = i.section ? nlohmann::json(sectionTagName(i.section)) : nlohmann::json(nullptr);
  j["offset"] = i.offset == kNoOffset ? nlohmann::json(nullptr) : nlohmann::json(i.offset);
  return j;
}

// What libvff does with `bytes`: the validator's issues (code, severity, section, offset; messages
// are left out, they are prose) and, for each checksum policy, the code File::openMemory fails with
// (0 when it opens) and the code readEverything() fails with (0 when everything reads, null when
// the file did not open).
inline nlohmann::json observe(std::span<const uint8_t> bytes) {
  nlohmann::json j;
  nlohmann::json issues = nlohmann::json::array();
  for (const Issue& i : validate(bytes).issues) issues.push_back(issueJson(i));
  j["validate"] = std::move(issues);
  nlohmann::json open = nlohmann::json::object();
  for (ChecksumPolicy policy : kPolicies) {
    ReadOptions ro;
    ro.checksums = policy;
    auto f = File::openMemory(bytes, ro);
    nlohmann::json o;
    if (!f) {
      o["open"] = uint32_t(f.error().code);
      o["read"] = nullptr;
    } else {
      o["open"] = 0;
      o["read"] = uint32_t(readEverything(*f).code);
    }
    open[policyName(policy)] = std::move(o);
  }
  j["open"] = std::move(open);
  return j;
}

// The validation IDs that File::open does not check (the validator does): padding bytes (4012),
// decoding compressed blocks (6010: blocks are decoded on first use, so the error comes from
// mapData/blockData) and the normal of a miss (6013).
inline bool isValidatorOnly(Code code) noexcept {
  return code == Code::kPadding || code == Code::kBlockDecode || code == Code::kValueRange;
}

}  // namespace vff::conformance
