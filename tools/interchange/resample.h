// resample.h - vff-convert's conversions that change the maps: a new distance encoding
// (reencode.cpp), fewer or other positional samples and smaller maps (lod.cpp), and the provenance
// entry every such conversion appends to META.
//
// One pass computes each map of the new field from the source, in three stages:
//   1. positions  (--positions / --count): each texel of an M x M map at the new sample point (M:
//      the source's), that is the ray from that point along the texel-centre direction, is
//      answered from the source field (PositionResample). Without a position change, stage 1 is
//      the source map itself;
//   2. map size   (--map-size): the stage-1 texels around each new texel (f = M / new M per side)
//      are combined by a DownsampleRule;
//   3. encoding   (--encoding): the distance is encoded with the new encoding.
// Distances travel as binary32 between the stages, so a field is quantised once, at stage 3. A
// stage that is not asked for passes texels through unchanged, and decoding then encoding a code
// with the same encoding and texel gives the same code: a conversion that changes nothing
// reproduces the maps byte for byte.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "convert.h"
#include "vff/vff.h"

namespace vff::convert {

// How stage 2 combines the source texels that cover one new texel. A texel's value is hit/miss and,
// for a hit, a distance; misses are never averaged with distances.
enum class DownsampleRule : uint8_t {
  kInvalid = 0,
  // Hit when any covered texel hits; the distance is the smallest hit distance. Occlusion is
  // conservative: a new texel never misses where a source texel hits.
  kMin = 1,
  // Hit when at least half of the covered texels hit; the distance is the mean of the hits.
  kMajority = 2,
  // The texels at the new texel's centre: the middle one for an odd factor f, the middle 2 x 2 for
  // an even f, combined as kMajority (a point sample of the new texel-centre direction, like a bake).
  kCentre = 3,
  // Every source texel whose centre lies within one new texel of the new texel's centre (a
  // (2f-1) or 2f square window, reaching into the neighbouring new texels), weighted by the tent
  // (1 - |dx|/f)(1 - |dy|/f), dx, dy its offset in source texels; hit when the hits weigh at least
  // as much as the misses; the distance is the weighted mean of the hits. The window stops at
  // the map's edge.
  kTent = 4,
};
const char* downsampleRuleName(DownsampleRule r) noexcept;  // "min", "majority", "centre", "tent"

// How stage 1 answers the ray of a new texel (from new sample point P' along direction w).
enum class PositionResample : uint8_t {
  kInvalid = 0,
  // The source sample k nearest to P' (PositionSet::nearest), its texel containing w; a hit at
  // distance d from P_k is reprojected onto the new ray: d' = max(0, d + (P_k - P') . w). Where P'
  // is a source sample (octa-hemi2 n from 2n: every new sample is one), this copies the map.
  kNearest = 1,
  // FieldQuery's Reconstruction::kInterpolated on that ray: the source samples within 1.3 mean
  // spacings, 2 x 2 texels each, every hit reprojected onto the ray, hits and misses weighted
  // separately (vff/query.h). Needs distances: not for a bit1 source.
  kInterpolated = 2,
};
const char* positionResampleName(PositionResample r) noexcept;  // "nearest", "interpolated"

struct ResampleOptions {
  std::optional<DistanceEncoding> encoding;      // unset: the source's
  uint32_t mapResolution = 0;                    // 0: the source's M; else it must divide M
  DownsampleRule downsample = DownsampleRule::kTent;  // the lowest AO error of the four (README.md)
  std::optional<PositionScheme> positionScheme;  // unset: the source's
  uint32_t positionParam = 0;                    // 0: the source's n for the same scheme, else the scheme's default
  PositionResample resample = PositionResample::kNearest;
  unsigned threads = 0;                          // 0: all cores; the result does not depend on it
};

// What a conversion did, for the tool's summary. Every value is independent of the thread count.
struct ResampleReport {
  bool positionsChanged = false, mapSizeChanged = false, encodingChanged = false;
  uint32_t factor = 1;             // source M / new M
  uint64_t sourceHits = 0;         // hit texels of the source distance plane
  uint64_t hits = 0;               // hit texels of the new distance plane
  uint64_t texels = 0;             // texels of the new distance plane
  uint64_t sourceTexels = 0;       // texels of the source distance plane
  // Stage 3, over every hit within the new encoding's scale: |decoded new distance - distance
  // before encoding|, in quantisation steps of the new encoding at that texel (0 for bit1, which
  // keeps no distance).
  // bc4-diameter: the error after the BC4 blocks (the 8-bit quantisation and the block fit).
  double maxErrorSteps = 0;
  double rmsErrorSteps = 0;        // root mean square of the same error over those hits
  double maxErrorRadii = 0;        // the same error in units of the radius R
  uint64_t clamped = 0;            // hits beyond the new encoding's scale, stored as its largest code
  double maxClampRadii = 0;        // how far beyond, at most, in units of R (not in maxErrorSteps)
  // Only for a pure re-encoding (no positions or map-size change): the hits whose new code, decoded
  // and encoded back into the source encoding, does not give the source code back. 0 means the
  // conversion is reversible (unorm8-* -> unorm16-diameter: every 8-bit code comes back, although
  // 65534 / 254 = 258.008 is no integer, so the 16-bit code is not simply 258 c).
  bool reverseChecked = false;
  uint64_t notReversible = 0;
};

// The largest payload (both planes) a conversion may produce, as vff-bake's limit: 16 GiB.
inline constexpr uint64_t kMaxResamplePayload = uint64_t{16} << 30;

// Checks `options` against the source field without touching the maps. Errors: kInvalidArgument
// (a parameter out of range: the message says which values are allowed, or a new payload above
// kMaxResamplePayload; the tool exits 1) and
// kUnsupported (a combination that cannot be done: from bit1 to a distance encoding,
// interpolated resampling of a bit1 source; exit 5).
Result<FieldDesc> planResample(const FieldDesc& source, const ResampleOptions& options);

// The converted field: the source's sphere, direction scheme, frame and normal encoding, the new
// positions, map size and encoding, metadata and codec copied (G reset to automatic when the maps
// change), layout limits copied (the gutter set to 0 for bit1; the caller recomputes the layout).
// Normal texels are copied from the source texel a value came from: the nearest sample's texel
// (for kInterpolated, the blend's normal where that texel misses); for kMin the minimum's, for the
// other rules the hit nearest the new texel's centre. A miss has a zero normal. Errors: those of
// planResample and FieldQuery::fromMaps, kOutOfMemory.
Result<FieldData> resampleField(const FieldData& source, const ResampleOptions& options, ResampleReport* report);

// The provenance entry of one conversion, appended to the array under "vff.provenance" in the
// metadata (created when absent; the other keys stay as they are): {"tool":TOOL,
// "version":VERSION,"operations":[...],"options":{...},"source":{"name":NAME,"xxh3":HEX,
// "positionScheme":..,"positionParam":..,"mapResolution":..,"distanceEncoding":..}}
// (spec/format.md, META). Errors: kMetadataJson when the metadata is not JSON, or when
// "vff.provenance" exists but is not an array.
Result<std::string> appendProvenance(const std::string& metadata, const FieldDesc& source, const FieldDesc& result,
                                     const ResampleOptions& options, const std::string& sourceName,
                                     uint64_t sourceXxh3, const char* tool = "vff-convert");

// The tool's summary of a conversion: one line per stage that changed something (or one saying
// that nothing did), the quantisation error of the new encoding and the hit counts.
std::string describeResample(const FieldDesc& source, const FieldDesc& result, const ResampleOptions& options,
                             const ResampleReport& report);

// XXH3-64 of a whole file's bytes (the "xxh3" of a provenance source). Errors: kIoOpen, kIoRead.
Result<uint64_t> fileXxh3(const std::string& path);

// Stage 3 (reencode.cpp): what encoding the texels of one thread found; merged into the report.
struct EncodeStats {
  double maxErrorSteps = 0, maxErrorRadii = 0;  // over the hits within the new scale
  double sumSquaredSteps = 0;                    // the same errors squared and summed (for the RMS)
  double maxClampRadii = 0;                      // over the clamped hits: distance - scale, in R
  uint64_t hits = 0, clamped = 0;
  void merge(const EncodeStats& o) noexcept;
};

// Stage 3 of one texel: the code of a hit at `distance` (or of a miss) in encoding `to`, its
// quantisation error accounted in `stats`. cosAlpha: z of the new texel-centre direction.
uint32_t encodeTexel(DistanceEncoding to, bool hit, float distance, float radius, float cosAlpha,
                     EncodeStats* stats) noexcept;
// Accounts the error of one hit (object-space units) in `stats`, in steps and radii.
void accountError(EncodeStats* stats, double error, float step, float radius) noexcept;

}  // namespace vff::convert
