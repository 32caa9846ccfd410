// The GLSL scene query (gpu/glsl/vff_scene.glsl, vff::gl::GpuScene) against the CPU vff::Scene,
// on a headless EGL context.
//
// A scene of 14 instances of three baked fields (a torus knot, a bowl and a box; three position
// schemes, both direction schemes, unorm8-diameter with normals, unorm8-chord, bit1; gutters 1, 1
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
#include "vff/gl/scene_loader.h"
#include "vff/vff.h"

namespace vff {
namespace {

constexpr double kNearestT = 1e-5;  // fraction of the instance's world radius
constexpr double kInterpT = 1e-4;
constexpr double kVisEps = 1e-4;
constexpr double kNormalEps = 1e-5;  // world normals, per component (the single-field bound)
constexpr double kMaxDifferingShare = 0.005;

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

struct GpuRay {
  float origin[4], direction[4], range[4];
};
struct GpuOut {
  uint32_t nearestHit;
  float nearestT;
  uint32_t nearestInstance, occluded, interpHit;
  float interpT;
  uint32_t interpInstance;
  float visibility;
  float normal[4];
};
static_assert(sizeof(GpuRay) == 48 && sizeof(GpuOut) == 48);

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

// The three fields and their queries.
struct Fields {
  std::vector<File> files;
  std::vector<FieldQuery> queries;
};

Fields bakeFields() {
  using gputest::FieldCase;
  Fields f;
  const FieldCase cases[3] = {
      {PositionScheme::kOctaHemi2, DirectionScheme::kConcentricEqualArea, DistanceEncoding::kUnorm8Diameter},
      {PositionScheme::kEqualAreaOctaGrid, DirectionScheme::kHemiOctahedral, DistanceEncoding::kUnorm8Chord},
      {PositionScheme::kSphericalFibonacci, DirectionScheme::kConcentricEqualArea, DistanceEncoding::kBit1}};
  const char* shapes[3] = {"torus-knot", "bowl", "box"};
  for (int i = 0; i < 3; ++i) {
    auto file = gputest::bakeFile(cases[i], i == 0, shapes[i]);
    EXPECT_TRUE(file.ok()) << file.error().toString();
    if (!file.ok()) return {};
    f.files.push_back(std::move(*file));
  }
  for (const File& file : f.files) {
    auto q = FieldQuery::fromFile(file);
    EXPECT_TRUE(q.ok()) << q.error().toString();
    if (!q.ok()) return {};
    f.queries.push_back(std::move(*q));
  }
  return f;
}

constexpr uint32_t kInstances = 14;
constexpr float kWorld = 3.0f;  // instances' centres within [-kWorld, kWorld]^3

RigidTransform placement(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.6f, 1.4f), a(0.0f, 6.2831853f);
  return RigidTransform::fromAxisAngle(Vec3{u(rng), u(rng), u(rng) + 0.01f}, a(rng),
                                       Vec3{kWorld * u(rng), kWorld * u(rng), kWorld * u(rng)}, s(rng));
}

void place(Scene* scene, const Fields& f, std::mt19937& rng, bool add) {
  for (uint32_t i = 0; i < kInstances; ++i) {
    const RigidTransform x = placement(rng);
    if (add) {
      auto id = scene->add(&f.queries[i % 3], x);
      ASSERT_TRUE(id.ok()) << id.error().toString();
    } else {
      ASSERT_TRUE(scene->setTransform(i, x).ok());
    }
  }
  ASSERT_TRUE(scene->commit().ok());
}

// Rays from outside the scene towards it, and from inside instances' spheres (near their surfaces).
std::vector<GpuRay> makeRays(const Scene& scene, uint32_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), uni(0.0f, 1.0f);
  auto dir = [&] {
    for (;;) {
      const Vec3 v{u(rng), u(rng), u(rng)};
      const float l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
      if (l > 0.1f && l <= 1.0f) return Vec3{v.x / l, v.y / l, v.z / l};
    }
  };
  std::vector<GpuRay> rays(count);
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmax = 1e30f;
    if (r % 2 == 0) {
      const Vec3 a = dir(), b{kWorld * u(rng), kWorld * u(rng), kWorld * u(rng)};
      const float far = 4.0f * kWorld;
      o = Vec3{b.x + a.x * far, b.y + a.y * far, b.z + a.z * far};
      d = Vec3{-a.x, -a.y, -a.z};
      if (r % 8 == 2) d = Vec3{d.x * 2.5f, d.y * 2.5f, d.z * 2.5f};
      if (r % 16 == 4) tmax = far * uni(rng);
    } else {
      const Sphere s = scene.instance(r % kInstances)->worldSphere();
      const Vec3 a = dir();
      const float k = s.radius * 0.9f * std::cbrt(uni(rng));
      o = Vec3{s.center[0] + a.x * k, s.center[1] + a.y * k, s.center[2] + a.z * k};
      d = dir();
      if (r % 8 == 3) tmax = s.radius * 2.0f * uni(rng);
    }
    // Sources (vff::Scene's *From calls): rays from inside a sphere start on its instance or on
    // none; a quarter of all rays have none given (the calls without sources).
    const float source = r % 4 == 0 ? -2.0f : r % 4 == 1 ? float(r % kInstances) : -1.0f;
    rays[r] = GpuRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {0.0f, tmax, r % 3 == 0 ? 0.0f : -1.0f, source}};
  }
  return rays;
}

