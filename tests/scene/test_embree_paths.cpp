// vff::embree (vff/embree.h) in the forms a renderer calls it: packets of 4 and 8, streams, ray
// sources through RTCRay::id, filter functions (the geometry's and the context's), and the
// two-pass hybrid, each against vff::Scene (and Embree's own triangles for the environment).
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

using test::bits;
using test::toEmbree;

const std::vector<std::unique_ptr<test::BakedShape>>& fields() { return test::embreeFields(); }

// A scene of n instances twice: as a vff::Scene and as FieldGeometry (geomID = instance id) in an
// RTCScene, optionally with a ground quad (geomID 100000) in a scene of its own and in the
// RTCScene.
struct World {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene embree = rtcNewScene(device);
  RTCScene ground = nullptr;
  Scene scene;
  std::vector<embree::FieldGeometry> geometries;
  World(Rng& rng, uint32_t n, float extent, embree::RaySources sources, bool withGround) {
    for (uint32_t i = 0; i < n; ++i) {
      const RigidTransform x = rng.transform(extent, 0.4f, 1.4f);
      EXPECT_TRUE(scene.add(&fields()[i % 2]->query, x).ok());
      geometries.push_back(
          embree::FieldGeometry::attach(device, embree, &fields()[i % 2]->query, x, {}, i, sources).value());
    }
    if (withGround) {
      ground = rtcNewScene(device);
      test::addGround(device, ground, 100000);
      rtcCommitScene(ground);
      test::addGround(device, embree, 100000);
    }
    EXPECT_TRUE(scene.commit().ok());
    rtcCommitScene(embree);
  }
  ~World() {
    geometries.clear();
    if (ground) rtcReleaseScene(ground);
    rtcReleaseScene(embree);
    rtcReleaseDevice(device);
  }
};

// Rays from around the scene and from inside the instances' spheres, some with a short tmax; with
// each ray's source: the instance whose sphere it starts in (every other one), or none.
struct Rays {
  std::vector<Ray> rays;
  std::vector<uint32_t> sources;
};
Rays makeRays(Rng& rng, const Scene& scene, size_t n, float e) {
  Rays out;
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    uint32_t source = kNoInstance;
    if (i % 2 == 0) {
      r.origin = rng.point(3 * e);
      const Vec3 target = rng.point(e);
      r.direction = {target.x - r.origin.x, target.y - r.origin.y, target.z - r.origin.z};
    } else {
      const uint32_t id = uint32_t(i / 2 % scene.size());
      const Sphere s = scene.instance(id)->worldSphere();
      const Vec3 d = rng.direction();
      const float k = 0.9f * s.radius * rng.uniform();
      r.origin = {s.center[0] + k * d.x, s.center[1] + k * d.y, s.center[2] + k * d.z};
      r.direction = rng.direction();
      r.tmax = rng.uniform(0.2f, 2.0f) * s.radius;
      if (i % 4 == 1) source = id;
    }
    out.rays.push_back(r);
    out.sources.push_back(source);
  }
  return out;
}

