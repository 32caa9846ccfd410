// embree_test.h - what the tests of the Embree component share (test_embree.cpp,
// test_embree_paths.cpp): their fields, a bitwise float view, a ground quad and Embree rays.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "common/baked_shape.h"
#include "vff/vff.h"

namespace vff::test {

// The two fields of every test, both with normals.
inline const std::vector<std::unique_ptr<BakedShape>>& embreeFields() { return knotAndBowl(true); }

inline uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// A ground quad at y = -3 (100 wide) as two triangles, attached to `scene` at `geomID`.
inline void addGround(RTCDevice device, RTCScene scene, unsigned geomID) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 4));
  const float q[12] = {-50, -3, -50, 50, -3, -50, 50, -3, 50, -50, -3, 50};
  std::memcpy(v, q, sizeof q);
  auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 2));
  const unsigned t[6] = {0, 2, 1, 0, 3, 2};
  std::memcpy(ix, t, sizeof t);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, geomID);
  rtcReleaseGeometry(g);
}

// r as an Embree ray (id: RTCRay::id) with no hit.
inline RTCRayHit toEmbree(const Ray& r, unsigned id = 0) {
  RTCRayHit rh{};
  rh.ray.org_x = r.origin.x, rh.ray.org_y = r.origin.y, rh.ray.org_z = r.origin.z;
  rh.ray.dir_x = r.direction.x, rh.ray.dir_y = r.direction.y, rh.ray.dir_z = r.direction.z;
  rh.ray.tnear = r.tmin;
  rh.ray.tfar = r.tmax;
  rh.ray.mask = ~0u;
  rh.ray.id = id;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

}  // namespace vff::test
