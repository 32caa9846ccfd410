// refine_section.cpp - the REFN section (spec/format.md section 14): its bytes from a refinement,
// and its checks (rules 8501-8503) when a reader or validator meets one.
#include "refine/refine_section.h"

#include <bit>
#include <cmath>
#include <string>

#include "container/le.h"

namespace vff {
namespace detail {
namespace {

uint64_t pad4(uint64_t n) { return (n + 3) & ~uint64_t(3); }

Error refineError(Code code, uint64_t offset, std::string message) {
  return makeError(code, std::move(message), kTagRefinement, offset);
}

// The first vertex of `positions` that is not finite or lies outside the field's sphere (beyond a
// relative tolerance for the sphere's binary32 rounding), or SIZE_MAX.
size_t firstVertexOutside(const FieldDesc& f, std::span<const float> positions) {
  const double r = double(f.sphere.radius) * (1.0 + 1e-4) + 1e-6;
  for (size_t v = 0; v < positions.size() / 3; ++v) {
    const double x = positions[3 * v] - double(f.sphere.center[0]), y = positions[3 * v + 1] - double(f.sphere.center[1]),
                 z = positions[3 * v + 2] - double(f.sphere.center[2]);
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || x * x + y * y + z * z > r * r) return v;
  }
  return SIZE_MAX;
}

std::string num(uint64_t v) { return std::to_string(v); }

}  // namespace

uint64_t refineUnsureBytes(const FieldDesc& f) noexcept {
  return (uint64_t(f.mapCount) * f.mapResolution * f.mapResolution + 7) / 8;
}

Status parseRefinement(const FieldDesc& f, std::span<const uint8_t> raw, RefinementView* out) {
  if (f.distanceEncoding == DistanceEncoding::kBit1)
    return refineError(Code::kRefineHeader, 0, "a bit1 field has no distances to refine: it cannot have REFN");
  if (raw.size() < kRefinementHeaderSize)
    return refineError(Code::kRefineHeader, 0, "REFN holds " + num(raw.size()) + " bytes, less than its 64-byte header");
  const uint8_t* h = raw.data();
  if (loadU32(h) != kRefinementHeaderSize)
    return refineError(Code::kRefineHeader, 0, "headerSize is " + num(loadU32(h)) + ", not 64");
  const uint32_t vertices = loadU32(h + 4), triangles = loadU32(h + 8);
  const float margin = loadF32(h + 12);
  const uint32_t unsureTexels = loadU32(h + 16);
  if (vertices < 3 || triangles < 1)
    return refineError(Code::kRefineHeader, 4, "vertexCount " + num(vertices) + " and triangleCount " + num(triangles) +
                                                   ": a refinement needs at least 3 vertices and 1 triangle");
  if (!std::isfinite(margin) || margin < 0)
    return refineError(Code::kRefineHeader, 12, "margin is not a finite number >= 0");
  for (uint32_t at = 20; at < kRefinementHeaderSize; ++at)
    if (h[at] != 0) return refineError(Code::kRefineHeader, at, "reserved REFN header bytes are not zero");
  const uint64_t bits = refineUnsureBytes(f);
  const uint64_t posAt = kRefinementHeaderSize + pad4(bits);
  const uint64_t idxAt = posAt + 12 * uint64_t(vertices);
  const uint64_t size = idxAt + 12 * uint64_t(triangles);
  if (raw.size() != size)
    return refineError(Code::kRefineHeader, 4, "REFN holds " + num(raw.size()) + " bytes; its header and the field (" +
                                                   num(f.mapCount) + " maps of " + num(f.mapResolution) + "^2 texels) give " +
                                                   num(size));
  // Rule 8502: the bits past the last texel and the padding are zero, unsureTexels counts the rest.
  const uint64_t texels = uint64_t(f.mapCount) * f.mapResolution * f.mapResolution;
  uint64_t set = 0;
  for (uint64_t b = 0; b < bits; ++b) {
    uint8_t v = h[kRefinementHeaderSize + b];
    if (b == bits - 1 && texels % 8 != 0 && (v >> (texels % 8)) != 0)
      return refineError(Code::kRefineUnsure, kRefinementHeaderSize + b, "bits past the last texel are not zero");
    set += uint64_t(std::popcount(v));
  }
  for (uint64_t b = kRefinementHeaderSize + bits; b < posAt; ++b)
    if (h[b] != 0) return refineError(Code::kRefineUnsure, b, "padding after the unsure bits is not zero");
  if (set != unsureTexels)
    return refineError(Code::kRefineUnsure, 16, "unsureTexels is " + num(unsureTexels) + " but " + num(set) +
                                                    " bits are set");
  const auto positions = std::span<const float>(reinterpret_cast<const float*>(h + posAt), size_t(vertices) * 3);
  const auto indices = std::span<const uint32_t>(reinterpret_cast<const uint32_t*>(h + idxAt), size_t(triangles) * 3);
  if (const size_t v = firstVertexOutside(f, positions); v != SIZE_MAX)
    return refineError(Code::kRefineMesh, posAt + 12 * v,
                       "vertex " + num(v) + " is not finite or lies outside the field's bounding sphere");
  for (size_t x = 0; x < indices.size(); ++x)
    if (indices[x] >= vertices)
      return refineError(Code::kRefineMesh, idxAt + 4 * x, "triangle " + num(x / 3) + " names vertex " +
                                                               num(indices[x]) + " of " + num(vertices));
  *out = RefinementView{margin, raw.subspan(kRefinementHeaderSize, size_t(bits)), unsureTexels, positions, indices};
  return {};
}

}  // namespace detail