TEST(SceneEmbreePaths, PacketsOf4And8AndStreamsGiveTheSceneHits) {
  Rng rng(21);
  World w(rng, 30, 3.0f, embree::RaySources::kOptions, false);
  const Rays in = makeRays(rng, w.scene, 1200, 3.0f);
  const std::vector<Ray>& rays = in.rays;
  std::vector<SceneHit> want(rays.size());
  std::vector<uint8_t> blocked(rays.size());
  ASSERT_TRUE(w.scene.intersect(rays, want).ok());
  ASSERT_TRUE(w.scene.occluded(rays, blocked).ok());
  size_t hits = 0;
  // Packets of 4 and 8, the last lanes of some invalid.
  for (size_t base = 0; base + 8 <= rays.size(); base += 8) {
    RTCRayHit4 p4[2]{};
    RTCRayHit8 p8{};
    alignas(32) int valid4[2][4], valid8[8];
    for (int k = 0; k < 8; ++k) {
      const RTCRayHit one = toEmbree(rays[base + size_t(k)]);
      const bool on = (base / 8 + size_t(k)) % 7 != 3;
      valid8[k] = valid4[k / 4][k % 4] = on ? -1 : 0;
      RTCRayHit4& q = p4[k / 4];
      const int l = k % 4;
      q.ray.org_x[l] = p8.ray.org_x[k] = one.ray.org_x, q.ray.org_y[l] = p8.ray.org_y[k] = one.ray.org_y;
      q.ray.org_z[l] = p8.ray.org_z[k] = one.ray.org_z, q.ray.dir_x[l] = p8.ray.dir_x[k] = one.ray.dir_x;
      q.ray.dir_y[l] = p8.ray.dir_y[k] = one.ray.dir_y, q.ray.dir_z[l] = p8.ray.dir_z[k] = one.ray.dir_z;
      q.ray.tnear[l] = p8.ray.tnear[k] = one.ray.tnear, q.ray.tfar[l] = p8.ray.tfar[k] = one.ray.tfar;
      q.ray.mask[l] = p8.ray.mask[k] = ~0u;
      q.hit.geomID[l] = p8.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect4(valid4[0], w.embree, &ctx, &p4[0]);
    rtcIntersect4(valid4[1], w.embree, &ctx, &p4[1]);
    rtcIntersect8(valid8, w.embree, &ctx, &p8);
    for (int k = 0; k < 8; ++k) {
      if (!valid8[k]) continue;
      const SceneHit& h = want[base + size_t(k)];
      hits += h.hit;
      const float t = h.hit ? h.t : rays[base + size_t(k)].tmax;
      ASSERT_EQ(bits(p8.ray.tfar[k]), bits(t)) << "ray " << base + size_t(k);
      ASSERT_EQ(bits(p4[k / 4].ray.tfar[k % 4]), bits(t)) << "ray " << base + size_t(k);
      ASSERT_EQ(p8.hit.geomID[k], h.hit ? h.instance : RTC_INVALID_GEOMETRY_ID);
    }
  }
  EXPECT_GT(hits, rays.size() / 10);
  // Streams: rtcIntersect1M and rtcOccluded1M over all the rays.
  std::vector<RTCRayHit> stream;
  std::vector<RTCRay> shadow;
  for (const Ray& r : rays) stream.push_back(toEmbree(r)), shadow.push_back(toEmbree(r).ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcIntersect1M(w.embree, &ctx, stream.data(), unsigned(stream.size()), sizeof(RTCRayHit));
  rtcInitIntersectContext(&ctx);
  rtcOccluded1M(w.embree, &ctx, shadow.data(), unsigned(shadow.size()), sizeof(RTCRay));
  for (size_t r = 0; r < rays.size(); ++r) {
    ASSERT_EQ(bits(stream[r].ray.tfar), bits(want[r].hit ? want[r].t : rays[r].tmax)) << "ray " << r;
    ASSERT_EQ(stream[r].hit.geomID, want[r].hit ? want[r].instance : RTC_INVALID_GEOMETRY_ID) << "ray " << r;
    ASSERT_EQ(shadow[r].tfar < 0, blocked[r] != 0) << "ray " << r;
  }
}

TEST(SceneEmbreePaths, RayIdSourcesAnswerAsTheScenesFromCalls) {
  Rng rng(22);
  World w(rng, 24, 2.0f, embree::RaySources::kRayId, false);  // close: the spheres overlap
  const Rays in = makeRays(rng, w.scene, 1600, 2.0f);
  std::vector<SceneHit> want(in.rays.size());
  std::vector<uint8_t> blocked(in.rays.size()), plain(in.rays.size());
  ASSERT_TRUE(w.scene.intersectFrom(in.rays, in.sources, want).ok());
  ASSERT_TRUE(w.scene.occludedFrom(in.rays, in.sources, blocked).ok());
  ASSERT_TRUE(w.scene.occluded(in.rays, plain).ok());
  size_t differ = 0;
  for (size_t r = 0; r < in.rays.size(); ++r) {
    const unsigned id = in.sources[r] == kNoInstance ? RTC_INVALID_GEOMETRY_ID : in.sources[r];
    RTCRayHit one = toEmbree(in.rays[r], id);
    RTCRay shadow = toEmbree(in.rays[r], id).ray;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(w.embree, &ctx, &one);
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(w.embree, &ctx, &shadow);
    ASSERT_EQ(bits(one.ray.tfar), bits(want[r].hit ? want[r].t : in.rays[r].tmax)) << "ray " << r;
    ASSERT_EQ(one.hit.geomID, want[r].hit ? want[r].instance : RTC_INVALID_GEOMETRY_ID) << "ray " << r;
    ASSERT_EQ(shadow.tfar < 0, blocked[r] != 0) << "ray " << r;
    differ += blocked[r] != plain[r];
  }
  EXPECT_GT(differ, 0u);  // the sources change answers: the test sees them
}

// An intersect filter that rejects every hit on an odd geomID; an occluded one, every hit farther
// than 1.5 along the ray.
void rejectOdd(const RTCFilterFunctionNArguments* a) {
  for (unsigned i = 0; i < a->N; ++i)
    if (a->valid[i] == -1 && RTCHitN_geomID(a->hit, a->N, i) % 2 == 1) a->valid[i] = 0;
}
void rejectFar(const RTCFilterFunctionNArguments* a) {
  for (unsigned i = 0; i < a->N; ++i)
    if (a->valid[i] == -1 && RTCRayN_tfar(a->ray, a->N, i) > 1.5f) a->valid[i] = 0;
}
void rejectAll(const RTCFilterFunctionNArguments* a) {
  for (unsigned i = 0; i < a->N; ++i) a->valid[i] = 0;
}

TEST(SceneEmbreePaths, FilterFunctionsSeeAndRejectHits) {
  Rng rng(23);
  World w(rng, 20, 3.0f, embree::RaySources::kOptions, false);
  for (embree::FieldGeometry& g : w.geometries) {
    ASSERT_TRUE(g.setIntersectFilter(rejectOdd).ok());
    ASSERT_TRUE(g.setOccludedFilter(rejectFar).ok());
  }
  rtcCommitScene(w.embree);
  // The even instances alone: what the intersect filter leaves.
  Scene even;
  for (uint32_t i = 0; i < w.scene.size(); ++i) {
    const Instance x = w.scene.instance(i).value();
    ASSERT_TRUE(even.add(x.field, x.transform).ok());
    if (i % 2 == 1) {
      ASSERT_TRUE(even.setTransform(i, RigidTransform::fromAxisAngle({0, 1, 0}, 0, {1e4f, 0, 0})).ok());
    }
  }
  ASSERT_TRUE(even.commit().ok());
  const Rays in = makeRays(rng, w.scene, 1000, 3.0f);
  size_t rejected = 0;
  for (size_t r = 0; r < in.rays.size(); ++r) {
    const Ray& ray = in.rays[r];
    const SceneHit e = even.intersect(ray).value();
    RTCRayHit one = toEmbree(ray);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(w.embree, &ctx, &one);
    ASSERT_EQ(bits(one.ray.tfar), bits(e.hit ? e.t : ray.tmax)) << "ray " << r;
    ASSERT_EQ(one.hit.geomID, e.hit ? e.instance : RTC_INVALID_GEOMETRY_ID) << "ray " << r;
    // Occlusion: some instance's hit lies within 1.5 (the filter rejects the rest).
    bool near = false;
    for (uint32_t i = 0; i < w.scene.size(); ++i) {
      const QueryHit h = w.scene.instance(i)->intersect(ray);
      near = near || (h.hit && h.t <= 1.5f);
    }
    RTCRay shadow = toEmbree(ray).ray;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(w.embree, &ctx, &shadow);
    ASSERT_EQ(shadow.tfar < 0, near) << "ray " << r;
    rejected += w.scene.occluded(ray).value() && !near;
    // The context's filter: every hit rejected.
    RTCRayHit none = toEmbree(ray);
    rtcInitIntersectContext(&ctx);
    ctx.filter = rejectAll;
    rtcIntersect1(w.embree, &ctx, &none);
    ASSERT_EQ(none.hit.geomID, RTC_INVALID_GEOMETRY_ID) << "ray " << r;
    ASSERT_EQ(bits(none.ray.tfar), bits(ray.tmax)) << "ray " << r;
  }
  EXPECT_GT(rejected, 0u);
}

TEST(SceneEmbreePaths, TwoPassHybridGivesTheNearerOfBoth) {
  Rng rng(24);
  World w(rng, 40, 3.0f, embree::RaySources::kOptions, true);
  const Rays in = makeRays(rng, w.scene, 2000, 3.0f);
  for (const bool withSources : {false, true}) {
    const std::span<const uint32_t> sources = withSources ? std::span<const uint32_t>(in.sources) : std::span<const uint32_t>{};
    std::vector<embree::HybridHit> hits(in.rays.size());
    std::vector<uint8_t> blocked(in.rays.size());
    ASSERT_TRUE(embree::intersect(w.ground, w.scene, in.rays, sources, hits).ok());
    ASSERT_TRUE(embree::occluded(w.ground, w.scene, in.rays, sources, blocked).ok());
    size_t ground = 0, field = 0;
    for (size_t r = 0; r < in.rays.size(); ++r) {
      const Ray& ray = in.rays[r];
      const SceneHit f = withSources ? w.scene.intersectFrom(ray, in.sources[r]).value() : w.scene.intersect(ray).value();
      const bool fo = withSources ? w.scene.occludedFrom(ray, in.sources[r]).value() : w.scene.occluded(ray).value();
      RTCRayHit g = toEmbree(ray);
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      rtcIntersect1(w.ground, &ctx, &g);
      const bool groundNearer = g.hit.geomID != RTC_INVALID_GEOMETRY_ID && (!f.hit || g.ray.tfar < f.t);
      ASSERT_EQ(hits[r].hit, f.hit || groundNearer) << "ray " << r;
      ASSERT_EQ(blocked[r] != 0, fo || g.hit.geomID != RTC_INVALID_GEOMETRY_ID) << "ray " << r;
      if (groundNearer) {
        ++ground;
        ASSERT_EQ(hits[r].geomID, 100000u);
        ASSERT_EQ(hits[r].instance, kNoInstance);
        ASSERT_EQ(bits(hits[r].t), bits(g.ray.tfar)) << "ray " << r;
      } else if (f.hit) {
        ++field;
        ASSERT_EQ(hits[r].instance, f.instance);
        ASSERT_EQ(hits[r].geomID, RTC_INVALID_GEOMETRY_ID);
        ASSERT_EQ(bits(hits[r].t), bits(f.t)) << "ray " << r;
      }
    }
    EXPECT_GT(ground, in.rays.size() / 20);
    EXPECT_GT(field, in.rays.size() / 20);
  }
  // Errors.
  std::vector<uint8_t> shortOut(3);
  EXPECT_EQ(embree::occluded(w.ground, w.scene, in.rays, {}, shortOut).error().code, Code::kInvalidArgument);
  std::vector<uint8_t> out(in.rays.size());
  EXPECT_EQ(embree::occluded(nullptr, w.scene, in.rays, {}, out).error().code, Code::kInvalidArgument);
  std::vector<uint32_t> bad(in.rays.size(), 999);
  EXPECT_EQ(embree::occluded(w.ground, w.scene, in.rays, bad, out).error().code, Code::kOutOfRange);
}

}  // namespace
}  // namespace vff
