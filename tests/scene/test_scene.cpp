// vff::Scene (vff/scene.h): every query, one ray and batched, nearest and interpolated, against the
// loop over the instances in id order (Instance's own answers), on random scenes and rays; scenes
// moved between frames; the empty scene; errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "common/baked_shape.h"
#include "common/rng.h"
#include "vff/vff.h"

namespace vff {
namespace {

using test::Rng;

// The two fields of every test: the torus knot with normals, the bowl without.
const std::vector<std::unique_ptr<test::BakedShape>>& fields() { return test::knotAndBowl(false); }

// n instances of the two fields, placed at random within extent (close enough to overlap).
std::vector<Instance> randomInstances(Rng& rng, size_t n, float extent) {
  std::vector<Instance> v;
  for (size_t i = 0; i < n; ++i) v.push_back(Instance{&fields()[i % 2]->query, rng.transform(extent, 0.3f, 1.5f)});
  return v;
}

Scene sceneOf(const std::vector<Instance>& v) {
  Scene s;
  for (size_t i = 0; i < v.size(); ++i) {
    Result<uint32_t> id = s.add(v[i].field, v[i].transform);
    EXPECT_TRUE(id.ok()) << id.error().toString();
    EXPECT_EQ(*id, i);
  }
  EXPECT_TRUE(s.commit().ok());
  return s;
}

// Rays from far away, from inside spheres, from points on the objects, with and without tmax,
// and some with a scaled direction.
std::vector<Ray> randomRays(Rng& rng, const std::vector<Instance>& v, size_t n, float extent) {
  std::vector<Ray> rays;
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    const int kind = int(i % 4);
    if (kind == 0 || v.empty()) {
      r.origin = rng.point(extent * 3);
      const Vec3 target = rng.point(extent);
      r.direction = {target.x - r.origin.x, target.y - r.origin.y, target.z - r.origin.z};
    } else {
      const Instance& in = v[i % v.size()];
      const Sphere s = in.worldSphere();
      const float k = kind == 1 ? 0.8f : 1.0f;
      const Vec3 d = rng.direction();
      r.origin = {s.center[0] + k * s.radius * d.x * rng.uniform(), s.center[1] + k * s.radius * d.y * rng.uniform(),
                  s.center[2] + k * s.radius * d.z * rng.uniform()};
      if (kind == 3) {  // a point on the object: the hit of a ray from outside, looking back out
        Ray probe{{s.center[0] + 3 * s.radius * d.x, s.center[1] + 3 * s.radius * d.y, s.center[2] + 3 * s.radius * d.z},
                  {-d.x, -d.y, -d.z}};
        const QueryHit h = in.intersect(probe);
        if (h.hit) r.origin = h.point;
      }
      r.direction = rng.direction();
    }
    const float scale = (i % 3 == 0) ? 2.5f : 1.0f;
    r.direction = {r.direction.x * scale, r.direction.y * scale, r.direction.z * scale};
    if (i % 5 == 0) r.tmax = rng.uniform(0.1f, 4.0f);
    rays.push_back(r);
  }
  return rays;
}

SceneHit loopIntersect(const std::vector<Instance>& v, const Ray& r, const QueryOptions& o) {
  SceneHit best;
  for (uint32_t i = 0; i < v.size(); ++i) {
    const QueryHit h = v[i].intersect(r, o);
    if (h.hit && h.t < best.t) {
      static_cast<QueryHit&>(best) = h;
      best.instance = i;
    }
  }
  return best;
}

bool loopOccluded(const std::vector<Instance>& v, const Ray& r, const QueryOptions& o) {
  for (const Instance& in : v)
    if (in.occluded(r, o)) return true;
  return false;
}

float loopVisibility(const std::vector<Instance>& v, const Ray& r, const QueryOptions& o) {
  float p = 1.0f;
  for (const Instance& in : v) p *= in.visibility(r, o);
  return p;
}

uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

void expectSameHit(const SceneHit& a, const SceneHit& b, size_t ray) {
  ASSERT_EQ(a.hit, b.hit) << "ray " << ray;
  ASSERT_EQ(a.instance, b.instance) << "ray " << ray;
  if (!a.hit) return;
  ASSERT_EQ(bits(a.t), bits(b.t)) << "ray " << ray;
  ASSERT_EQ(bits(a.point.x), bits(b.point.x)) << "ray " << ray;
  ASSERT_EQ(bits(a.point.z), bits(b.point.z)) << "ray " << ray;
  ASSERT_EQ(a.hasNormal, b.hasNormal) << "ray " << ray;
  ASSERT_EQ(bits(a.normal.y), bits(b.normal.y)) << "ray " << ray;
  ASSERT_EQ(a.inside, b.inside) << "ray " << ray;
}

// Every query of the scene, one ray and batched, against the loop. Returns how many rays hit.
size_t checkAgainstLoop(const Scene& scene, const std::vector<Instance>& v, const std::vector<Ray>& rays,
                        const QueryOptions& o) {
  std::vector<SceneHit> hits(rays.size());
  std::vector<uint8_t> blocked(rays.size());
  std::vector<float> vis(rays.size());
  EXPECT_TRUE(scene.intersect(rays, hits, o).ok());
  EXPECT_TRUE(scene.occluded(rays, blocked, o).ok());
  EXPECT_TRUE(scene.visibility(rays, vis, o).ok());
  size_t hitCount = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const SceneHit want = loopIntersect(v, rays[i], o);
    hitCount += want.hit;
    Result<SceneHit> one = scene.intersect(rays[i], o);
    EXPECT_TRUE(one.ok());
    expectSameHit(*one, want, i);
    expectSameHit(hits[i], want, i);
    const bool occ = loopOccluded(v, rays[i], o);
    EXPECT_EQ(scene.occluded(rays[i], o).value(), occ) << "ray " << i;
    EXPECT_EQ(blocked[i] != 0, occ) << "ray " << i;
    const float vi = loopVisibility(v, rays[i], o);
    EXPECT_EQ(bits(scene.visibility(rays[i], o).value()), bits(vi)) << "ray " << i;
    EXPECT_EQ(bits(vis[i]), bits(vi)) << "ray " << i;
    if (::testing::Test::HasFatalFailure()) return hitCount;
  }
  return hitCount;
}

