// The Vulkan scene walk (vff/vk/scene.h: gpu/glsl/vff_scene.glsl in shaders/vff_vk_scene.comp,
// compiled at build time) against the CPU vff::Scene, with the Khronos validation layer on.
//
// The scene, rays, comparisons and tolerances are the GL suite's (scene_cases.h, shared with
// test_gpu_scene.cpp): 14 instances of three baked fields of different encodings and slice layouts,
// random world rays with and without sources; intersect (kNearest and kInterpolated: hit, instance,
// t within the single-field bounds), occluded, visibility and the kNearest hit's world normal
// against Scene's answers, at most 0.5% of the rays differing (a sample or texel boundary); the
// first rays also against the loop over Instance::intersect; all again after every instance moved
// and GpuScene::update. Every case runs with the kernel compiled from GLSL (instantiation Glsl) and
// with the one compiled from the HLSL that spirv-cross generates from it (Hlsl), and requires zero
// validation errors and warnings. Where no Vulkan device, validation layer or HLSL kernel is
// available, the cases skip and say why (vk_env.h).
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "scene_cases.h"
#include "vff/vff.h"
#include "vff/vk/scene.h"
#include "vk_env.h"

namespace vff {
namespace vk {
// The parameter's name in test listings (gtest finds PrintTo in the type's namespace).
void PrintTo(ShaderLanguage l, std::ostream* os) {
  *os << vktest::languageName(l);
}
}  // namespace vk

namespace {

using namespace scenetest;  // the scene, rays and comparisons (scene_cases.h)
using vk::ShaderLanguage;
using vktest::expectNoValidationMessages, vktest::languageName, vktest::vkEnv;  // vk_env.h

// The kernel's answer is the GL test kernel's output, member for member.
static_assert(sizeof(vk::SceneAnswer) == sizeof(SceneOut));
static_assert(offsetof(vk::SceneAnswer, visibility) == offsetof(SceneOut, visibility));
static_assert(offsetof(vk::SceneAnswer, normal) == offsetof(SceneOut, normal));

// Runs the rays through the scene; ADD_FAILUREs and returns empty on a failure.
std::vector<SceneOut> runVk(const vk::ScenePipeline& pipe, const vk::GpuScene& gpu, const std::vector<GpuRay>& rays) {
  auto answers = pipe.run(*vkEnv().ctx, gpu, toSceneRays<vk::SceneRay>(rays));
  EXPECT_TRUE(answers.ok()) << answers.error().toString();
  if (!answers) return {};
  std::vector<SceneOut> out(answers->size());
  std::memcpy(out.data(), answers->data(), out.size() * sizeof(SceneOut));
  return out;
}

// Each case: the three fields, the scene of 14 instances (not yet given to the GPU), the fields
// uploaded and the pipeline of the case's language.
class VkScene : public ::testing::TestWithParam<ShaderLanguage> {
 protected:
  void SetUp() override {
    VFF_REQUIRE_VK();
    VFF_REQUIRE_LANGUAGE(GetParam());
    f_ = bakeFields();
    ASSERT_EQ(f_.queries.size(), 3u);
    place(&scene_, f_, rng_, true);
    auto gpu = vk::loadScene(ctx(), sceneFields(f_));
    ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
    gpu_ = std::move(*gpu);
    vk::PipelineOptions po;
    po.language = GetParam();
    auto pipe = vk::ScenePipeline::create(ctx(), po);
    ASSERT_TRUE(pipe.ok()) << pipe.error().toString();
    pipe_ = std::move(*pipe);
  }
  static const vk::Context& ctx() { return *vkEnv().ctx; }

