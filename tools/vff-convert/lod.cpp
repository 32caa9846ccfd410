// lod.cpp - level of detail: a field with other positional samples (stage 1) or smaller maps
// (stage 2), computed from a larger field, and the driver of the three stages (resample.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "platform/parallel.h"
#include "resample.h"

namespace vff::convert {
namespace {

// A texel between the stages: hit/miss, the distance of a hit from its sample point (0 for bit1),
// and the raw oct-snorm16 normal of the source texel it came from (zero for a miss).
struct Value {
  bool hit = false;
  float distance = 0;
  std::array<uint8_t, 4> normal{};
};

uint32_t defaultParam(PositionScheme s) {
  switch (s) {
    case PositionScheme::kEqualAreaOctaGrid: return 65;     // 4225 maps, as vff-bake
    case PositionScheme::kSphericalFibonacci: return 4226;
    default: return 32;                                      // octa-hemi2: 4226 maps
  }
}

Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Every map resolution a source of resolution m can be reduced to (its divisors; for bit1, those
// that are multiples of 8), as "1, 2, 4".
std::string allowedSizes(uint32_t m, bool bit1) {
  std::string s;
  for (uint32_t d = 1; d <= m; ++d) {
    if (m % d != 0 || (bit1 && d % 8 != 0)) continue;
    s += (s.empty() ? "" : ", ") + std::to_string(d);
  }
  return s.empty() ? "none" : s;
}

// Reads the source field, texel by texel, and answers stage 1.
class Source {
 public:
  Source(const FieldData& d, const std::vector<Vec3>& dirs) : d_(d), dirs_(dirs) {
    m_ = d.field.mapResolution;
    radius_ = d.field.sphere.radius;
    mapBytes_ = distanceMapBytes(d.field.distanceEncoding, m_);
    normalBytes_ = normalMapBytes(d.field.normalEncoding, m_);
  }
  Value texel(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    const DistanceEncoding e = d_.field.distanceEncoding;
    const size_t t = size_t(j) * m_ + i;
    const uint32_t code = loadCode(e, {d_.distance.data() + size_t(k) * mapBytes_, mapBytes_}, m_, i, j);
    const Texel x = decodeDistance(e, code, radius_, dirs_[t].z);
    Value v;
    v.hit = x.hit;
    v.distance = x.distance;
    if (x.hit && !d_.normals.empty())
      std::copy_n(d_.normals.data() + size_t(k) * normalBytes_ + 4 * t, 4, v.normal.begin());
    return v;
  }
  uint32_t m() const noexcept { return m_; }

 private:
  const FieldData& d_;
  const std::vector<Vec3>& dirs_;  // texelDirection of each texel of an M x M map
  uint32_t m_ = 0;
  float radius_ = 0;
  uint64_t mapBytes_ = 0, normalBytes_ = 0;
};

// Stage 2: the value of new texel (i, j) from the stage-1 values of one map at the source
// resolution m (row-major, plane[y * m + x]); f = m / new M.
Value combine(const std::vector<Value>& plane, uint32_t m, uint32_t f, uint32_t i, uint32_t j, DownsampleRule rule) {
  const uint32_t x0 = i * f, y0 = j * f;
  if (f == 1) return plane[size_t(y0) * m + x0];
  if (rule == DownsampleRule::kMin) {
    const Value* best = nullptr;
    for (uint32_t y = y0; y < y0 + f; ++y)
      for (uint32_t x = x0; x < x0 + f; ++x) {
        const Value& v = plane[size_t(y) * m + x];
        if (v.hit && (!best || v.distance < best->distance)) best = &v;
      }
    return best ? *best : Value{};
  }
  // kMajority over the f x f texels, kCentre over the middle one (odd f) or the middle 2 x 2 (even
  // f), both with unit weights; kTent over every source texel whose centre lies within one new
  // texel of the new centre, weighted (1 - |dx| / f)(1 - |dy| / f), dx, dy in source texels.
  // Offsets are kept doubled (2 dx) so that they stay integers.
  int lo = 0, hi = int(f);  // the window, relative to (x0, y0)
  if (rule == DownsampleRule::kCentre) {
    lo = int(f - 1) / 2;
    hi = int(f / 2) + 1;
  } else if (rule == DownsampleRule::kTent) {
    lo = -int(f / 2);
    hi = int(f) + int(f / 2);
  }
  const int twoF = int(2 * f);
  double hitWeight = 0, missWeight = 0, sum = 0;
  const Value* nearest = nullptr;
  int nearestD2 = 0;
  for (int b = lo; b < hi; ++b)
    for (int a = lo; a < hi; ++a) {
      const int x = int(x0) + a, y = int(y0) + b;
      if (x < 0 || y < 0 || x >= int(m) || y >= int(m)) continue;  // beyond the map's edge
      const int dx = std::abs(2 * a + 1 - int(f)), dy = std::abs(2 * b + 1 - int(f));  // 2 |offset|
      double w = 1.0;
      if (rule == DownsampleRule::kTent) {
        if (dx >= twoF || dy >= twoF) continue;
        w = double(twoF - dx) * double(twoF - dy);
      }
      const Value& v = plane[size_t(y) * m + size_t(x)];
      if (!v.hit) {
        missWeight += w;
        continue;
      }
      hitWeight += w;
      sum += w * double(v.distance);
      // The hit nearest the new texel's centre gives the normal (the first in row order on ties).
      if (!nearest || dx * dx + dy * dy < nearestD2) {
        nearest = &v;
        nearestD2 = dx * dx + dy * dy;
      }
    }
  // Hit when the hits weigh at least as much as the misses (at least half of them, unweighted).
  if (!nearest || hitWeight < missWeight) return {};
  Value out = *nearest;
  out.distance = float(sum / hitWeight);
  return out;
}

// The converted field `nf` of `src` before its maps are computed: its layout, metadata, codec and
// G, and its planes allocated (zero).
Result<FieldData> newField(const FieldData& src, const FieldDesc& nf, const ResampleReport& r) {
  FieldData out;
  out.field = nf;
  out.layout = src.layout;
  if (nf.distanceEncoding == DistanceEncoding::kBit1) out.layout.gutter = 0;  // bit1 tiles have no gutters
  if (nf.distanceEncoding == DistanceEncoding::kBc4Diameter) {  // nor bc4 tiles, which only 2D arrays hold
    out.layout.gutter = 0;
    out.layout.target = LayoutTarget::kTexture2DArray;
  }
  out.metadata = src.metadata;
  out.codec = src.codec;
  // The source's G fits the source's maps; new maps get the writer's automatic G.
  out.mapsPerBlock = (r.positionsChanged || r.mapSizeChanged || r.encodingChanged) ? 0 : src.mapsPerBlock;
  try {
    out.distance.assign(size_t(nf.mapCount) * distanceMapBytes(nf.distanceEncoding, nf.mapResolution), 0);
    if (!src.normals.empty())
      out.normals.assign(size_t(nf.mapCount) * normalMapBytes(nf.normalEncoding, nf.mapResolution), 0);
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory, "cannot allocate the new field's maps");
  }
  return out;
}

// The error of a map fitted to BC4 blocks (`map`, bc4-diameter) against the distances before
// encoding (`exact`, -1 for a miss), accounted in `stats`.
void accountBc4Errors(const FieldDesc& nf, std::span<const uint8_t> map, const std::vector<float>& exact,
                      EncodeStats* stats) {
  const uint32_t nm = nf.mapResolution;
  const float radius = nf.sphere.radius;
  const float step = quantizationStep(nf.distanceEncoding, radius, 1.0f);
  for (uint32_t j = 0; j < nm; ++j)
    for (uint32_t i = 0; i < nm; ++i) {
      const float want = exact[size_t(j) * nm + i];
      if (want < 0) continue;  // a miss, and the blocks keep it one
      ++stats->hits;
      const Texel x = decodeDistance(nf.distanceEncoding, loadCode(nf.distanceEncoding, map, nm, i, j), radius, 1.0f);
      const float scale = 2.0f * radius;
      if (want > scale) {  // beyond the sphere's diameter: the largest code
        ++stats->clamped;
        stats->maxClampRadii = std::max(stats->maxClampRadii, std::fabs(double(x.distance) - want) / double(radius));
        continue;
      }
      accountError(stats, std::fabs(double(x.distance) - double(want)), step, radius);
    }
}

// The hit texels of the source's distance plane, into r->sourceHits.
void countSourceHits(const FieldData& src, ResampleReport* r) {
  const FieldDesc& sf = src.field;
  const uint32_t m = sf.mapResolution;
  const uint64_t sBytes = distanceMapBytes(sf.distanceEncoding, m);
  for (uint32_t k = 0; k < sf.mapCount; ++k)
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i)
        r->sourceHits += loadCode(sf.distanceEncoding, {src.distance.data() + size_t(k) * sBytes, sBytes}, m, i, j) !=
                         missCode(sf.distanceEncoding);
}

// For a pure re-encoding (no position or map-size change, not to bit1): how many new codes do not
// give the source code back when decoded and encoded again (r->notReversible).
void checkReversible(const FieldData& src, const FieldData& out, const std::vector<Vec3>& srcDirs,
                     ResampleReport* r) {
  const FieldDesc& sf = src.field;
  const FieldDesc& nf = out.field;
  const uint32_t m = sf.mapResolution;
  const float radius = sf.sphere.radius;
  const uint64_t sBytes = distanceMapBytes(sf.distanceEncoding, m);
  const uint64_t nBytes = distanceMapBytes(nf.distanceEncoding, nf.mapResolution);
  if (r->encodingChanged && !r->positionsChanged && !r->mapSizeChanged && nf.distanceEncoding != DistanceEncoding::kBit1) {
    r->reverseChecked = true;
    for (uint32_t k = 0; k < sf.mapCount; ++k)
      for (uint32_t j = 0; j < m; ++j)
        for (uint32_t i = 0; i < m; ++i) {
          const size_t t = size_t(j) * m + i;
          const uint32_t c = loadCode(sf.distanceEncoding, {src.distance.data() + size_t(k) * sBytes, sBytes}, m, i, j);
          const uint32_t n = loadCode(nf.distanceEncoding, {out.distance.data() + size_t(k) * nBytes, nBytes}, m, i, j);
          const Texel x = decodeDistance(nf.distanceEncoding, n, radius, srcDirs[t].z);
          r->notReversible += encodeDistance(sf.distanceEncoding, x.hit, x.distance, radius, srcDirs[t].z) != c;
        }
  }
}

}  // namespace