Result<std::vector<uint8_t>> encodeRefinement(const FieldDesc& f, const RefinementView& r) {
  const uint64_t bits = detail::refineUnsureBytes(f);
  if (r.unsure.size() != bits)
    return makeError(Code::kInvalidArgument, "the refinement has " + std::to_string(r.unsure.size()) +
                                                 " bytes of unsure bits, the field needs " + std::to_string(bits));
  if (r.positions.size() % 3 != 0 || r.indices.size() % 3 != 0 || r.positions.size() / 3 > UINT32_MAX ||
      r.indices.size() / 3 > UINT32_MAX)
    return makeError(Code::kInvalidArgument, "the refinement's positions and indices must come in threes");
  const uint64_t posAt = kRefinementHeaderSize + detail::pad4(bits);
  std::vector<uint8_t> raw(posAt + 4 * r.positions.size() + 4 * r.indices.size(), 0);
  detail::store<uint32_t>(&raw[0], kRefinementHeaderSize);
  detail::store<uint32_t>(&raw[4], uint32_t(r.positions.size() / 3));
  detail::store<uint32_t>(&raw[8], uint32_t(r.indices.size() / 3));
  detail::storeF32(&raw[12], r.margin);
  detail::store<uint32_t>(&raw[16], r.unsureTexels);
  std::copy(r.unsure.begin(), r.unsure.end(), raw.begin() + kRefinementHeaderSize);
  for (size_t v = 0; v < r.positions.size(); ++v) detail::storeF32(&raw[posAt + 4 * v], r.positions[v]);
  const uint64_t idxAt = posAt + 4 * r.positions.size();
  for (size_t x = 0; x < r.indices.size(); ++x) detail::store<uint32_t>(&raw[idxAt + 4 * x], r.indices[x]);
  // The writer's checks are the reader's: a file it writes is one its reader opens.
  RefinementView parsed;
  if (Status s = detail::parseRefinement(f, raw, &parsed); !s) {
    Error e = std::move(s).error();
    e.code = Code::kInvalidArgument;
    e.offset = kNoOffset;
    return e;
  }
  return raw;
}

}  // namespace vff
