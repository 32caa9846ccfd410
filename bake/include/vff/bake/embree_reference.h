// vff/bake/embree_reference.h - exact ray casts, the reference that tests and benchmarks compare fields
// to: Embree 3 on its own single-threaded scene (rtcIntersect1 / rtcOccluded1, robust mode),
// independent of the baker's packet path. Header-only; link Embree 3.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>

#include "vff/bake/mesh.h"
#include "vff/direction.h"

namespace vff::bake {

class EmbreeReference {
 public:
  explicit EmbreeReference(const Mesh& m) {
    dev_ = rtcNewDevice("threads=1");
    scene_ = rtcNewScene(dev_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(dev_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, m.vertexCount()));
    auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, m.triangleCount()));
    std::copy(m.positions.begin(), m.positions.end(), v);
    std::copy(m.indices.begin(), m.indices.end(), ix);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene_);
  }
  ~EmbreeReference() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(dev_);
  }
  EmbreeReference(const EmbreeReference&) = delete;
  EmbreeReference& operator=(const EmbreeReference&) = delete;

  // Distance to the first hit (in multiples of d) in [tnear, tfar], or a negative value for a miss.
  float cast(Vec3 o, Vec3 d, Vec3* ng = nullptr, float tnear = 0, float tfar = INFINITY) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return -1;
    if (ng) *ng = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    return rh.ray.tfar;
  }

  // True when something lies on the ray within [tnear, tfar].
  bool occluded(Vec3 o, Vec3 d, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r{};
    r.org_x = o.x;
    r.org_y = o.y;
    r.org_z = o.z;
    r.dir_x = d.x;
    r.dir_y = d.y;
    r.dir_z = d.z;
    r.tnear = tnear;
    r.tfar = tfar;
    r.mask = ~0u;
    rtcOccluded1(scene_, &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar to -inf on a hit
  }

 private:
  RTCDevice dev_;
  RTCScene scene_;
};

}  // namespace vff::bake