Result<FieldDesc> planResample(const FieldDesc& source, const ResampleOptions& o) {
  FieldDesc f = source;
  const bool bit1Source = source.distanceEncoding == DistanceEncoding::kBit1;
  if (o.encoding) {
    if (bit1Source && *o.encoding != DistanceEncoding::kBit1)
      return makeError(Code::kUnsupported, std::string("the source is bit1, which holds hit or miss and no distance: "
                                                       "it cannot be converted to ") +
                                               distanceEncodingName(*o.encoding));
    f.distanceEncoding = *o.encoding;
  }
  f.positionScheme = o.positionScheme.value_or(source.positionScheme);
  f.positionParam = o.positionParam ? o.positionParam
                    : f.positionScheme == source.positionScheme ? source.positionParam
                                                                : defaultParam(f.positionScheme);
  auto count = positionCount(f.positionScheme, f.positionParam);
  if (!count)
    return makeError(Code::kInvalidArgument, "--count " + std::to_string(f.positionParam) + " for " +
                                                 positionSchemeName(f.positionScheme) + ": " + count.error().message);
  f.mapCount = *count;
  const bool positionsChanged = f.positionScheme != source.positionScheme || f.positionParam != source.positionParam;
  if (positionsChanged && bit1Source && o.resample == PositionResample::kInterpolated)
    return makeError(
        Code::kUnsupported,
        "interpolated resampling reprojects distances, and a bit1 source has none: use --resample nearest");
  if (o.resample != PositionResample::kNearest && o.resample != PositionResample::kInterpolated)
    return makeError(Code::kInvalidArgument, "unknown resampling");
  if (o.downsample != DownsampleRule::kMin && o.downsample != DownsampleRule::kMajority &&
      o.downsample != DownsampleRule::kCentre && o.downsample != DownsampleRule::kTent)
    return makeError(Code::kInvalidArgument, "unknown downsampling rule");

  const uint32_t m = source.mapResolution;
  f.mapResolution = o.mapResolution ? o.mapResolution : m;
  const bool bit1 = f.distanceEncoding == DistanceEncoding::kBit1;
  if (!o.mapResolution && bit1 && m % 8 != 0)
    return makeError(Code::kInvalidArgument, "bit1 maps need a size that is a multiple of 8, the source's is " +
                                                 std::to_string(m) +
                                                 ": add --map-size, allowed: " + allowedSizes(m, true));
  if (f.mapResolution > m || m % f.mapResolution != 0 || (bit1 && f.mapResolution % 8 != 0))
    return makeError(Code::kInvalidArgument, "--map-size " + std::to_string(f.mapResolution) +
                                                 ": the new maps are made of whole source texels, " +
                                                 "so the size must divide the source's " + std::to_string(m) +
                                                 (bit1 ? " and be a multiple of 8 (bit1)" : "") +
                                                 "; allowed: " + allowedSizes(m, bit1));
  if (Status s = checkFieldDesc(f); !s) return makeError(Code::kInvalidArgument, s.error().message);
  const uint64_t payload = uint64_t(f.mapCount) * (distanceMapBytes(f.distanceEncoding, f.mapResolution) +
                                                   normalMapBytes(f.normalEncoding, f.mapResolution));
  if (payload > kMaxResamplePayload)
    return makeError(Code::kInvalidArgument, "the new field would hold " + std::to_string(payload) +
                                                 " bytes of maps, above vff-convert's limit of " +
                                                 std::to_string(kMaxResamplePayload) + ": fewer samples");
  return f;
}