TEST(Scene, RandomScenesMatchTheLoopNearest) {
  Rng rng(1);
  for (size_t n : {1, 7, 60, 300}) {
    const auto v = randomInstances(rng, n, 4.0f);
    const Scene s = sceneOf(v);
    const auto rays = randomRays(rng, v, 1500, 4.0f);
    const size_t hits = checkAgainstLoop(s, v, rays, {});
    EXPECT_GT(hits, rays.size() / 10) << n << " instances";  // the test sees hits, not just misses
  }
}

TEST(Scene, RandomScenesMatchTheLoopInterpolated) {
  Rng rng(2);
  QueryOptions o;
  o.reconstruction = Reconstruction::kInterpolated;
  for (size_t n : {3, 80}) {
    const auto v = randomInstances(rng, n, 3.0f);
    const Scene s = sceneOf(v);
    const auto rays = randomRays(rng, v, 1200, 3.0f);
    EXPECT_GT(checkAgainstLoop(s, v, rays, o), rays.size() / 10);
  }
  o.intraBias = 0;  // rays from points that are not on the objects
  const auto v = randomInstances(rng, 20, 3.0f);
  checkAgainstLoop(sceneOf(v), v, randomRays(rng, v, 800, 3.0f), o);
}

// Rays with sources: the scene's *From functions against the loop in which the source instance
// answers by section 7.3 and every other by section 7.4 (vff/scene.h), one ray and batched.
void checkSourcesAgainstLoop(const Scene& scene, const std::vector<Instance>& v, const std::vector<Ray>& rays,
                             const std::vector<uint32_t>& sources, const QueryOptions& o) {
  std::vector<SceneHit> hits(rays.size());
  std::vector<uint8_t> blocked(rays.size());
  std::vector<float> vis(rays.size());
  ASSERT_TRUE(scene.intersectFrom(rays, sources, hits, o).ok());
  ASSERT_TRUE(scene.occludedFrom(rays, sources, blocked, o).ok());
  ASSERT_TRUE(scene.visibilityFrom(rays, sources, vis, o).ok());
  for (size_t i = 0; i < rays.size(); ++i) {
    SceneHit want;
    bool occ = false;
    float vi = 1.0f;
    for (uint32_t k = 0; k < v.size(); ++k) {
      QueryOptions ok = o;
      ok.origin = k == sources[i] ? RayOrigin::kOnObject : RayOrigin::kOffObject;
      const QueryHit h = v[k].intersect(rays[i], ok);
      if (h.hit && h.t < want.t) {
        static_cast<QueryHit&>(want) = h;
        want.instance = k;
      }
      occ = occ || v[k].occluded(rays[i], ok);
      vi *= v[k].visibility(rays[i], ok);
    }
    expectSameHit(scene.intersectFrom(rays[i], sources[i], o).value(), want, i);
    expectSameHit(hits[i], want, i);
    ASSERT_EQ(scene.occludedFrom(rays[i], sources[i], o).value(), occ) << "ray " << i;
    ASSERT_EQ(blocked[i] != 0, occ) << "ray " << i;
    ASSERT_EQ(bits(scene.visibilityFrom(rays[i], sources[i], o).value()), bits(vi)) << "ray " << i;
    ASSERT_EQ(bits(vis[i]), bits(vi)) << "ray " << i;
  }
}

