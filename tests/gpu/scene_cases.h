// scene_cases.h - the scene of the GPU scene suites and its comparison with the CPU vff::Scene,
// shared by the GL suite (test_gpu_scene.cpp), the Vulkan one (test_vk_scene.cpp) and the WebGPU one
// (test_wgsl_scene.cpp), so that all run the same fields, placements, rays and tolerances:
// 14 instances of three baked fields (a torus knot, a bowl and a box; three position schemes, both
// direction schemes, unorm8-diameter with normals, unorm8-chord, bit1; gutters 1, 1 and 0), placed
// by random rigid transforms with overlapping spheres; random world rays from outside the scene and
// from inside instances' spheres, with and without sources. The answers of one ray are SceneOut
// (the GL test kernel's std430 output, vff::vk::SceneAnswer's layout).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "baked_fields.h"
#include "vff/gl/scene_loader.h"
#include "vff/vff.h"

namespace vff::scenetest {

inline constexpr double kNearestT = 1e-5;  // fraction of the instance's world radius
inline constexpr double kInterpT = 1e-4;
inline constexpr double kVisEps = 1e-4;
inline constexpr double kNormalEps = 1e-5;  // world normals, per component (the single-field bound)
inline constexpr double kMaxDifferingShare = 0.005;

struct GpuRay {
  float origin[4], direction[4], range[4];
};
struct SceneOut {
  uint32_t nearestHit;
  float nearestT;
  uint32_t nearestInstance, occluded, interpHit;
  float interpT;
  uint32_t interpInstance;
  float visibility;
  float normal[4];
};
static_assert(sizeof(GpuRay) == 48 && sizeof(SceneOut) == 48);

// The three fields and their queries.
struct Fields {
  std::vector<File> files;
  std::vector<FieldQuery> queries;
};

inline Fields bakeFields() {
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

inline constexpr uint32_t kInstances = 14;
inline constexpr float kWorld = 3.0f;  // instances' centres within [-kWorld, kWorld]^3

inline RigidTransform placement(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.6f, 1.4f), a(0.0f, 6.2831853f);
  return RigidTransform::fromAxisAngle(Vec3{u(rng), u(rng), u(rng) + 0.01f}, a(rng),
                                       Vec3{kWorld * u(rng), kWorld * u(rng), kWorld * u(rng)}, s(rng));
}

inline void place(Scene* scene, const Fields& f, std::mt19937& rng, bool add) {
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
inline std::vector<GpuRay> makeRays(const Scene& scene, uint32_t count, uint64_t seed) {
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
inline constexpr uint32_t kNoSources = 0xFFFFFFFEu;
inline uint32_t sourceOf(const GpuRay& g) {
  return g.range[3] == -2.0f ? kNoSources : g.range[3] < 0 ? kNoInstance : uint32_t(g.range[3]);
}

// The CPU Scene's answers with the ray's source, or without.
template <class T>
inline T sceneAnswer(const Scene& scene, const GpuRay& g, const Ray& ray, const QueryOptions& o,
                     Result<T> (Scene::*plain)(const Ray&, const QueryOptions&) const,
                     Result<T> (Scene::*from)(const Ray&, uint32_t, const QueryOptions&) const) {
  const uint32_t s = sourceOf(g);
  return s == kNoSources ? (scene.*plain)(ray, o).value() : (scene.*from)(ray, s, o).value();
}

inline Ray toRay(const GpuRay& g) {
  return Ray{{g.origin[0], g.origin[1], g.origin[2]},
             {g.direction[0], g.direction[1], g.direction[2]},
             g.range[0],
             g.range[1]};
}

// The same hit: hit flag and instance equal, t within eps R (D / R)^2 of the CPU's, in world
// distance (R: the instance's world radius; D: the distance from the ray's origin to its centre,
// at least R). eps R is the single-field tests' bound (kNearest 1e-5: llvmpipe rounds some steps
// of the sphere test differently; kInterpolated 1e-4), for origins within a few R. The sphere test
// subtracts quantities of size D^2 to get the entry point, so a rounding difference grows with
// (D / R)^2 for the far origins of a scene.
inline bool sameHit(const Scene& scene, const Ray& ray, uint32_t gpuHit, float gpuT, uint32_t gpuInstance,
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
inline uint32_t compareWithScene(const Scene& scene, const std::vector<GpuRay>& rays, const std::vector<SceneOut>& g,
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
        const double e =
            std::max({std::fabs(double(g[r].normal[0]) - a.normal.x), std::fabs(double(g[r].normal[1]) - a.normal.y),
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
        std::printf(
            "[ gpu ] %s ray %zu differs: nearest GPU (%u, %.9g, %u) CPU (%d, %.9g, %u); occluded %u/%d; "
            "interpolated GPU (%u, %.9g, %u) CPU (%d, %.9g, %u); visibility %.7f/%.7f\n",
            label, r, g[r].nearestHit, double(g[r].nearestT), g[r].nearestInstance, int(a.hit), double(a.t), a.instance,
            g[r].occluded, int(occ), g[r].interpHit, double(g[r].interpT), g[r].interpInstance, int(b.hit), double(b.t),
            b.instance, double(g[r].visibility), double(vis));
    }
  }
  std::printf(
      "[ gpu ] %s: %zu rays (%u kNearest hits, %u kInterpolated hits); differ from the CPU Scene: "
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
inline void compareWithLoop(const Scene& scene, const std::vector<GpuRay>& rays, const std::vector<SceneOut>& g,
                            size_t n) {
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
  std::printf("[ gpu ] against the loop over Instance::intersect: %zu rays, %u hits, %u differ\n",
              std::min(n, rays.size()), hits, differing);
  EXPECT_GT(hits, 0u);
  EXPECT_LE(differing, uint32_t(kMaxDifferingShare * double(n)) + 1);
}

// The rays in a kernel's std430 VffVkSceneRay (vff::vk::SceneRay and the WebGPU suite's copy):
// origin[3], source, direction[3], tmin, tmax, intraBias.
template <class SceneRay>
std::vector<SceneRay> toSceneRays(const std::vector<GpuRay>& rays) {
  std::vector<SceneRay> out(rays.size());
  for (size_t r = 0; r < rays.size(); ++r) {
    const GpuRay& g = rays[r];
    SceneRay& v = out[r];
    for (int a = 0; a < 3; ++a) {
      v.origin[a] = g.origin[a];
      v.direction[a] = g.direction[a];
    }
    v.tmin = g.range[0];
    v.tmax = g.range[1];
    v.intraBias = g.range[2];
    v.source = sourceOf(g);  // kNoSources is vff::vk::kSceneNoSources
  }
  return out;
}

// The empty scene's answers: every query misses (no hit, not occluded, visibility 1, no instance).
inline uint32_t answeredRays(const std::vector<SceneOut>& g) {
  uint32_t answered = 0;
  for (const SceneOut& o : g)
    answered += o.nearestHit != 0 || o.occluded != 0 || o.interpHit != 0 || o.visibility != 1.0f ||
                o.nearestInstance != kNoInstance;
  return answered;
}

inline std::vector<gl::SceneField> sceneFields(const Fields& f) {
  std::vector<gl::SceneField> out;
  for (size_t i = 0; i < f.files.size(); ++i) out.push_back({&f.files[i], &f.queries[i]});
  return out;
}

}  // namespace vff::scenetest
