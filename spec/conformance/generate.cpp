// generate.cpp - writes the .vff conformance vectors (see README.md in this folder).
//
//   vff-conformance-gen OUTDIR
//
// writes, deterministically (the same bytes on every run, host and thread count):
//   OUTDIR/valid/NAME.vff            small valid files covering the format's options
//   OUTDIR/valid/NAME.expected.json  what a reader must decode from each (computed from the source
//                                    data, not by reading the file back)
//   OUTDIR/invalid/ID/NAME.vff       mutations of the valid files, each raising validation ID `ID`
//   OUTDIR/invalid/ID/NAME.expect.json  what libvff does with it (validator issues, open and read
//                                    under each checksum policy), pinned KTX-CTS style
//   OUTDIR/manifest.json             every file with its XXH3-64 and whether it depends on zstd
// Files it wrote before are replaced; stale .vff/.json files under valid/ and invalid/ are removed.
//
// The generator uses libvff's public API to write the valid files and then edits bytes by hand,
// re-sealing the checksums it did not mean to break, so that each invalid file has one fault. It
// checks every vector it makes (valid ones decode to their source data; invalid ones raise their
// ID) and exits 1 on any disagreement.
//
// Its parts, one concept a file (namespace vff::gen):
//   gen_bytes.h        problems, hashes, little-endian fields, zstd frames
//   gen_vff.h          a .vff held in memory and edited by hand (sections, blocks, checksums)
//   gen_scene.h        the source data: an analytic scene and the maps computed from it
//   gen_reference.h    what the vectors decode to, written from the spec independently of libvff
//   gen_valid.h        the valid vectors, their expected.json (gen_expected_json.cpp), their check
//   gen_invalid.h      the invalid vectors, by validation ID range
//   generate.cpp       this file: writes them all, with manifest.json
#include <zstd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "conformance.h"
#include "gen_bytes.h"
#include "gen_invalid.h"
#include "gen_valid.h"
#include "vff/vff.h"

namespace fs = std::filesystem;
using namespace vff;
using namespace vff::gen;

namespace {

constexpr uint64_t kMaxJsonBytes = 200 << 10;

// Invalid cases that libvff does not handle as the format requires: generated and checked, but not
// written, so that the suite stays green; each is reported (README.md) and comes back by deleting its
// line here once the library is fixed.
// Entries look like {"invalid/4012/in-plane-section", "why (file:line)"}.
const std::map<std::string, const char*> kKnownLibraryBugs = {};

void writeFile(const fs::path& p, std::span<const uint8_t> bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream o(p, std::ios::binary | std::ios::trunc);
  o.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!o) die("cannot write " + p.string());
}
void writeText(const fs::path& p, const std::string& s) {
  writeFile(p, std::span(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
}

// Removes what an earlier run wrote (.vff and .json files under valid/ and invalid/, then the
// folders left empty), so that renamed or dropped vectors do not linger.
void clean(const fs::path& out) {
  for (const char* sub : {"valid", "invalid"}) {
    const fs::path dir = out / sub;
    if (!fs::exists(dir)) continue;
    std::vector<fs::path> files, dirs;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.is_directory())
        dirs.push_back(e.path());
      else if (e.path().extension() == ".vff" || e.path().extension() == ".json")
        files.push_back(e.path());
    }
    for (const auto& f : files) fs::remove(f);
    std::sort(dirs.rbegin(), dirs.rend());
    for (const auto& d : dirs)
      if (fs::is_empty(d)) fs::remove(d);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: vff-conformance-gen OUTDIR\n");
    return argc == 2 && std::strcmp(argv[1], "--help") == 0 ? 0 : 1;
  }
  const fs::path out = argv[1];
  fs::create_directories(out);
  clean(out);

  nlohmann::json manifest;
  manifest["format"] = "vff conformance vectors";
  manifest["vffVersion"] = std::to_string(kVersionMajor) + "." + std::to_string(kVersionMinor);
  manifest["generator"] = "vff-conformance-gen (spec/conformance/generate.cpp)";
  manifest["zstdVersion"] = ZSTD_versionString();
  manifest["zstdLevel"] = kZstdLevel;
  nlohmann::json files = nlohmann::json::object();
  auto record = [&](const std::string& rel, std::span<const uint8_t> bytes, bool zstd) {
    writeFile(out / rel, bytes);
    files[rel] = {{"size", bytes.size()}, {"xxh3", hex64(xxh(bytes))}, {"zstd", zstd}};
  };

  std::map<std::string, BuiltValid> valid;
  for (const ValidCase& c : validCases()) {
    BuiltValid v = buildValid(c);
    checkValid(v);
    const std::string json = expectedJson(v);
    if (json.size() >= kMaxJsonBytes) fail(c.name + ": expected.json is " + std::to_string(json.size()) + " bytes");
    if (!nlohmann::json::accept(json)) fail(c.name + ": expected.json is not valid JSON");
    record("valid/" + c.name + ".vff", v.bytes, v.zstd);
    record("valid/" + c.name + ".expected.json", std::span(reinterpret_cast<const uint8_t*>(json.data()), json.size()),
           v.zstd);
    valid.emplace(c.name, std::move(v));
  }

  std::map<std::string, int> names;
  for (const InvalidCase& c : invalidCases(valid)) {
    const std::string rel = "invalid/" + std::to_string(c.id) + "/" + c.name;
    if (names[rel]++) fail(rel + ": duplicate name");
    const nlohmann::json seen = conformance::observe(c.bytes);
    // The vector must raise its ID in the validator, as an error.
    bool raised = false;
    for (const auto& i : seen["validate"]) raised |= i["code"] == c.id && i["severity"] == "error";
    if (auto bug = kKnownLibraryBugs.find(rel); bug != kKnownLibraryBugs.end()) {
      // Not written while libvff gets it wrong (README.md, "Known library deviations").
      std::fprintf(stderr, "vff-conformance-gen: note: %s not written: %s%s\n", rel.c_str(), bug->second,
                   raised ? " (it now raises its ID: drop it from kKnownLibraryBugs)" : "");
      continue;
    }
    if (!raised) fail(rel + ": the validator does not report " + std::to_string(c.id) + ": " + seen.dump());
    // File::open with the default policy fails with the ID, unless the ID is one open does not check.
    const nlohmann::json& va = seen["open"]["verify-all"];
    if (conformance::isValidatorOnly(Code(c.id))) {
      const uint32_t wantRead = c.id == uint32_t(Code::kBlockDecode) ? c.id : 0;
      if (va["open"] != 0 || va["read"] != wantRead) fail(rel + ": unexpected open/read result " + va.dump());
    } else if (va["open"] != c.id) {
      fail(rel + ": File::openMemory fails with " + va["open"].dump() + ", not " + std::to_string(c.id));
    }
    nlohmann::json expect;
    expect["id"] = c.id;
    expect["name"] = codeName(Code(c.id));
    expect["base"] = "valid/" + c.base + ".vff";
    expect["mutation"] = c.mutation;
    expect["observed"] = seen;
    const std::string text = expect.dump(1) + "\n";
    record(rel + ".vff", c.bytes, c.zstd);
    record(rel + ".expect.json", std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()), c.zstd);
  }

  manifest["files"] = std::move(files);
  const std::string m = manifest.dump(1) + "\n";
  writeText(out / "manifest.json", m);
  if (failureCount()) {
    std::fprintf(stderr, "vff-conformance-gen: %d problem(s)\n", failureCount());
    return 1;
  }
  return 0;
}
