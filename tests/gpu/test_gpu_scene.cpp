// The GLSL scene query (gpu/glsl/vff_scene.glsl, vff::gl::GpuScene) against the CPU vff::Scene,
// on a headless EGL context.
//
// The scene, rays and comparisons are scene_cases.h's (shared with the Vulkan suite,
// test_vk_scene.cpp): a scene of 14 instances of three baked fields (a torus knot, a bowl and a
// box; three position schemes, both direction schemes, unorm8-diameter with normals, unorm8-chord, bit1; gutters 1, 1
// and 0; so the shared maps texture holds fields of different slice and tile layouts), placed by
// random rigid transforms with overlapping spheres. Random world rays (from outside the scene,
// and from inside instances' spheres, non-unit directions, finite tmax, intra bias -1 and 0):
// * intersect (kNearest and kInterpolated): hit and instance equal to Scene::intersect's, t within
//   1e-5 R (kInterpolated 1e-4 R) of it, the single-field tests' bounds; occluded (kNearest) equal to Scene::occluded; visibility (kInterpolated)
//   within 1e-4 of Scene::visibility (the single-field tolerance: the GPU multiplies in walk order);
//   a ray may differ only where the field lookups themselves may (a sample or texel boundary,
//   spec/geometry.md section 8): at most 0.5% of the rays, counted and printed;
// * the first rays also against the loop over Instance::intersect (lowest id on equal t);
// * after every instance moved, Scene::commit and GpuScene::update: the same again;
// * a ground-AO frame of the scene (gpu/harness/ao_scene.h) equal to the CPU Scene's within the
//   single-field AO test's bounds.
#include <gtest/gtest.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "ao_gl.h"
#include "ao_scene.h"
#include "baked_fields.h"
#include "dispatch.h"
#include "egl_context.h"
#include "gl_test.h"
#include "scene_cases.h"
#include "vff/gl/scene_loader.h"
#include "vff/vff.h"

namespace vff {
namespace {

using namespace scenetest;  // the scene, rays and comparisons (scene_cases.h)

// One ray per invocation: the four scene queries (vffSceneIntersect kNearest and kInterpolated,
// vffSceneOccluded, vffSceneVisibility), through their common walk, called from a loop whose
// count is a uniform (4) so that the driver compiles the walk once, not four times.
const std::string kMain = R"(
struct TestOut { uint nearestHit; float nearestT; uint nearestInstance; uint occluded;
                 uint interpHit; float interpT; uint interpInstance; float visibility;
                 vec4 normal; };  // normal: the kNearest hit's world normal, w = hasNormal
layout(location = 0) uniform int queries;
)" + test::rayShaderHead(8, 9) + R"(
  TestOut o;
  for (int q = 0; q < queries; ++q) {
    // q: 0 intersect kNearest (vffSceneIntersect), 1 intersect kInterpolated, 2 occluded
    // (vffSceneOccluded), 3 visibility kInterpolated (vffSceneVisibility).
    uint mode = q < 2 ? VFF_SCENE_INTERSECT : (q == 2 ? VFF_SCENE_OCCLUDED : VFF_SCENE_VISIBILITY);
    float v;
    // range.w: the ray's source, an instance id, -1 for none, -2 for a call without sources.
    uint source = r.range.w == -2.0 ? VFF_SCENE_NO_SOURCE : (r.range.w < 0.0 ? VFF_NO_INSTANCE : uint(r.range.w));
    VffSceneHit h = vffSceneWalk(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, q == 1 || q == 3,
                                 source, mode, v);
    if (q == 0) {
      o.nearestHit = h.hit ? 1u : 0u;
      o.nearestT = h.t;
      o.nearestInstance = h.instance;
      o.normal = vec4(h.normal, h.hasNormal ? 1.0 : 0.0);
    } else if (q == 1) {
      o.interpHit = h.hit ? 1u : 0u;
      o.interpT = h.t;
      o.interpInstance = h.instance;
    } else if (q == 2) {
      o.occluded = h.hit ? 1u : 0u;
    } else {
      o.visibility = v;
    }
  }
  outs[id] = o;
}
)";

