// vff::embree::FieldGeometry (vff/embree.h): field instances as Embree user geometry give the
// hits of vff::Scene, one ray and in packets of 16; mixed with exact triangles, the nearest of
// both; moved between frames; errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "common/baked_shape.h"
#include "embree_test.h"
#include "common/rng.h"
#include "vff/embree.h"
#include "vff/vff.h"

namespace vff {
namespace {

using test::Rng;

using test::addGround;
using test::bits;
using test::toEmbree;

const std::vector<std::unique_ptr<test::BakedShape>>& fields() { return test::embreeFields(); }

struct EmbreeWorld {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  std::vector<embree::FieldGeometry> geometries;
  ~EmbreeWorld() {
    geometries.clear();
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
};

std::vector<Ray> randomRays(Rng& rng, size_t n, float e) {
  std::vector<Ray> rays;
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    r.origin = rng.point(3 * e);
    const Vec3 target = rng.point(e);
    r.direction = {target.x - r.origin.x, target.y - r.origin.y, target.z - r.origin.z};
    if (i % 4 == 0) r.direction = rng.direction();  // also from inside spheres
    rays.push_back(r);
  }
  return rays;
}

// Compares Embree's nearest hits (one ray and packets of 16) with the scene's; with a ground,
// with the nearer of the scene and the ground. Returns the number of field hits.
size_t compare(RTCScene embreeScene, RTCScene groundOnly, const Scene& scene, const std::vector<Ray>& rays) {
  RTCIntersectContext ctx;
  size_t fieldHits = 0;
  for (size_t base = 0; base < rays.size(); base += 16) {
    RTCRayHit16 packet{};
    alignas(64) int valid[16];
    for (int k = 0; k < 16; ++k) {
      valid[k] = base + size_t(k) < rays.size() ? -1 : 0;
      if (!valid[k]) continue;
      const RTCRayHit one = toEmbree(rays[base + size_t(k)]);
      packet.ray.org_x[k] = one.ray.org_x, packet.ray.org_y[k] = one.ray.org_y, packet.ray.org_z[k] = one.ray.org_z;
      packet.ray.dir_x[k] = one.ray.dir_x, packet.ray.dir_y[k] = one.ray.dir_y, packet.ray.dir_z[k] = one.ray.dir_z;
      packet.ray.tnear[k] = one.ray.tnear, packet.ray.tfar[k] = one.ray.tfar, packet.ray.mask[k] = ~0u;
      packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcInitIntersectContext(&ctx);
    rtcIntersect16(valid, embreeScene, &ctx, &packet);
    for (int k = 0; k < 16 && base + size_t(k) < rays.size(); ++k) {
      const Ray& r = rays[base + size_t(k)];
      const SceneHit want = scene.intersect(r).value();
      float wantT = want.hit ? want.t : r.tmax;
      unsigned wantGeom = want.hit ? want.instance : RTC_INVALID_GEOMETRY_ID;
      if (groundOnly) {
        RTCRayHit g = toEmbree(r);
        rtcInitIntersectContext(&ctx);
        rtcIntersect1(groundOnly, &ctx, &g);
        if (g.hit.geomID != RTC_INVALID_GEOMETRY_ID && g.ray.tfar < wantT) wantT = g.ray.tfar, wantGeom = g.hit.geomID;
      }
      fieldHits += want.hit && wantGeom == want.instance;
      RTCRayHit one = toEmbree(r);
      rtcInitIntersectContext(&ctx);
      rtcIntersect1(embreeScene, &ctx, &one);
      EXPECT_EQ(bits(one.ray.tfar), bits(wantT)) << "ray " << base + size_t(k);
      EXPECT_EQ(bits(packet.ray.tfar[k]), bits(wantT)) << "ray " << base + size_t(k);
      // Hits at one t on two instances (none in these scenes) could go either way.
      EXPECT_EQ(one.hit.geomID, wantGeom) << "ray " << base + size_t(k);
      EXPECT_EQ(packet.hit.geomID[k], wantGeom) << "ray " << base + size_t(k);
      if (want.hit && wantGeom == want.instance) {
        EXPECT_EQ(bits(one.hit.Ng_x), bits(want.normal.x));
        EXPECT_EQ(bits(packet.hit.Ng_z[k]), bits(want.normal.z));
      }
      RTCRay shadow = toEmbree(r).ray;
      rtcInitIntersectContext(&ctx);
      rtcOccluded1(embreeScene, &ctx, &shadow);
      if (!groundOnly) {
        EXPECT_EQ(shadow.tfar < 0, scene.occluded(r).value()) << "ray " << base + size_t(k);
      }
    }
    if (::testing::Test::HasFailure()) break;
  }
  return fieldHits;
}

TEST(SceneEmbree, FieldGeometryGivesTheSceneHits) {
  Rng rng(11);
  EmbreeWorld w;
  Scene scene;
  for (uint32_t i = 0; i < 60; ++i) {
    const RigidTransform x = rng.transform(4.0f, 0.4f, 1.4f);
    ASSERT_TRUE(scene.add(&fields()[i % 2]->query, x).ok());
    auto g = embree::FieldGeometry::attach(w.device, w.scene, &fields()[i % 2]->query, x, {}, i);
    ASSERT_TRUE(g.ok()) << g.error().toString();
    EXPECT_EQ(g->geomID(), i);
    w.geometries.push_back(std::move(*g));
  }
  ASSERT_TRUE(scene.commit().ok());
  rtcCommitScene(w.scene);
  const auto rays = randomRays(rng, 1600, 4.0f);
  EXPECT_GT(compare(w.scene, nullptr, scene, rays), 200u);
  // The next frame: every instance moves.
  for (uint32_t i = 0; i < 60; ++i) {
    const RigidTransform x = rng.transform(4.0f, 0.4f, 1.4f);
    ASSERT_TRUE(scene.setTransform(i, x).ok());
    ASSERT_TRUE(w.geometries[i].setTransform(x).ok());
  }
  ASSERT_TRUE(scene.commit().ok());
  rtcCommitScene(w.scene);
  EXPECT_GT(compare(w.scene, nullptr, scene, randomRays(rng, 800, 4.0f)), 100u);
}

TEST(SceneEmbree, MixedWithTrianglesGivesTheNearerOfBoth) {
  Rng rng(12);
  EmbreeWorld w;
  RTCScene ground = rtcNewScene(w.device);
  addGround(w.device, ground, 100000);
  rtcCommitScene(ground);
  addGround(w.device, w.scene, 100000);
  Scene scene;
  for (uint32_t i = 0; i < 20; ++i) {
    const RigidTransform x = rng.transform(3.0f, 0.4f, 1.4f);
    ASSERT_TRUE(scene.add(&fields()[i % 2]->query, x).ok());
    w.geometries.push_back(embree::FieldGeometry::attach(w.device, w.scene, &fields()[i % 2]->query, x, {}, i).value());
  }
  ASSERT_TRUE(scene.commit().ok());
  rtcCommitScene(w.scene);
  EXPECT_GT(compare(w.scene, ground, scene, randomRays(rng, 800, 3.0f)), 50u);
  rtcReleaseScene(ground);
}

TEST(SceneEmbree, Errors) {
  EmbreeWorld w;
  const FieldQuery* f = &fields()[0]->query;
  EXPECT_EQ(embree::FieldGeometry::attach(w.device, w.scene, nullptr, {}).error().code, Code::kInvalidArgument);
  EXPECT_EQ(embree::FieldGeometry::attach(nullptr, w.scene, f, {}).error().code, Code::kInvalidArgument);
  RigidTransform bad;
  bad.scale = -1;
  EXPECT_EQ(embree::FieldGeometry::attach(w.device, w.scene, f, bad).error().code, Code::kInvalidArgument);
  auto g = embree::FieldGeometry::attach(w.device, w.scene, f, {});
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->setTransform(bad).error().code, Code::kInvalidArgument);
  g->detach();
  EXPECT_EQ(g->setTransform({}).error().code, Code::kBadState);
  embree::FieldGeometry none;
  EXPECT_EQ(none.setTransform({}).error().code, Code::kBadState);
}

}  // namespace
}  // namespace vff
