// hybrid.cpp - the two-pass hybrid of vff/embree.h: a batch of rays answered against a vff::Scene
// (the moving field objects, in its batches) and then an Embree scene (the static environment, in
// packets of 16), without attaching the fields to Embree.
#include <algorithm>
#include <limits>
#include <vector>

#include "vff/embree.h"

namespace vff::embree {

namespace {

// The environment pass casts the rays the fields left in packets of 16 (rtcOccluded16,
// rtcIntersect16): for incoherent rays Embree's stream calls answer one ray at a time, its packets
// traverse 16 together.
constexpr unsigned kPacket = 16;

Status checkArguments(RTCScene environment, size_t rays, size_t out) {
  if (!environment) return makeError(Code::kInvalidArgument, "embree: null environment scene");
  if (rays != out)
    return makeError(Code::kInvalidArgument,
                     "embree: out has " + std::to_string(out) + " entries for " + std::to_string(rays) + " rays");
  return {};
}

// Lane k of a packet of 16: ray r with tfar.
void setLane(RTCRay16* p, unsigned k, const Ray& r, float tfar) {
  p->org_x[k] = r.origin.x, p->org_y[k] = r.origin.y, p->org_z[k] = r.origin.z;
  p->dir_x[k] = r.direction.x, p->dir_y[k] = r.direction.y, p->dir_z[k] = r.direction.z;
  p->tnear[k] = r.tmin, p->tfar[k] = tfar, p->mask[k] = ~0u, p->time[k] = 0, p->id[k] = 0, p->flags[k] = 0;
}

// Calls cast(valid, count, which) for the rays with want(r), 16 at a time; which[k] is lane k's ray.
template <class Want, class Cast>
void inPackets(size_t rays, Want&& want, Cast&& cast) {
  alignas(64) int valid[kPacket];
  size_t which[kPacket];
  unsigned n = 0;
  auto flush = [&] {
    if (n == 0) return;
    for (unsigned k = 0; k < kPacket; ++k) valid[k] = k < n ? -1 : 0;
    cast(valid, n, which);
    n = 0;
  };
  for (size_t r = 0; r < rays; ++r) {
    if (!want(r)) continue;
    which[n++] = r;
    if (n == kPacket) flush();
  }
  flush();
}

}  // namespace

Status occluded(RTCScene environment, const Scene& fields, std::span<const Ray> rays, std::span<const uint32_t> sources,
                std::span<uint8_t> out, const QueryOptions& options) {
  if (Status s = checkArguments(environment, rays.size(), out.size()); !s) return s;
  // 1. The fields, in vff::Scene's batches.
  if (Status s = sources.empty() ? fields.occluded(rays, out, options) : fields.occludedFrom(rays, sources, out, options);
      !s)
    return s;
  // 2. The environment, for the rays the fields did not stop.
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  inPackets(rays.size(), [&](size_t r) { return out[r] == 0; }, [&](const int* valid, unsigned n, const size_t* which) {
    RTCRay16 p;
    for (unsigned k = 0; k < kPacket; ++k) setLane(&p, k, rays[which[std::min(k, n - 1)]], rays[which[std::min(k, n - 1)]].tmax);
    rtcOccluded16(valid, environment, &context, &p);
    for (unsigned k = 0; k < n; ++k)
      if (p.tfar[k] == -std::numeric_limits<float>::infinity()) out[which[k]] = 1;
  });
  return {};
}

Status intersect(RTCScene environment, const Scene& fields, std::span<const Ray> rays,
                 std::span<const uint32_t> sources, std::span<HybridHit> out, const QueryOptions& options) {
  if (Status s = checkArguments(environment, rays.size(), out.size()); !s) return s;
  // 1. The fields, in vff::Scene's batches.
  std::vector<SceneHit> hits(rays.size());
  if (Status s = sources.empty() ? fields.intersect(rays, hits, options)
                                 : fields.intersectFrom(rays, sources, hits, options);
      !s)
    return s;
  for (size_t r = 0; r < rays.size(); ++r) {
    out[r] = HybridHit{};
    static_cast<QueryHit&>(out[r]) = hits[r];
    out[r].instance = hits[r].instance;
  }
  // 2. The environment, each ray's tfar cut to its field hit: Embree reports only what lies
  // nearer (of equal t, the field's hit stays).
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  inPackets(rays.size(), [](size_t) { return true; }, [&](const int* valid, unsigned n, const size_t* which) {
    RTCRayHit16 p;
    for (unsigned k = 0; k < kPacket; ++k) {
      const size_t r = which[std::min(k, n - 1)];
      setLane(&p.ray, k, rays[r], hits[r].hit ? hits[r].t : rays[r].tmax);
      p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, environment, &context, &p);
    for (unsigned k = 0; k < n; ++k) {
      const size_t r = which[k];
      if (p.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
      if (hits[r].hit && !(p.ray.tfar[k] < hits[r].t)) continue;
      const Ray& ray = rays[r];
      HybridHit& h = out[r];
      h = HybridHit{};
      h.hit = true;
      h.t = p.ray.tfar[k];
      h.point = {ray.origin.x + ray.direction.x * h.t, ray.origin.y + ray.direction.y * h.t,
                 ray.origin.z + ray.direction.z * h.t};
      h.normal = {p.hit.Ng_x[k], p.hit.Ng_y[k], p.hit.Ng_z[k]};
      h.hasNormal = true;
      h.geomID = p.hit.geomID[k];
      h.primID = p.hit.primID[k];
      h.u = p.hit.u[k];
      h.v = p.hit.v[k];
    }
  });
  return {};
}

}  // namespace vff::embree