TEST(Scene, RaySourcesMatchTheLoop) {
  Rng rng(3);
  for (Reconstruction r : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    QueryOptions o;
    o.reconstruction = r;
    for (size_t n : {2, 40}) {
      const auto v = randomInstances(rng, n, 2.5f);  // close: the spheres overlap
      const Scene s = sceneOf(v);
      const auto rays = randomRays(rng, v, 1200, 2.5f);
      // Rays from a point on instance i % n (randomRays' kind 3) start on it; the others on none,
      // or (every seventh) on a random instance.
      std::vector<uint32_t> sources(rays.size(), kNoInstance);
      for (size_t i = 0; i < rays.size(); ++i) {
        if (i % 4 == 3) sources[i] = uint32_t(i % v.size());
        if (i % 7 == 0) sources[i] = uint32_t(rng.uniform(0, float(n) - 0.01f));
      }
      checkSourcesAgainstLoop(s, v, rays, sources, o);
      if (HasFatalFailure()) return;
    }
  }
  // Without sources, the scene answers as before: every instance by options.origin.
  const auto v = randomInstances(rng, 10, 2.5f);
  QueryOptions o;
  o.origin = RayOrigin::kOffObject;
  checkAgainstLoop(sceneOf(v), v, randomRays(rng, v, 600, 2.5f), o);
}

TEST(Scene, TiesGoToTheLowerId) {
  // The same instance twice: every hit is a tie, and the lower id wins.
  const Instance a{&fields()[0]->query, RigidTransform::fromAxisAngle({0, 1, 0}, 0.3f, {1, 0, 0})};
  const std::vector<Instance> v{Instance{&fields()[1]->query, RigidTransform::fromAxisAngle({1, 0, 0}, 0, {9, 9, 9})}, a, a};
  const Scene s = sceneOf(v);
  Rng rng(3);
  size_t hits = 0;
  const std::vector<Ray> rays = randomRays(rng, {a}, 400, 1.5f);
  std::vector<SceneHit> batch(rays.size());
  ASSERT_TRUE(s.intersect(rays, batch).ok());
  for (size_t i = 0; i < rays.size(); ++i) {
    const SceneHit h = s.intersect(rays[i]).value();
    if (h.hit && loopIntersect(v, rays[i], {}).instance == 1) {
      EXPECT_EQ(h.instance, 1u);
      EXPECT_EQ(batch[i].instance, 1u);
      ++hits;
    }
  }
  EXPECT_GT(hits, 50u);
}

