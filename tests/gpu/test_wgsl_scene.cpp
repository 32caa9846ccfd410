// The WGSL translation of the Vulkan scene kernel (gpu/wgsl/kernels/vff_vk_scene.wgsl, generated
// from gpu/vulkan/shaders/vff_vk_scene.comp by web/tools/gen-wgsl.mjs) run through WebGPU in
// headless Chromium (wgsl_runner.h), against the CPU vff::Scene.
//
// The scene, rays, comparisons and tolerances are the Vulkan suite's (test_vk_scene.cpp, shared in
// scene_cases.h): 14 instances of three baked fields, random world rays with and without sources;
// intersect (kNearest and kInterpolated), occluded, visibility and the world normal against Scene's
// answers, the first rays also against the loop over Instance::intersect; all again after every
// instance moved. The empty scene misses every ray, and the full scene after it hits again. The
// runs of one test go through one runner call (one Chromium). Where node, web/node_modules,
// chromium, a WebGPU adapter or the kernel is missing, the cases skip and say why.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "scene_cases.h"
#include "vff/vff.h"
#include "wgsl_runner.h"

namespace vff {
namespace {

using namespace scenetest;  // the scene, rays and comparisons (scene_cases.h)
using wgsltest::Kernel;
using wgsltest::SceneRay;

constexpr unsigned kPlacementSeed = 7u;  // the Vulkan suite's

class WgslScene : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string why = wgsltest::environmentSkip(); !why.empty()) GTEST_SKIP() << why;
    if (!std::filesystem::exists(wgsltest::kernelPath(Kernel::kScene)))
      GTEST_SKIP() << wgsltest::kernelPath(Kernel::kScene) << " is not generated yet (gen-wgsl.mjs)";
    f_ = bakeFields();
    ASSERT_EQ(f_.queries.size(), 3u);
    place(&scene_, f_, rng_, true);
  }

  // Adds a run of `scene` over `rays`; ADD_FAILUREs and returns SIZE_MAX on a failure.
  size_t addRun(wgsltest::Job& job, const wgsltest::SceneData& data, const Scene& scene,
                const std::vector<GpuRay>& rays) {
    auto run = job.addSceneRun(data, scene, toSceneRays<SceneRay>(rays));
    EXPECT_TRUE(run.ok()) << run.error().toString();
    return run ? *run : SIZE_MAX;
  }

  Fields f_;
  Scene scene_;
  std::mt19937 rng_{kPlacementSeed};
};

#define VFF_RUN_SCENE_JOB(job)                  \
  do {                                          \
    const wgsltest::Outcome o_ = (job).run();   \
    if (o_.skipped) GTEST_SKIP() << o_.message; \
    ASSERT_TRUE(o_.ok) << o_.message;           \
  } while (0)

TEST_F(WgslScene, MatchesCpuSceneBeforeAndAfterMoving) {
  wgsltest::Job job("scene-moving");
  auto data = job.addSceneFields(sceneFields(f_));
  ASSERT_TRUE(data.ok()) << data.error().toString();
  ASSERT_EQ(data->plan.fields.size(), 3u);
  const std::vector<GpuRay> rays = makeRays(scene_, 4096, 11);
  const size_t first = addRun(job, *data, scene_, rays);
  // Every instance moves (Scene::setTransform, commit), as in the Vulkan suite: the same scene built
  // again from the same random sequence and moved, since both scenes' answers are compared after
  // the one runner call; the second run gets the moved scene's instances and nodes.
  Scene moved;
  std::mt19937 replay{kPlacementSeed};
  place(&moved, f_, replay, true);
  place(&moved, f_, replay, false);
  const std::vector<GpuRay> rays2 = makeRays(moved, 4096, 12);
  const size_t second = addRun(job, *data, moved, rays2);
  ASSERT_NE(first, SIZE_MAX);
  ASSERT_NE(second, SIZE_MAX);
  VFF_RUN_SCENE_JOB(job);
  const std::vector<SceneOut> g = job.answers<SceneOut>(first);
  ASSERT_EQ(g.size(), rays.size());
  compareWithScene(scene_, rays, g, "wgsl scene");
  compareWithLoop(scene_, rays, g, 256);
  const std::vector<SceneOut> g2 = job.answers<SceneOut>(second);
  ASSERT_EQ(g2.size(), rays2.size());
  compareWithScene(moved, rays2, g2, "wgsl scene after moving");
  compareWithLoop(moved, rays2, g2, 256);
}

TEST_F(WgslScene, EmptySceneMissesEverything) {
  // Rays that hit the full scene's instances miss the empty one; the full scene after it hits.
  wgsltest::Job job("scene-empty");
  auto data = job.addSceneFields(sceneFields(f_));
  ASSERT_TRUE(data.ok()) << data.error().toString();
  const std::vector<GpuRay> rays = makeRays(scene_, 256, 13);
  const Scene empty;  // never touched: committed, no instances
  const size_t none = addRun(job, *data, empty, rays);
  const size_t full = addRun(job, *data, scene_, rays);
  ASSERT_NE(none, SIZE_MAX);
  ASSERT_NE(full, SIZE_MAX);
  VFF_RUN_SCENE_JOB(job);
  const std::vector<SceneOut> g = job.answers<SceneOut>(none);
  ASSERT_EQ(g.size(), rays.size());
  EXPECT_EQ(answeredRays(g), 0u);
  uint32_t hits = 0;
  for (const SceneOut& o : job.answers<SceneOut>(full)) hits += o.nearestHit != 0;
  EXPECT_GT(hits, 0u);
}

}  // namespace
}  // namespace vff
