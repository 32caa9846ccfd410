// vff::Scene::hierarchy (vff/scene_hierarchy.h): the exported flat hierarchy is the one the
// queries walk. A plain walker over the export (slab tests of every reached child, no order, no
// culling by hits) must reach exactly the instances Scene::candidates lists, on random scenes
// and rays; every instance is in one leaf; depth bounds the walk's stack; errors are values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/vff.h"

namespace vff {
namespace {

const FieldQuery& field() {
  static const FieldQuery* q = [] {
    auto scene = bake::Scene::create(bake::makeShape("torus-knot"));
    EXPECT_TRUE(scene.ok());
    bake::BakeOptions o;
    o.positionParam = 4;
    o.mapResolution = 8;
    static auto baked = bake::bakeField(*scene, o);
    EXPECT_TRUE(baked.ok());
    auto f = FieldQuery::fromMaps(baked->field, baked->distance, baked->normals);
    EXPECT_TRUE(f.ok()) << f.error().toString();
    return new FieldQuery(std::move(*f));
  }();
  return *q;
}

// The ids whose boxes the segment [0, tmax] reaches, by the export alone; *maxStack: the most
// entries the walk's stack held.
std::vector<uint32_t> walk(const SceneHierarchy& h, const Ray& r, uint32_t* maxStack) {
  std::vector<uint32_t> ids;
  *maxStack = 0;
  if (h.nodes.empty()) return ids;
  const float o[3] = {r.origin.x, r.origin.y, r.origin.z};
  const float d[3] = {r.direction.x, r.direction.y, r.direction.z};
  float inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = 1.0f / (d[a] == 0 ? 1e-30f : d[a]);
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const SceneNode& n = h.nodes[stack.back()];
    stack.pop_back();
    for (int c = 0; c < 4; ++c) {
      if (!(n.valid & (1u << c))) continue;
      float tn = 0, tf = r.tmax;
      for (int a = 0; a < 3; ++a) {
        const float t1 = (n.lo[a][c] - o[a]) * inv[a], t2 = (n.hi[a][c] - o[a]) * inv[a];
        tn = std::max(tn, std::min(t1, t2));
        tf = std::min(tf, std::max(t1, t2));
      }
      if (!(tn <= tf)) continue;
      if (n.count[c] == 0) {
        stack.push_back(n.child[c]);
      } else {
        for (uint32_t i = 0; i < n.count[c]; ++i) ids.push_back(h.order[n.child[c] + i]);
      }
    }
    *maxStack = std::max(*maxStack, uint32_t(stack.size()));
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

TEST(SceneHierarchy, WalkingTheExportReachesTheCandidates) {
  std::mt19937_64 g(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (uint32_t count : {1u, 2u, 5u, 40u, 700u}) {
    Scene scene;
    const float world = 2.0f * std::cbrt(float(count));
    for (uint32_t i = 0; i < count; ++i)
      ASSERT_TRUE(scene.add(&field(), RigidTransform::fromAxisAngle({u(g), u(g), u(g) + 0.01f}, 3 * u(g),
                                                                      {world * u(g), world * u(g), world * u(g)},
                                                                      0.75f + 0.5f * u(g)))
                      .ok());
    ASSERT_TRUE(scene.commit().ok());
    auto h = scene.hierarchy();
    ASSERT_TRUE(h.ok()) << h.error().toString();
    // Every instance in exactly one leaf.
    std::vector<uint32_t> order = h->order;
    std::sort(order.begin(), order.end());
    ASSERT_EQ(order.size(), count);
    for (uint32_t i = 0; i < count; ++i) EXPECT_EQ(order[i], i);
    EXPECT_GE(h->depth, 1u);
    EXPECT_GT(h->maxRadius, 0.0f);
    uint32_t reached = 0;
    for (int r = 0; r < 400; ++r) {
      const Vec3 a{u(g), u(g), u(g)};
      const Ray ray{{world * 2 * a.x, world * 2 * a.y, world * 2 * a.z},
                    {u(g) - a.x, u(g) - a.y, u(g) - a.z}, 0.0f, r % 4 == 0 ? 1.0f + 3.0f * (u(g) + 1) : 1e30f};
      uint32_t maxStack = 0;
      const std::vector<uint32_t> mine = walk(*h, ray, &maxStack);
      auto cpu = scene.candidates(ray);
      ASSERT_TRUE(cpu.ok());
      EXPECT_EQ(mine, *cpu) << count << " instances, ray " << r;
      EXPECT_LE(maxStack, 3 * h->depth + 1);
      reached += !mine.empty();
    }
    EXPECT_GT(reached, 0u) << count << " instances";
  }
}

TEST(SceneHierarchy, EmptyAndUncommittedScenes) {
  Scene empty;
  auto h = empty.hierarchy();
  ASSERT_TRUE(h.ok());
  EXPECT_TRUE(h->nodes.empty());
  EXPECT_TRUE(h->order.empty());
  EXPECT_EQ(h->depth, 0u);
  Scene s;
  ASSERT_TRUE(s.add(&field(), RigidTransform{}).ok());
  auto bad = s.hierarchy();
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kBadState);
  ASSERT_TRUE(s.commit().ok());
  auto one = s.hierarchy();
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one->nodes.size(), 1u);
  EXPECT_EQ(one->depth, 1u);
  EXPECT_EQ(one->order, std::vector<uint32_t>{0});
}

}  // namespace
}  // namespace vff