TEST(Scene, TransformsUpdatedBetweenFrames) {
  Rng rng(4);
  auto v = randomInstances(rng, 200, 6.0f);
  Scene s = sceneOf(v);
  for (int frame = 0; frame < 3; ++frame) {
    for (uint32_t i = 0; i < v.size(); ++i) {
      if ((i + frame) % 2) continue;  // half of them move each frame
      v[i].transform = rng.transform(6.0f, 0.3f, 1.5f);
      ASSERT_TRUE(s.setTransform(i, v[i].transform).ok());
    }
    EXPECT_FALSE(s.committed());
    EXPECT_EQ(s.intersect(Ray{{0, 0, 0}, {1, 0, 0}}).error().code, Code::kBadState);
    ASSERT_TRUE(s.commit().ok());
    EXPECT_TRUE(s.committed());
    EXPECT_EQ(s.instance(7)->transform.translation.x, v[7].transform.translation.x);
    checkAgainstLoop(s, v, randomRays(rng, v, 600, 6.0f), {});
  }
}

TEST(Scene, ManyInstancesAreCulled) {
  // A grid of 4096 small instances: a ray along a row considers about that row, not the grid.
  std::vector<Instance> v;
  for (int x = 0; x < 16; ++x)
    for (int y = 0; y < 16; ++y)
      for (int z = 0; z < 16; ++z)
        v.push_back(Instance{&fields()[(x + y + z) % 2]->query,
                             RigidTransform::fromAxisAngle({0, 0, 1}, float(x), {3.0f * float(x), 3.0f * float(y), 3.0f * float(z)}, 0.5f)});
  const Scene s = sceneOf(v);
  const Ray row{{-5, 3.0f * 4, 3.0f * 7}, {1, 0, 0}};
  Result<std::vector<uint32_t>> c = s.candidates(row);
  ASSERT_TRUE(c.ok());
  EXPECT_GE(c->size(), 16u);
  EXPECT_LE(c->size(), 64u);
  EXPECT_TRUE(std::is_sorted(c->begin(), c->end()));
  Rng rng(5);
  checkAgainstLoop(s, v, randomRays(rng, v, 300, 24.0f), {});
}

TEST(Scene, CoincidentInstancesMatchTheLoop) {
  // 150 instances in one place (the hierarchy cannot split them by position) and one far away:
  // every hit is a 150-way tie, which the lowest id wins.
  const RigidTransform x = RigidTransform::fromAxisAngle({1, 2, 3}, 0.7f, {0.5f, 0, 0}, 1.2f);
  std::vector<Instance> v(150, Instance{&fields()[0]->query, x});
  v.push_back(Instance{&fields()[1]->query, RigidTransform::fromAxisAngle({0, 1, 0}, 0, {40, 0, 0})});
  const Scene s = sceneOf(v);
  Rng rng(6);
  EXPECT_GT(checkAgainstLoop(s, v, randomRays(rng, {v[0]}, 300, 1.5f), {}), 30u);
}

