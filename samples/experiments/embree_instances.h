// embree_instances.h - what the scene experiments share with Embree: placing an instance by a
// vff::RigidTransform, one exact occlusion ray, packets of 16.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstdint>

#include "vff/query.h"

namespace vffx {

// Sets an instance geometry's transform (Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR: the 3 x 4 matrix
// [R s | t] row by row) and commits the geometry.
inline void setEmbreeTransform(RTCGeometry g, const vff::RigidTransform& x) {
  float m[12];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m[4 * r + c] = x.rotation[r][c] * x.scale;
  m[3] = x.translation.x, m[7] = x.translation.y, m[11] = x.translation.z;
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
  rtcCommitGeometry(g);
}

// True when `scene` blocks the ray within [tmin, tmax].
inline bool occluded1(RTCScene scene, const vff::Ray& r) {
  RTCRay ray{};
  ray.org_x = r.origin.x, ray.org_y = r.origin.y, ray.org_z = r.origin.z;
  ray.dir_x = r.direction.x, ray.dir_y = r.direction.y, ray.dir_z = r.direction.z;
  ray.tnear = r.tmin, ray.tfar = r.tmax, ray.mask = ~0u;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded1(scene, &ctx, &ray);
  return ray.tfar < 0;
}

// Rays [lo, hi) in packets of 16 (rtcOccluded16; the last one part-filled), ray i's id ids[i]
// (none: 0); out[i] = 1 where occluded.
inline void occluded16(RTCScene scene, const vff::Ray* rays, const unsigned* ids, uint64_t lo, uint64_t hi,
                       uint8_t* out) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (uint64_t b = lo; b < hi; b += 16) {
    alignas(64) int valid[16];
    RTCRay16 p;
    for (unsigned k = 0; k < 16; ++k) {
      const uint64_t i = std::min(b + k, hi - 1);  // (invalid lanes repeat the last ray)
      const vff::Ray& r = rays[i];
      valid[k] = b + k < hi ? -1 : 0;
      p.org_x[k] = r.origin.x, p.org_y[k] = r.origin.y, p.org_z[k] = r.origin.z;
      p.dir_x[k] = r.direction.x, p.dir_y[k] = r.direction.y, p.dir_z[k] = r.direction.z;
      p.tnear[k] = r.tmin, p.tfar[k] = r.tmax, p.mask[k] = ~0u, p.id[k] = ids ? ids[i] : 0u, p.time[k] = 0,
      p.flags[k] = 0;
    }
    rtcOccluded16(valid, scene, &ctx, &p);
    for (unsigned k = 0; k < 16 && b + k < hi; ++k) out[b + k] = p.tfar[k] < 0;
  }
}

}  // namespace vffx