  Fields f_;
  Scene scene_;
  std::mt19937 rng_{7u};
  vk::GpuScene gpu_;
  vk::ScenePipeline pipe_;
};

std::string languageParamName(const ::testing::TestParamInfo<ShaderLanguage>& i) {
  return languageName(i.param);
}

TEST_P(VkScene, MatchesCpuSceneBeforeAndAfterMoving) {
  // The three fields share the images: different slice sizes, layers appended.
  ASSERT_EQ(gpu_.plan().fields.size(), 3u);
  EXPECT_EQ(gpu_.plan().fields[1].mapsLayer, f_.files[0].layout().sliceCount);
  EXPECT_GT(gpu_.plan().fields[2].positionsBase, gpu_.plan().fields[1].positionsBase);
  ASSERT_TRUE(gpu_.update(ctx(), scene_).ok());
  EXPECT_EQ(gpu_.instanceCount(), kInstances);
  const std::string label = std::string("vk scene (") + languageName(GetParam()) + ")";
  const std::vector<GpuRay> rays = makeRays(scene_, 4096, 11);
  const std::vector<SceneOut> g = runVk(pipe_, gpu_, rays);
  ASSERT_EQ(g.size(), rays.size());
  compareWithScene(scene_, rays, g, label.c_str());
  compareWithLoop(scene_, rays, g, 256);

  // Every instance moves: the CPU commits, the GPU updates; the old answers no longer hold.
  place(&scene_, f_, rng_, false);
  ASSERT_TRUE(gpu_.update(ctx(), scene_).ok());
  const std::vector<GpuRay> rays2 = makeRays(scene_, 4096, 12);
  const std::vector<SceneOut> g2 = runVk(pipe_, gpu_, rays2);
  ASSERT_EQ(g2.size(), rays2.size());
  compareWithScene(scene_, rays2, g2, (label + " after moving").c_str());
  compareWithLoop(scene_, rays2, g2, 256);
  expectNoValidationMessages();
}

TEST_P(VkScene, EmptySceneMissesEverything) {
  // Rays that hit the full scene's instances miss the empty one (also before any update).
  const std::vector<GpuRay> rays = makeRays(scene_, 256, 13);
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      const Scene empty;  // never touched: committed, no instances
      ASSERT_TRUE(gpu_.update(ctx(), empty).ok());
    }
    EXPECT_EQ(gpu_.instanceCount(), 0u);
    EXPECT_EQ(answeredRays(runVk(pipe_, gpu_, rays)), 0u) << "pass " << pass;
  }
  // And the full scene again after it: the buffers grow back.
  ASSERT_TRUE(gpu_.update(ctx(), scene_).ok());
  uint32_t hits = 0;
  for (const SceneOut& o : runVk(pipe_, gpu_, rays)) hits += o.nearestHit != 0;
  EXPECT_GT(hits, 0u);
  expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Glsl, VkScene, ::testing::Values(ShaderLanguage::kGlsl), languageParamName);
INSTANTIATE_TEST_SUITE_P(Hlsl, VkScene, ::testing::Values(ShaderLanguage::kHlsl), languageParamName);

TEST(VkSceneLoader, RefusesForeignFieldsAndUncommittedScenes) {
  VFF_REQUIRE_VK();
  const vk::Context& ctx = *vkEnv().ctx;
  const Fields f = bakeFields();
  ASSERT_EQ(f.queries.size(), 3u);
  std::vector<gl::SceneField> two = sceneFields(f);
  two.pop_back();
  auto gpu = vk::loadScene(ctx, two);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  Scene scene;
  ASSERT_TRUE(scene.add(&f.queries[2], RigidTransform{}).ok());
  Status s = gpu->update(ctx, scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, Code::kBadState);  // not committed
  ASSERT_TRUE(scene.commit().ok());
  s = gpu->update(ctx, scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, Code::kInvalidArgument);  // field 2 was not uploaded
  std::vector<gl::SceneField> twice = {two[0], two[0]};
  auto dup = vk::loadScene(ctx, twice);
  ASSERT_FALSE(dup.ok());
  EXPECT_EQ(dup.error().code, Code::kInvalidArgument);
  auto none = vk::loadScene(ctx, std::vector<gl::SceneField>{});
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, Code::kInvalidArgument);
  expectNoValidationMessages();
}

}  // namespace
}  // namespace vff
