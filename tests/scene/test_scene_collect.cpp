// The scene hierarchy's batch traversal (libvff/src/scene/scene_bvh.h): Bvh4::collect finds for each
// ray of a batch exactly the leaves the one-ray walk visits; its AVX-512 node step gives the same
// lists, entry for entry, as the scalar step it is written from; BoxRays hold each ray as boxRay
// makes it. On random boxes and rays, with the awkward ones among them: zero, negative-zero and
// subnormal direction components, origins on the boxes' planes (slab terms of 0 * inf), tmax 0
// and infinite.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "scene/scene_bvh.h"  // private: the traversal under test
#include "vff/vff.h"

namespace vff::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<Box> randomBoxes(size_t n, std::mt19937& g) {
  std::uniform_real_distribution<float> u(-10.0f, 10.0f), r(0.1f, 2.0f);
  std::vector<Box> boxes(n);
  for (Box& b : boxes) {
    const float c[3] = {u(g), u(g), u(g)}, h = r(g);
    for (int a = 0; a < 3; ++a) b.lo[a] = c[a] - h, b.hi[a] = c[a] + h;
  }
  return boxes;
}

std::vector<Ray> randomRays(size_t n, const std::vector<Box>& boxes, std::mt19937& g) {
  std::uniform_real_distribution<float> u(-12.0f, 12.0f), d(-1.0f, 1.0f), len(0.0f, 6.0f);
  std::uniform_int_distribution<int> pick(0, 9);
  std::vector<Ray> rays(n);
  for (size_t i = 0; i < n; ++i) {
    Ray& ray = rays[i];
    ray.origin = {u(g), u(g), u(g)};
    ray.direction = {d(g), d(g), d(g)};
    ray.tmax = len(g);
    switch (pick(g)) {
      case 0: ray.direction.x = 0.0f; break;
      case 1: ray.direction.y = -0.0f, ray.direction.z = 0.0f; break;
      case 2: ray.direction.z = 1e-40f; break;  // its inverse is infinite
      case 3: ray.tmax = kInf; break;
      case 4: ray.tmax = 0.0f; break;
      case 5: {  // from a box's corner plane, along it
        const Box& b = boxes[i % boxes.size()];
        ray.origin = {b.lo[0], b.lo[1], b.hi[2]};
        ray.direction.x = 0.0f, ray.direction.y = 1e-40f;
        break;
      }
      case 6: {  // from a box's far corner, every component subnormal: slab terms 0 * inf (NaN)
        const Box& b = boxes[i % boxes.size()];
        ray.origin = {b.hi[0], b.hi[1], b.hi[2]};
        ray.direction = {1e-40f, -1e-40f, 1e-40f};
        break;
      }
      default: break;
    }
  }
  return rays;
}

// Each ray's reached primitives, from collect's lists.
std::vector<std::vector<uint32_t>> perRay(const RayLists& l, size_t rays) {
  std::vector<std::vector<uint32_t>> out(rays);
  for (size_t c = 0; c < l.prim.size(); ++c)
    for (uint32_t k = 0; k < l.count[c]; ++k) out[l.rays[l.first[c] + k]].push_back(l.prim[c]);
  for (auto& v : out) std::sort(v.begin(), v.end());
  return out;
}

TEST(SceneCollect, BoxRaysAreBoxRayOfEachRay) {
  std::mt19937 g(3);
  const std::vector<Box> boxes = randomBoxes(7, g);
  for (size_t n : {0u, 1u, 3u, 4u, 5u, 17u, 1000u}) {
    const std::vector<Ray> rays = randomRays(n, boxes, g);
    BoxRays b;
    b.assign(rays);
    ASSERT_EQ(b.data.size(), n);
    for (size_t i = 0; i < n; ++i) {
      const BoxRay want = boxRay(rays[i]);
      EXPECT_EQ(std::memcmp(&b.data[i], &want, sizeof want), 0) << "ray " << i << " of " << n;
    }
  }
}

TEST(SceneCollect, ReachesWhatTheOneRayWalkVisits) {
  std::mt19937 g(5);
  for (size_t boxCount : {1u, 2u, 5u, 64u, 1000u}) {
    const std::vector<Box> boxes = randomBoxes(boxCount, g);
    Bvh4 bvh;
    bvh.build(boxes);
    const std::vector<Ray> rays = randomRays(2000, boxes, g);
    BoxRays b;
    b.assign(rays);
    RayLists lists;
    bvh.collect(b, &lists, collectNodeScalar);
    const auto got = perRay(lists, rays.size());
    size_t pairs = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      std::vector<uint32_t> want;
      const BoxRay r = boxRay(rays[i]);
      bvh.walk(r, [&](uint32_t prim) {
        want.push_back(prim);
        return r.tmax;  // never lowered: every reached leaf
      });
      std::sort(want.begin(), want.end());
      ASSERT_EQ(got[i], want) << boxCount << " boxes, ray " << i;
      pairs += want.size();
    }
    EXPECT_GT(pairs, 0u) << boxCount << " boxes: no ray reached any (the test tests nothing)";
  }
}

TEST(SceneCollect, Avx512StepGivesTheScalarStepsLists) {
  const CollectNodeFn avx512 = collectNodeAvx512Fn();
  if (!avx512) GTEST_SKIP() << "this build or CPU has no AVX-512 node step";
  std::mt19937 g(7);
  for (size_t boxCount : {1u, 3u, 17u, 1000u}) {
    const std::vector<Box> boxes = randomBoxes(boxCount, g);
    Bvh4 bvh;
    bvh.build(boxes);
    for (size_t n : {1u, 15u, 16u, 17u, 1000u, 4096u}) {
      const std::vector<Ray> rays = randomRays(n, boxes, g);
      BoxRays b;
      b.assign(rays);
      RayLists scalar, wide;
      bvh.collect(b, &scalar, collectNodeScalar);
      bvh.collect(b, &wide, avx512);
      EXPECT_EQ(wide.prim, scalar.prim) << boxCount << " boxes, " << n << " rays";
      EXPECT_EQ(wide.first, scalar.first) << boxCount << " boxes, " << n << " rays";
      EXPECT_EQ(wide.count, scalar.count) << boxCount << " boxes, " << n << " rays";
      EXPECT_EQ(wide.rays, scalar.rays) << boxCount << " boxes, " << n << " rays";
    }
  }
}

}  // namespace
}  // namespace vff::detail