Result<FieldData> resampleField(const FieldData& src, const ResampleOptions& o, ResampleReport* report) {
  auto plan = planResample(src.field, o);
  if (!plan) return std::move(plan).error();
  const FieldDesc& sf = src.field;
  const FieldDesc nf = *plan;
  ResampleReport r;
  r.positionsChanged = nf.positionScheme != sf.positionScheme || nf.positionParam != sf.positionParam;
  r.mapSizeChanged = nf.mapResolution != sf.mapResolution;
  r.encodingChanged = nf.distanceEncoding != sf.distanceEncoding;
  r.factor = sf.mapResolution / nf.mapResolution;

  const uint32_t m = sf.mapResolution, nm = nf.mapResolution, f = r.factor;
  const float radius = sf.sphere.radius;
  const uint64_t nBytes = distanceMapBytes(nf.distanceEncoding, nm);
  const uint64_t nNormBytes = normalMapBytes(nf.normalEncoding, nm);
  const bool normals = !src.normals.empty();

  auto made = newField(src, nf, r);
  if (!made) return std::move(made).error();
  FieldData& out = *made;
  const bool bc4 = nf.distanceEncoding == DistanceEncoding::kBc4Diameter;

  std::vector<Vec3> srcDirs(size_t(m) * m), newDirs(size_t(nm) * nm);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) srcDirs[size_t(j) * m + i] = texelDirection(sf.directionScheme, m, i, j);
  for (uint32_t j = 0; j < nm; ++j)
    for (uint32_t i = 0; i < nm; ++i) newDirs[size_t(j) * nm + i] = texelDirection(nf.directionScheme, nm, i, j);
  const Source source(src, srcDirs);

  PositionSet srcPos, newPos;
  std::optional<FieldQuery> query;
  if (r.positionsChanged) {
    auto a = PositionSet::fromField(sf);
    if (!a) return std::move(a).error();
    auto b = PositionSet::fromField(nf);
    if (!b) return std::move(b).error();
    srcPos = *a;
    newPos = *b;
    if (o.resample == PositionResample::kInterpolated) {
      auto q = FieldQuery::fromMaps(sf, src.distance, src.normals);
      if (!q) return std::move(q).error();
      query.emplace(std::move(*q));
    }
  }
  const Vec3 centre{sf.sphere.center[0], sf.sphere.center[1], sf.sphere.center[2]};
  const bool distances = sf.distanceEncoding != DistanceEncoding::kBit1;

  // One new map: stage 1 for each of its f x f sub-texels per new texel, stage 2, stage 3.
  // bc4: each map is quantised to unorm8-diameter codes in `codes`, then fitted to BC4 blocks, and the
  // error is that of the decoded blocks against the distance before encoding.
  auto doMap = [&](uint32_t k, std::vector<Value>& plane, std::vector<uint8_t>& codes, std::vector<float>& exact,
                   EncodeStats& stats) {
    Vec3 u{}, uk{};
    Frame frame{}, frameK{};
    uint32_t ks = k;  // the source map answering this map (nearest sample)
    if (r.positionsChanged) {
      u = newPos.position(k);
      frame = newPos.frame(k);
      ks = srcPos.nearest(u);
      uk = srcPos.position(ks);
      frameK = srcPos.frame(ks);
    }
    const float reproject = radius;  // (P_k - P') . w = R (u_k - u') . w
    const Vec3 du = sub(uk, u);
    auto stage1 = [&](uint32_t i, uint32_t j) -> Value {
      if (!r.positionsChanged) return source.texel(k, i, j);
      const Vec3 w = toWorld(frame, srcDirs[size_t(j) * m + i]);
      uint32_t si = 0, sj = 0;
      squareToTexel(hemisphereToSquare(sf.directionScheme, toLocal(frameK, w)), m, &si, &sj);
      Value v = source.texel(ks, si, sj);
      if (!query) {
        if (v.hit && distances) v.distance = std::max(0.0f, v.distance + reproject * dot3(du, w));
        return v;
      }
      // Interpolated: a ray from just outside the sphere through the new sample point along w.
      const float delta = 0.01f * radius;
      const Vec3 origin{centre.x + radius * u.x - delta * w.x, centre.y + radius * u.y - delta * w.y,
                        centre.z + radius * u.z - delta * w.z};
      const QueryHit h =
          query->intersect(Ray{origin, w, 0.0f, std::numeric_limits<float>::infinity()},
                           QueryOptions{.reconstruction = Reconstruction::kInterpolated, .intraBias = 0.0f});
      Value x;
      if (!h.hit) return x;
      x.hit = true;
      x.distance = std::max(0.0f, h.t - delta);
      // The normal of the nearest sample's texel when it hits, else the blend's.
      if (v.hit)
        x.normal = v.normal;
      else if (h.hasNormal)
        encodeNormal(h.normal, x.normal.data());
      return x;
    };
    for (uint32_t y = 0; y < m; ++y)
      for (uint32_t x = 0; x < m; ++x) plane[size_t(y) * m + x] = stage1(x, y);
    uint8_t* map = out.distance.data() + size_t(k) * nBytes;
    for (uint32_t j = 0; j < nm; ++j)
      for (uint32_t i = 0; i < nm; ++i) {
        const Value v = combine(plane, m, f, i, j, o.downsample);
        const size_t t = size_t(j) * nm + i;
        if (bc4) {
          codes[t] = uint8_t(encodeDistance(nf.distanceEncoding, v.hit, v.distance, radius, 1.0f));
          exact[t] = v.hit ? v.distance : -1.0f;
        } else {
          const uint32_t code = encodeTexel(nf.distanceEncoding, v.hit, v.distance, radius, newDirs[t].z, &stats);
          storeCode(nf.distanceEncoding, {map, nBytes}, nm, i, j, code);
        }
        if (normals && v.hit)
          std::copy(v.normal.begin(), v.normal.end(), out.normals.data() + size_t(k) * nNormBytes + 4 * t);
      }
    if (!bc4) return;
    encodeBc4Map(codes, nm, {map, nBytes});
    accountBc4Errors(nf, {map, nBytes}, exact, &stats);
  };

  // One map per chunk, each map's statistics apart and merged in map order, so that the report does
  // not depend on the thread count any more than the maps do; each worker its own scratch planes.
  struct Scratch {
    std::vector<Value> plane;  // stage 1 of one map, at the source resolution
    std::vector<uint8_t> codes;
    std::vector<float> exact;
  };
  std::vector<EncodeStats> stats(nf.mapCount);
  std::vector<Scratch> scratch(parallel::workerCount(nf.mapCount, 1, o.threads));
  parallel::parallelForWorkers(nf.mapCount, 1, o.threads, [&](unsigned w, size_t begin, size_t end) {
    Scratch& s = scratch[w];
    if (s.plane.empty()) {
      s.plane.resize(size_t(m) * m);
      s.codes.resize(bc4 ? size_t(nm) * nm : 0);
      s.exact.resize(s.codes.size());
    }
    for (size_t k = begin; k < end; ++k) doMap(uint32_t(k), s.plane, s.codes, s.exact, stats[k]);
  });
  EncodeStats all;
  for (const EncodeStats& s : stats) all.merge(s);

  r.texels = uint64_t(nf.mapCount) * nm * nm;
  r.sourceTexels = uint64_t(sf.mapCount) * m * m;
  r.hits = all.hits;
  r.maxErrorSteps = all.maxErrorSteps;
  r.maxErrorRadii = all.maxErrorRadii;
  r.rmsErrorSteps = all.hits > all.clamped ? std::sqrt(all.sumSquaredSteps / double(all.hits - all.clamped)) : 0.0;
  r.clamped = all.clamped;
  r.maxClampRadii = all.maxClampRadii;
  countSourceHits(src, &r);
  checkReversible(src, out, srcDirs, &r);
  if (report) *report = r;
  return out;
}

}  // namespace vff::convert