// A ray's source as vff::Scene takes it (kNoSources: a call without sources).
constexpr uint32_t kNoSources = 0xFFFFFFFEu;
uint32_t sourceOf(const GpuRay& g) {
  return g.range[3] == -2.0f ? kNoSources : g.range[3] < 0 ? kNoInstance : uint32_t(g.range[3]);
}

// The CPU Scene's answers with the ray's source, or without.
template <class T>
T sceneAnswer(const Scene& scene, const GpuRay& g, const Ray& ray, const QueryOptions& o,
              Result<T> (Scene::*plain)(const Ray&, const QueryOptions&) const,
              Result<T> (Scene::*from)(const Ray&, uint32_t, const QueryOptions&) const) {
  const uint32_t s = sourceOf(g);
  return s == kNoSources ? (scene.*plain)(ray, o).value() : (scene.*from)(ray, s, o).value();
}

Ray toRay(const GpuRay& g) {
  return Ray{{g.origin[0], g.origin[1], g.origin[2]}, {g.direction[0], g.direction[1], g.direction[2]}, g.range[0],
             g.range[1]};
}

std::vector<GpuOut> runRays(const gl::GpuScene& gpu, GLuint program, const std::vector<GpuRay>& rays) {
  gpu.bind();
  glUseProgram(program);
  glUniform1i(0, 4);
  std::vector<GpuOut> out = test::dispatchRays<GpuOut>(std::span<const GpuRay>(rays), rays.size(), 1, 8, 9);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

// The same hit: hit flag and instance equal, t within eps R (D / R)^2 of the CPU's, in world
// distance (R: the instance's world radius; D: the distance from the ray's origin to its centre,
// at least R). eps R is the single-field tests' bound (kNearest 1e-5: llvmpipe rounds some steps
// of the sphere test differently; kInterpolated 1e-4), for origins within a few R. The sphere test
// subtracts quantities of size D^2 to get the entry point, so a rounding difference grows with
// (D / R)^2 for the far origins of a scene.
bool sameHit(const Scene& scene, const Ray& ray, uint32_t gpuHit, float gpuT, uint32_t gpuInstance,
             const SceneHit& c, double eps) {
  if ((gpuHit != 0) != c.hit) return false;
  if (!c.hit) return true;
  if (gpuInstance != c.instance) return false;
  const double len = std::sqrt(double(ray.direction.x) * ray.direction.x + double(ray.direction.y) * ray.direction.y +
                               double(ray.direction.z) * ray.direction.z);
  const Sphere s = scene.instance(c.instance)->worldSphere();
  const double R = s.radius;
  const double dx = ray.origin.x - s.center[0], dy = ray.origin.y - s.center[1], dz = ray.origin.z - s.center[2];
  const double D = std::max(R, std::sqrt(dx * dx + dy * dy + dz * dz));
  return std::fabs(double(gpuT) - double(c.t)) * len <= eps * R * (D / R) * (D / R);
}

// Compares every ray with the CPU Scene; returns the rays answered differently (any query).
uint32_t compareWithScene(const Scene& scene, const std::vector<GpuRay>& rays, const std::vector<GpuOut>& g,
                          const char* label) {
  uint32_t nearestDiff = 0, occludedDiff = 0, interpDiff = 0, visDiff = 0, differing = 0, hits = 0, interpHits = 0;
  uint32_t normals = 0, normalDiff = 0;
  double maxVis = 0;
  for (size_t r = 0; r < rays.size(); ++r) {
    const Ray ray = toRay(rays[r]);
    const QueryOptions nearest{.reconstruction = Reconstruction::kNearest, .intraBias = rays[r].range[2]};
    const QueryOptions interp{.reconstruction = Reconstruction::kInterpolated, .intraBias = rays[r].range[2]};
    const SceneHit a = sceneAnswer<SceneHit>(scene, rays[r], ray, nearest, &Scene::intersect, &Scene::intersectFrom);
    const SceneHit b = sceneAnswer<SceneHit>(scene, rays[r], ray, interp, &Scene::intersect, &Scene::intersectFrom);
    const bool occ = sceneAnswer<bool>(scene, rays[r], ray, nearest, &Scene::occluded, &Scene::occludedFrom);
    const float vis = sceneAnswer<float>(scene, rays[r], ray, interp, &Scene::visibility, &Scene::visibilityFrom);
    hits += a.hit;
    interpHits += b.hit;
    const bool dn = !sameHit(scene, ray, g[r].nearestHit, g[r].nearestT, g[r].nearestInstance, a, kNearestT);
    // The world normal of the same hit (instances of the field with a normal plane).
    if (!dn && a.hit) {
      EXPECT_EQ(g[r].normal[3] != 0, a.hasNormal) << label << " ray " << r;
      if (a.hasNormal) {
        ++normals;
        const double e = std::max({std::fabs(double(g[r].normal[0]) - a.normal.x),
                                   std::fabs(double(g[r].normal[1]) - a.normal.y),
                                   std::fabs(double(g[r].normal[2]) - a.normal.z)});
        normalDiff += !(e <= kNormalEps);
      }
    }
    const bool doc = (g[r].occluded != 0) != occ;
    const bool di = !sameHit(scene, ray, g[r].interpHit, g[r].interpT, g[r].interpInstance, b, kInterpT);
    const double dv = std::fabs(double(g[r].visibility) - double(vis));
    const bool dvis = !(dv <= kVisEps);
    maxVis = std::max(maxVis, dvis ? dv : 0.0);
    nearestDiff += dn;
    occludedDiff += doc;
    interpDiff += di;
    visDiff += dvis;
    if (dn || doc || di || dvis) {
      ++differing;
      if (differing <= 5)
        std::printf("[ gpu ] %s ray %zu differs: nearest GPU (%u, %.9g, %u) CPU (%d, %.9g, %u); occluded %u/%d; "
                    "interpolated GPU (%u, %.9g, %u) CPU (%d, %.9g, %u); visibility %.7f/%.7f\n",
                    label, r, g[r].nearestHit, double(g[r].nearestT), g[r].nearestInstance, int(a.hit), double(a.t),
                    a.instance, g[r].occluded, int(occ), g[r].interpHit, double(g[r].interpT), g[r].interpInstance,
                    int(b.hit), double(b.t), b.instance, double(g[r].visibility), double(vis));
    }
  }
  std::printf("[ gpu ] %s: %zu rays (%u kNearest hits, %u kInterpolated hits); differ from the CPU Scene: "
              "intersect %u, occluded %u, interpolated intersect %u, visibility %u (beyond %.0e; max %.3g)\n",
              label, rays.size(), hits, interpHits, nearestDiff, occludedDiff, interpDiff, visDiff, kVisEps, maxVis);
  std::printf("[ gpu ] %s: %u kNearest hits with a normal; world normals beyond %.0e of the CPU's: %u\n", label,
              normals, kNormalEps, normalDiff);
  EXPECT_GT(normals, 0u);
  EXPECT_EQ(normalDiff, 0u) << label;
  // The rays must exercise the scene: hits of several instances, and misses.
  EXPECT_GT(hits, rays.size() / 8);
  EXPECT_LT(hits, rays.size());
  EXPECT_LE(differing, uint32_t(kMaxDifferingShare * double(rays.size()))) << label;
  return differing;
}

// The first rays against the loop over the instances in id order (vff/scene.h's definition).
void compareWithLoop(const Scene& scene, const std::vector<GpuRay>& rays, const std::vector<GpuOut>& g, size_t n) {
  uint32_t differing = 0, hits = 0;
  for (size_t r = 0; r < std::min(n, rays.size()); ++r) {
    const Ray ray = toRay(rays[r]);
    const QueryOptions o{.reconstruction = Reconstruction::kNearest, .intraBias = rays[r].range[2]};
    SceneHit best;
    bool occ = false;
    const uint32_t source = sourceOf(rays[r]);
    for (uint32_t i = 0; i < scene.size(); ++i) {
      const Instance in = scene.instance(i).value();
      QueryOptions oi = o;  // with a source: 7.3 for the instance the ray starts on, 7.4 for the rest
      if (source != kNoSources) oi.origin = i == source ? RayOrigin::kOnObject : RayOrigin::kOffObject;
      const QueryHit h = in.intersect(ray, oi);
      occ = occ || in.occluded(ray, oi);
      if (h.hit && h.t < best.t) {  // ascending ids: the lowest id keeps an equal t
        static_cast<QueryHit&>(best) = h;
        best.instance = i;
      }
    }
    hits += best.hit;
    differing += !sameHit(scene, ray, g[r].nearestHit, g[r].nearestT, g[r].nearestInstance, best, kNearestT) ||
                 (g[r].occluded != 0) != occ;
  }
  std::printf("[ gpu ] against the loop over Instance::intersect: %zu rays, %u hits, %u differ\n", std::min(n, rays.size()),
              hits, differing);
  EXPECT_GT(hits, 0u);
  EXPECT_LE(differing, uint32_t(kMaxDifferingShare * double(n)) + 1);
}

std::vector<gl::SceneField> sceneFields(const Fields& f) {
  std::vector<gl::SceneField> out;
  for (size_t i = 0; i < f.files.size(); ++i) out.push_back({&f.files[i], &f.queries[i]});
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
  const std::vector<GpuOut> g = runRays(*gpu, prog, rays);
  compareWithScene(scene, rays, g, "scene");
  compareWithLoop(scene, rays, g, 256);

  // Every instance moves: the CPU commits, the GPU updates; the old answers no longer hold.
  place(&scene, f, rng, false);
  ASSERT_TRUE(gpu->update(scene).ok());
  const std::vector<GpuRay> rays2 = makeRays(scene, 4096, 12);
  const std::vector<GpuOut> g2 = runRays(*gpu, prog, rays2);
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
  const std::vector<GpuOut> g = runRays(*gpu, prog, rays);
  uint32_t answered = 0;
  for (const GpuOut& o : g)
    answered += o.nearestHit != 0 || o.occluded != 0 || o.interpHit != 0 || o.visibility != 1.0f ||
                o.nearestInstance != kNoInstance;
  EXPECT_EQ(answered, 0u);
  // And the full scene again after it: the same buffers grow back.
  ASSERT_TRUE(gpu->update(full).ok());
  const std::vector<GpuOut> g2 = runRays(*gpu, prog, rays);
  uint32_t hits = 0;
  for (const GpuOut& o : g2) hits += o.nearestHit != 0;
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