TEST(Scene, EmptySceneMissesEverything) {
  Scene never;  // never touched: committed and empty
  EXPECT_TRUE(never.committed());
  EXPECT_EQ(never.size(), 0u);
  Scene s;
  ASSERT_TRUE(s.commit().ok());
  const std::vector<Ray> rays{Ray{{0, 0, 0}, {1, 0, 0}}, Ray{{1, 2, 3}, {0, -1, 0}, 0, 5}};
  for (const Scene* sc : {&never, &s}) {
    EXPECT_FALSE(sc->intersect(rays[0])->hit);
    EXPECT_EQ(sc->intersect(rays[0])->instance, kNoInstance);
    EXPECT_FALSE(sc->occluded(rays[1]).value());
    EXPECT_EQ(sc->visibility(rays[1]).value(), 1.0f);
    std::vector<SceneHit> h(2);
    std::vector<uint8_t> b(2, 7);
    std::vector<float> vis(2, 0.5f);
    ASSERT_TRUE(sc->intersect(rays, h).ok());
    ASSERT_TRUE(sc->occluded(rays, b).ok());
    ASSERT_TRUE(sc->visibility(rays, vis).ok());
    EXPECT_FALSE(h[1].hit);
    EXPECT_EQ(b[0] + b[1], 0);
    EXPECT_EQ(vis[0] + vis[1], 2.0f);
  }
}

TEST(Scene, ErrorsAreValues) {
  const FieldQuery* f = &fields()[0]->query;
  Scene s;
  EXPECT_EQ(s.add(nullptr, {}).error().code, Code::kInvalidArgument);
  RigidTransform bad;
  bad.scale = 0;
  EXPECT_EQ(s.add(f, bad).error().code, Code::kInvalidArgument);
  bad = {};
  bad.rotation[0][0] = 2;  // not orthonormal
  EXPECT_EQ(s.add(f, bad).error().code, Code::kInvalidArgument);
  bad = {};
  bad.rotation[2][2] = -1;  // a reflection
  Result<uint32_t> refl = s.add(f, bad);
  ASSERT_FALSE(refl.ok());
  EXPECT_NE(refl.error().message.find("reflection"), std::string::npos);
  bad = {};
  bad.translation.y = std::nanf("");
  EXPECT_EQ(s.add(f, bad).error().code, Code::kInvalidArgument);
  FieldQuery empty;  // no field: its sphere has radius 0
  EXPECT_EQ(s.add(&empty, {}).error().code, Code::kSphere);
  EXPECT_EQ(s.size(), 0u);

  ASSERT_TRUE(s.add(f, {}).ok());
  EXPECT_EQ(s.occluded(Ray{{5, 0, 0}, {-1, 0, 0}}).error().code, Code::kBadState);
  std::vector<Ray> rays(3, Ray{{5, 0, 0}, {-1, 0, 0}});
  std::vector<float> vis(3);
  EXPECT_EQ(s.visibility(rays, vis).error().code, Code::kBadState);
  ASSERT_TRUE(s.commit().ok());
  std::vector<float> shortOut(2);
  EXPECT_EQ(s.visibility(rays, shortOut).error().code, Code::kInvalidArgument);
  EXPECT_EQ(s.setTransform(1, {}).error().code, Code::kOutOfRange);
  EXPECT_EQ(s.instance(5).error().code, Code::kOutOfRange);
  EXPECT_EQ(s.setTransform(0, bad).error().code, Code::kInvalidArgument);
  EXPECT_TRUE(s.committed());  // a refused move changes nothing
  EXPECT_TRUE(s.occluded(Ray{{5, 0, 0}, {-1, 0, 0}}).value());
  // Sources: one per ray, each an instance's id or kNoInstance.
  std::vector<uint32_t> sources{0, kNoInstance};
  EXPECT_EQ(s.visibilityFrom(rays, sources, vis).error().code, Code::kInvalidArgument);
  sources = {0, kNoInstance, 1};
  Status st = s.visibilityFrom(rays, sources, vis);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, Code::kOutOfRange);
  EXPECT_NE(st.error().message.find("sources[2] = 1"), std::string::npos) << st.error().message;
  EXPECT_EQ(s.occludedFrom(rays[0], 1).error().code, Code::kOutOfRange);
  EXPECT_TRUE(s.occludedFrom(rays[0], kNoInstance).value());
}

}  // namespace
}  // namespace vff
