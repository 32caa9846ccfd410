#include <cmath>
#include <string>

#include "vff/format.h"

namespace vff {

const char* codecName(Codec codec) noexcept {
  switch (codec) {
    case Codec::kStored: return "stored";
    case Codec::kZstd: return "zstd";
  }
  return "unknown";
}

const char* filterName(Filter filter) noexcept {
  switch (filter) {
    case Filter::kNone: return "none";
    case Filter::kHitsMed: return "hits-med";
  }
  return "unknown";
}

const char* positionSchemeName(PositionScheme s) noexcept {
  switch (s) {
    case PositionScheme::kOctaHemi2: return "octa-hemi2";
    case PositionScheme::kEqualAreaOctaGrid: return "ea-octa-grid";
    case PositionScheme::kSphericalFibonacci: return "fibonacci";
    case PositionScheme::kInvalid: break;
  }
  return "invalid";
}

const char* directionSchemeName(DirectionScheme s) noexcept {
  switch (s) {
    case DirectionScheme::kConcentricEqualArea: return "concentric-equal-area";
    case DirectionScheme::kHemiOctahedral: return "hemi-octahedral";
    case DirectionScheme::kInvalid: break;
  }
  return "invalid";
}

const char* frameConventionName(FrameConvention f) noexcept {
  return f == FrameConvention::kDuff2017 ? "duff2017" : "invalid";
}

const char* distanceEncodingName(DistanceEncoding e) noexcept {
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter: return "unorm8-diameter";
    case DistanceEncoding::kUnorm8Chord: return "unorm8-chord";
    case DistanceEncoding::kUnorm16Diameter: return "unorm16-diameter";
    case DistanceEncoding::kBit1: return "bit1";
    case DistanceEncoding::kBc4Diameter: return "bc4-diameter";
    case DistanceEncoding::kInvalid: break;
  }
  return "invalid";
}

const char* normalEncodingName(NormalEncoding e) noexcept {
  switch (e) {
    case NormalEncoding::kNone: return "none";
    case NormalEncoding::kOctSnorm16: return "oct-snorm16";
  }
  return "invalid";
}

const char* layoutTargetName(LayoutTarget t) noexcept {
  switch (t) {
    case LayoutTarget::kTexture2DArray: return "2d-array";
    case LayoutTarget::kTexture3D: return "3d";
    case LayoutTarget::kInvalid: break;
  }
  return "invalid";
}

Result<uint32_t> positionCount(PositionScheme scheme, uint32_t n) {
  switch (scheme) {
    case PositionScheme::kOctaHemi2:
      if (n < 1 || n > 1024)
        return makeError(Code::kPositionScheme, "octa-hemi2 needs 1 <= n <= 1024, got " + std::to_string(n));
      return uint32_t(2 * (2 * n * n + 2 * n + 1));
    case PositionScheme::kEqualAreaOctaGrid:
      if (n < 1 || n > 2048)
        return makeError(Code::kPositionScheme, "ea-octa-grid needs 1 <= n <= 2048, got " + std::to_string(n));
      return uint32_t(n * n);
    case PositionScheme::kSphericalFibonacci:
      if (n < 1 || n > (1u << 24))
        return makeError(Code::kPositionScheme, "fibonacci needs 1 <= n <= 2^24, got " + std::to_string(n));
      return n;
    case PositionScheme::kInvalid: break;
  }
  return makeError(Code::kPositionScheme, "unknown positional-sample scheme " + std::to_string(uint32_t(scheme)));
}

uint32_t missCode(DistanceEncoding e) noexcept {
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
    case DistanceEncoding::kBc4Diameter: return 255;
    case DistanceEncoding::kUnorm16Diameter: return 65535;
    case DistanceEncoding::kBit1:
    case DistanceEncoding::kInvalid: break;
  }
  return 0;
}

uint32_t maxHitCode(DistanceEncoding e) noexcept {
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
    case DistanceEncoding::kBc4Diameter: return 254;
    case DistanceEncoding::kUnorm16Diameter: return 65534;
    case DistanceEncoding::kBit1: return 1;
    case DistanceEncoding::kInvalid: break;
  }
  return 0;
}

uint64_t distanceMapBytes(DistanceEncoding e, uint32_t m) noexcept {
  uint64_t texels = uint64_t(m) * m;
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord: return texels;
    case DistanceEncoding::kUnorm16Diameter: return texels * 2;
    case DistanceEncoding::kBit1: return (m % 8 == 0) ? texels / 8 : 0;
    case DistanceEncoding::kBc4Diameter: return (m % 4 == 0) ? texels / 2 : 0;
    case DistanceEncoding::kInvalid: break;
  }
  return 0;
}

uint64_t normalMapBytes(NormalEncoding e, uint32_t m) noexcept {
  return e == NormalEncoding::kOctSnorm16 ? uint64_t(m) * m * 4 : 0;
}

Status checkFieldDesc(const FieldDesc& d) {
  const Sphere& s = d.sphere;
  if (!std::isfinite(s.center[0]) || !std::isfinite(s.center[1]) || !std::isfinite(s.center[2]) ||
      !std::isfinite(s.radius) || !(s.radius > 0))
    return makeError(Code::kSphere, "the bounding sphere needs a finite centre and a finite radius > 0");
  auto count = positionCount(d.positionScheme, d.positionParam);
  if (!count) return count.error();
  if (*count != d.mapCount)
    return makeError(Code::kMapCount, std::string(positionSchemeName(d.positionScheme)) + " n=" +
                                          std::to_string(d.positionParam) + " yields " +
                                          std::to_string(*count) + " maps, mapCount is " +
                                          std::to_string(d.mapCount));
  if (d.directionScheme != DirectionScheme::kConcentricEqualArea &&
      d.directionScheme != DirectionScheme::kHemiOctahedral)
    return makeError(Code::kDirectionScheme, "unknown direction scheme " + std::to_string(uint32_t(d.directionScheme)));
  if (d.frame != FrameConvention::kDuff2017)
    return makeError(Code::kFrameConvention, "unknown tangent-frame convention " + std::to_string(uint32_t(d.frame)));
  if (d.distanceEncoding == DistanceEncoding::kInvalid || uint32_t(d.distanceEncoding) > 5)
    return makeError(Code::kDistanceEncoding, "unknown distance encoding " + std::to_string(uint32_t(d.distanceEncoding)));
  if (d.mapResolution < 1 || d.mapResolution > kMaxMapResolution)
    return makeError(Code::kMapResolution, "mapResolution must be in [1, " + std::to_string(kMaxMapResolution) +
                                               "], got " + std::to_string(d.mapResolution));
  if (d.distanceEncoding == DistanceEncoding::kBit1 && d.mapResolution % 8 != 0)
    return makeError(Code::kMapResolution, "bit1 maps need a mapResolution that is a multiple of 8, got " +
                                               std::to_string(d.mapResolution));
  if (d.distanceEncoding == DistanceEncoding::kBc4Diameter && d.mapResolution % 4 != 0)
    return makeError(Code::kMapResolution, "bc4-diameter maps need a mapResolution that is a multiple of 4 "
                                           "(4x4 texel blocks), got " + std::to_string(d.mapResolution));
  if (d.normalEncoding != NormalEncoding::kNone && d.normalEncoding != NormalEncoding::kOctSnorm16)
    return makeError(Code::kNormalEncoding, "unknown normal encoding " + std::to_string(uint32_t(d.normalEncoding)));
  return {};
}

}  // namespace vff