std::string sceneSource(const std::string& defines, const std::string& body) {
  return "#version 430\n" + defines +
         gl::sceneShaderSource(harness::readGlsl("vff_scene.glsl"), harness::readGlsl("vff_query.glsl")) + body;
}

GLuint buildSceneProgram(const std::string& defines, const std::string& body) {
  std::string log;
  const GLuint prog = harness::buildProgram(sceneSource(defines, body), &log);
  EXPECT_NE(prog, 0u) << log;
  return prog;
}

std::vector<SceneOut> runRays(const gl::GpuScene& gpu, GLuint program, const std::vector<GpuRay>& rays) {
  gpu.bind();
  glUseProgram(program);
  glUniform1i(0, 4);
  std::vector<SceneOut> out = test::dispatchRays<SceneOut>(std::span<const GpuRay>(rays), rays.size(), 1, 8, 9);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

TEST(GpuScene, MatchesCpuSceneBeforeAndAfterMoving) {
  VFF_REQUIRE_GL();
  const Fields f = bakeFields();
  ASSERT_EQ(f.queries.size(), 3u);
  Scene scene;
  std::mt19937 rng(7u);
  place(&scene, f, rng, true);
  const std::vector<gl::SceneField> fields = sceneFields(f);
  auto gpu = gl::loadScene(fields);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  // The three fields share the textures: different slice sizes, layers appended.
  ASSERT_EQ(gpu->plan().fields.size(), 3u);
  EXPECT_EQ(gpu->plan().fields[1].mapsLayer, f.files[0].layout().sliceCount);
  EXPECT_GT(gpu->plan().fields[2].positionsBase, gpu->plan().fields[1].positionsBase);
  ASSERT_TRUE(gpu->update(scene).ok());
  EXPECT_EQ(gpu->instanceCount(), kInstances);
  const GLuint prog = buildSceneProgram("", kMain);
  ASSERT_NE(prog, 0u);
  const std::vector<GpuRay> rays = makeRays(scene, 4096, 11);
  const std::vector<SceneOut> g = runRays(*gpu, prog, rays);
  compareWithScene(scene, rays, g, "scene");
  compareWithLoop(scene, rays, g, 256);

  // Every instance moves: the CPU commits, the GPU updates; the old answers no longer hold.
  place(&scene, f, rng, false);
  ASSERT_TRUE(gpu->update(scene).ok());
  const std::vector<GpuRay> rays2 = makeRays(scene, 4096, 12);
  const std::vector<SceneOut> g2 = runRays(*gpu, prog, rays2);
  compareWithScene(scene, rays2, g2, "scene after moving");
  compareWithLoop(scene, rays2, g2, 256);
  glDeleteProgram(prog);
}

TEST(GpuScene, UpdateRefusesForeignFieldsAndUncommittedScenes) {
  VFF_REQUIRE_GL();
  const Fields f = bakeFields();
  ASSERT_EQ(f.queries.size(), 3u);
  std::vector<gl::SceneField> two = sceneFields(f);
  two.pop_back();
  auto gpu = gl::loadScene(two);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  Scene scene;
  ASSERT_TRUE(scene.add(&f.queries[2], RigidTransform{}).ok());
  Status s = gpu->update(scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, Code::kBadState);  // not committed
  ASSERT_TRUE(scene.commit().ok());
  s = gpu->update(scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, Code::kInvalidArgument);  // field 2 was not uploaded
  // The fields fit the context one by one, but not together in one texture.
  gl::LoadOptions few;
  few.maxLayers = f.files[0].layout().sliceCount + f.files[1].layout().sliceCount - 1;
  auto tooMany = gl::loadScene(two, few);
  ASSERT_FALSE(tooMany.ok());
  EXPECT_EQ(tooMany.error().code, Code::kUnsupported);
  EXPECT_NE(tooMany.error().message.find("GL_MAX_ARRAY_TEXTURE_LAYERS"), std::string::npos) << tooMany.error().message;
  std::vector<gl::SceneField> twice = {two[0], two[0]};
  auto dup = gl::loadScene(twice);
  ASSERT_FALSE(dup.ok());
  EXPECT_EQ(dup.error().code, Code::kInvalidArgument);
}

TEST(GpuScene, EmptySceneMissesEverything) {
  VFF_REQUIRE_GL();
  const Fields f = bakeFields();
  ASSERT_EQ(f.queries.size(), 3u);
  Scene full;
  std::mt19937 rng(7u);
  place(&full, f, rng, true);
  auto gpu = gl::loadScene(sceneFields(f));
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  const Scene empty;  // never touched: committed, no instances
  ASSERT_TRUE(gpu->update(empty).ok());
  EXPECT_EQ(gpu->instanceCount(), 0u);
  const GLuint prog = buildSceneProgram("", kMain);
  ASSERT_NE(prog, 0u);
  // Rays that hit the full scene's instances miss the empty one.
  const std::vector<GpuRay> rays = makeRays(full, 256, 13);
  const std::vector<SceneOut> g = runRays(*gpu, prog, rays);
  uint32_t answered = 0;
  for (const SceneOut& o : g)
    answered += o.nearestHit != 0 || o.occluded != 0 || o.interpHit != 0 || o.visibility != 1.0f ||
                o.nearestInstance != kNoInstance;
  EXPECT_EQ(answered, 0u);
  // And the full scene again after it: the same buffers grow back.
  ASSERT_TRUE(gpu->update(full).ok());
  const std::vector<SceneOut> g2 = runRays(*gpu, prog, rays);
  uint32_t hits = 0;
  for (const SceneOut& o : g2) hits += o.nearestHit != 0;
  EXPECT_GT(hits, 0u);
  glDeleteProgram(prog);
}

TEST(GpuScene, GroundAoMatchesCpuScene) {
  VFF_REQUIRE_GL();
  const Fields f = bakeFields();
  ASSERT_EQ(f.queries.size(), 3u);
  Scene scene;
  std::mt19937 rng(5u);
  place(&scene, f, rng, true);
  auto gpu = gl::loadScene(sceneFields(f));
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  ASSERT_TRUE(gpu->update(scene).ok());
  // The ground under the scene: the AO scene of a field whose sphere bounds the instances.
  FieldDesc bounds = f.files[0].field();
  float lowest = INFINITY, extent = 0;
  for (uint32_t i = 0; i < scene.size(); ++i) {
    const Sphere s = scene.instance(i)->worldSphere();
    lowest = std::min(lowest, s.center[1] - 0.5f * s.radius);
    for (int a = 0; a < 3; ++a) extent = std::max(extent, std::fabs(s.center[a]) + s.radius);
  }
  bounds.sphere = Sphere{{0, 0, 0}, 0.5f * extent};
  constexpr int kSize = 48, kRays = 32;
  const harness::AoScene s = harness::makeAoScene(bounds, lowest, kSize);
  std::string log;
  const GLuint prog = harness::buildProgram(harness::sceneAoShaderSource(), &log);
  ASSERT_NE(prog, 0u) << log;
  const harness::AoBuffers aoBuffers(s);
  harness::useSceneAo(*gpu, aoBuffers, prog);
  for (Reconstruction r : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    const bool interp = r == Reconstruction::kInterpolated;
    std::vector<float> g;
    (void)harness::renderAo(s, aoBuffers, kRays, interp ? 1 : 0, &g);
    const std::vector<float> c = harness::cpuAo(scene, s, kRays, r, 2);
    const harness::AoDiff d = harness::compareAo(c, g);
    std::printf("[ gpu ] scene ground AO %dx%d, %d rays/px, %s: mean AO %.4f; GPU vs CPU Scene on the 8-bit "
                "scale: max %.0f, RMS %.4f, %llu of %d pixels differ\n",
                kSize, kSize, kRays, interp ? "kInterpolated visibility" : "kNearest occluded", d.meanA, d.max, d.rms,
                (unsigned long long)d.differing, kSize * kSize);
    // As the single-field AO test: one ray of a pixel answered differently moves it by 255 / 32
    // levels here, so kNearest allows 8.
    EXPECT_LE(d.max, interp ? 1.0 : 8.0);
    EXPECT_LE(d.rms, interp ? 0.1 : 0.5);
    EXPECT_LT(d.meanA, 0.99);  // the instances do occlude the ground
  }
  glDeleteProgram(prog);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}


}  // namespace
}  // namespace vff
