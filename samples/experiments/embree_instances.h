// embree_instances.h - what the scene experiments share with Embree: placing an instance by a
// vff::RigidTransform, and one exact occlusion ray.
#pragma once

#include <embree3/rtcore.h>

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

}  // namespace vffx
