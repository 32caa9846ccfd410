// vff_consumer_embree: the field vff_consumer wrote, placed twice in an Embree scene as user
// geometry (the component vff::embree), and one ray traced through it and through a vff::Scene.
// Usage: vff_consumer_embree consumer.vff
#include <cmath>
#include <cstdio>

#include <vff/embree.h>
#include <vff/vff.h>

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "consumer.vff";
  vff::Result<vff::File> file = vff::File::open(path);
  if (!file) {
    std::fprintf(stderr, "vff_consumer_embree: error: %s: %s\n", path, file.error().toString().c_str());
    return 3;
  }
  vff::Result<vff::FieldQuery> field = vff::FieldQuery::fromFile(*file);
  if (!field) {
    std::fprintf(stderr, "vff_consumer_embree: error: %s: %s\n", path, field.error().toString().c_str());
    return 3;
  }
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene rtc = rtcNewScene(device);
  vff::Scene scene;
  int rc = 0;
  {
    vff::embree::FieldGeometry geometries[2];
    for (unsigned i = 0; i < 2; ++i) {
      const vff::RigidTransform x = vff::RigidTransform::fromAxisAngle({0, 1, 0}, 0, {3.0f * float(i), 0, 0});
      vff::Result<vff::embree::FieldGeometry> g = vff::embree::FieldGeometry::attach(device, rtc, &*field, x, {}, i);
      if (!g || !scene.add(&*field, x)) {
        std::fprintf(stderr, "vff_consumer_embree: error: cannot place instance %u\n", i);
        return 4;
      }
      geometries[i] = std::move(*g);
    }
    rtcCommitScene(rtc);
    (void)scene.commit();
    const vff::Ray ray{{3, 0, -5}, {0, 0, 1}};
    RTCRayHit rh{};
    rh.ray.org_x = 3, rh.ray.org_z = -5, rh.ray.dir_z = 1, rh.ray.tfar = INFINITY, rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(rtc, &ctx, &rh);
    const vff::SceneHit h = scene.intersect(ray).value();
    const bool agree = h.hit && h.instance == rh.hit.geomID && h.t == rh.ray.tfar;
    std::printf("embree: geomID %u at t %.1f; vff::Scene %s\n", rh.hit.geomID, double(rh.ray.tfar),
                agree ? "agrees" : "differs");
    rc = agree ? 0 : 4;
  }
  rtcReleaseScene(rtc);
  rtcReleaseDevice(device);
  return rc;
}
