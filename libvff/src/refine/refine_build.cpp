// refine_build.cpp - marking a field's unsure texels (makeRefinement, vff/refine.h).
#include <cmath>
#include <cstring>
#include <string>

#include "platform/parallel.h"
#include "refine/refine_section.h"
#include "refine/triangle_bvh.h"
#include "vff/encoding.h"
#include "vff/positions.h"
#include "vff/query.h"
#include "vff/refine.h"

namespace vff {
namespace {

struct Hit {
  bool hit;
  float distance;
};

Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 scaled(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The probes' entry points, in mean sample spacings from the sample: the corners of a hexagon that
// holds a square cell of side one spacing (0.5 * sqrt(2) / cos 30 degrees).
constexpr float kProbeRadius = 0.82f;

}  // namespace

RefinementBvh buildRefinementBvh(const RefinementView& r) {
  RefinementBvh out;
  if (r.empty()) return out;
  const detail::TriangleBvh bvh(r.positions, r.indices);
  out.nodes.resize(bvh.nodes().size() * 8);
  std::memcpy(out.nodes.data(), bvh.nodes().data(), bvh.nodes().size_bytes());
  out.triangles.assign(bvh.triangles().begin(), bvh.triangles().end());
  return out;
}

float refineSpread(const FieldDesc& f) noexcept {
  if (f.mapCount == 0 || f.mapResolution == 0) return 0;
  const double pi = 3.14159265358979323846;
  return float(0.5 * std::sqrt(4 * pi / f.mapCount) + std::sqrt(2 * pi) / f.mapResolution);
}

Result<Refinement> makeRefinement(const FieldDesc& f, std::span<const uint8_t> distance, std::span<const float> positions,
                                  std::span<const uint32_t> indices, const RefineOptions& o) {
  if (Status s = checkFieldDesc(f); !s) return s.error();
  if (f.distanceEncoding == DistanceEncoding::kBit1)
    return makeError(Code::kUnsupported, "a bit1 field has no distances to refine");
  auto ps = PositionSet::fromField(f);
  if (!ps) return ps.error();
  const uint32_t m = f.mapResolution;
  const uint64_t mapBytes = distanceMapBytes(f.distanceEncoding, m);
  if (distance.size() != mapBytes * f.mapCount)
    return makeError(Code::kInvalidArgument, "distance plane holds " + std::to_string(distance.size()) +
                                                 " bytes, the field needs " + std::to_string(mapBytes * f.mapCount));
  if (!(o.marginSpreads >= 0) || !(o.jumpMargins > 0) || !std::isfinite(o.marginSpreads) || !std::isfinite(o.jumpMargins))
    return makeError(Code::kInvalidArgument, "marginSpreads must be >= 0 and jumpMargins > 0, both finite");

  Refinement out;
  out.margin = o.marginSpreads * refineSpread(f);
  out.positions.assign(positions.begin(), positions.end());
  out.indices.assign(indices.begin(), indices.end());
  const float jump = o.jumpMargins * std::max(out.margin, 1e-3f) * f.sphere.radius;
  const Vec3 center{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const std::vector<uint32_t> neighbours = queryNeighbours(*ps);
  // Per texel of a map: its local direction and the cosine the chord encoding decodes with.
  std::vector<Vec3> local(size_t(m) * m);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) local[size_t(j) * m + i] = texelDirection(f.directionScheme, m, i, j);
  auto decode = [&](uint32_t k, uint32_t i, uint32_t j) {
    const auto map = distance.subspan(size_t(k) * mapBytes, mapBytes);
    const Texel t = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, map, m, i, j), f.sphere.radius,
                                   local[size_t(j) * m + i].z);
    return Hit{t.hit, t.distance};
  };
  out.unsure.assign(detail::refineUnsureBytes(f), 0);
  // The mesh's checks (those the reader makes of the section) before the BVH is built from it.
  if (auto raw = encodeRefinement(f, out.view()); !raw) return std::move(raw).error();
  const detail::TriangleBvh bvh = o.probe ? detail::TriangleBvh(out.positions, out.indices) : detail::TriangleBvh();
  const float sigma = std::sqrt(4.0f * 3.14159265f / float(f.mapCount));
  const float margin = out.margin * f.sphere.radius;
  // Whether a ray through a corner of the texel's cell in ray space meets the surface otherwise
  // than the texel says (a hit against a miss, or a hit more than the margin away). The cell: entry
  // points around the sample (6 at kProbeRadius mean spacings, a hexagon around its Voronoi cell)
  // times directions in the texel (its 4 corners). Where the surface's silhouette or a depth step
  // crosses the cell as a smooth front, some corner lies beyond it.
  auto probesDisagree = [&](uint32_t k, uint32_t i, uint32_t j, const Hit& own, const Frame& frame) {
    const Vec3 uk = ps->position(k);
    const Vec2 centre = texelCenter(i, j, m);
    const float half = 0.999f / float(m);
    for (uint32_t a = 0; a < 6; ++a) {
      const float phi = float(a) * (6.2831853f / 6.0f), rr = kProbeRadius * sigma;
      const Vec3 c = add(uk, add(scaled(frame.t, rr * std::cos(phi)), scaled(frame.b, rr * std::sin(phi))));
      const Vec3 from = add(center, scaled(c, f.sphere.radius / std::sqrt(dot(c, c))));
      for (uint32_t corner = 0; corner < 4; ++corner) {
        const Vec2 uv{centre.x + ((corner & 1u) ? half : -half), centre.y + ((corner & 2u) ? half : -half)};
        const Vec3 d = toWorld(frame, squareToHemisphere(f.directionScheme, uv));
        float t = 0;
        Vec3 n;
        const bool hit = bvh.intersect(from, d, 0.0f, 2.0f * f.sphere.radius, &t, &n);
        if (hit != own.hit || (hit && std::fabs(t - own.distance) > margin)) return true;
      }
    }
    return false;
  };
  std::vector<uint8_t> flag(uint64_t(f.mapCount) * m * m, 0);
  parallel::parallelFor(f.mapCount, 16, o.threads, [&](size_t begin, size_t end) {
    for (uint32_t k = uint32_t(begin); k < end; ++k) {
      const Frame frame = ps->frame(k);
      const Vec3 pk = add(center, scaled(ps->position(k), f.sphere.radius));
      for (uint32_t j = 0; j < m; ++j) {
        for (uint32_t i = 0; i < m; ++i) {
          const Hit own = decode(k, i, j);
          const Vec3 dir = toWorld(frame, local[size_t(j) * m + i]);
          bool unsure = false;
          // A neighbour's answer, its ray starting at `from` in direction `nd`, against this texel's.
          auto differs = [&](const Hit& n, Vec3 from, Vec3 nd) {
            if (n.hit != own.hit) return true;
            if (!own.hit) return false;
            const Vec3 at = add(from, scaled(nd, n.distance));
            const float along = dot(add(at, scaled(pk, -1.0f)), dir);
            return std::fabs(along - own.distance) > jump;
          };
          for (int dj = -1; dj <= 1 && !unsure; ++dj)
            for (int di = -1; di <= 1 && !unsure; ++di) {
              const int64_t ni = int64_t(i) + di, nj = int64_t(j) + dj;
              if ((di == 0 && dj == 0) || ni < 0 || nj < 0 || ni >= m || nj >= m) continue;
              unsure = differs(decode(k, uint32_t(ni), uint32_t(nj)), pk,
                               toWorld(frame, local[size_t(nj) * m + size_t(ni)]));
            }
          for (uint32_t x = 0; x < kQueryNeighbours && !unsure; ++x) {
            const uint32_t s = neighbours[size_t(k) * kQueryNeighbours + x];
            if (s == UINT32_MAX) continue;
            const Vec3 l = toLocal(ps->frame(s), dir);
            if (!(l.z > 0)) continue;  // the direction leaves the sphere there: no ray of that map
            uint32_t si = 0, sj = 0;
            squareToTexel(hemisphereToSquare(f.directionScheme, l), m, &si, &sj);
            unsure = differs(decode(s, si, sj), add(center, scaled(ps->position(s), f.sphere.radius)), dir);
          }
          // The texels whose neighbours disagree: the probes decide.
          if (unsure && o.probe) unsure = probesDisagree(k, i, j, own, frame);
          flag[(uint64_t(k) * m + j) * m + i] = unsure;
        }
      }
    }
  });
  for (uint64_t t = 0; t < flag.size(); ++t)
    if (flag[t]) {
      out.unsure[t >> 3] |= uint8_t(1u << (t & 7u));
      ++out.unsureTexels;
    }
  return out;
}

}  // namespace vff
