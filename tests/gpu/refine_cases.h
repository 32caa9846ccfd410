// refine_cases.h - the refined query's GPU-vs-CPU comparison, defined once for the GL suite
// (test_gpu_refine.cpp) and the Vulkan suite (test_vk_refine.cpp, GLSL and HLSL): the shapes
// (baked with a refinement, written with REFN and opened again), the rays, the tolerances, and one
// run's answers checked against FieldQuery's Reconstruction::kRefined.
//
// Two procedural shapes (the torus knot with normals, the bowl) baked at n 8, m 16 with a
// refinement (vff::makeRefinement), written to a file (REFN). Three sets of rays: from outside the
// sphere aimed at points inside it (some with non-unit directions, some with a finite tmax that
// ends near the surface), ground AO rays from points of the plane under the object inside the
// sphere (RayOrigin::kOffObject, VFF_OFF_OBJECT, tmax 2R), and rays from inside on the object
// (section 7.3, which kRefined answers as kNearest). Per ray, against FieldQuery::intersect
// (kRefined and kNearest) and the batch FieldQuery::occluded (kRefined, the any-hit cast):
// * the hit flags equal, except for at most kMaxFlagMismatches rays (printed): a ray through a
//   triangle's edge or a box face may be met by one cast and missed by the other where the GPU
//   rounds a step differently, and a lookup within rounding of a texel or sample boundary may read
//   the neighbour (spec/geometry.md section 8);
// * t within kT R (scaled by |direction|) and, for the exact step's hits, the triangle's normal
//   within kNormal, per component;
// * the exact step taken: every ray whose lookup (FieldQuery::site, the same texel as the GPU's)
//   reads an unsure texel is answered exactly on the GPU, and on the rays where the CPU's refined
//   answer differs from its kNearest one, the GPU's refined answer differs from the GPU's kNearest
//   one the same way (both counts must be non-zero).
//
// The kernels answer a GpuRay with a GpuOut: the refined answer (with whether the exact step gave
// it), the refined occlusion, and kNearest's answer (gpu/vulkan/shaders/vff_vk_refine.comp's
// VffVkRay and VffVkRefinedAnswer; the GL suite's main makes the same calls).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/baked_shape.h"
#include "common/rng.h"
#include "vff/refine.h"
#include "vff/vff.h"

namespace vff::refinetest {

inline constexpr double kT = 1e-5;       // fraction of R
inline constexpr double kNormal = 1e-5;  // per component
inline constexpr uint64_t kMaxFlagMismatches = 4;  // per shape and answer (intersect, occluded)


struct GpuRay {
  float origin[4], direction[4], range[4];  // range: tmin, tmax, intraBias (-2: VFF_OFF_OBJECT)
};
struct GpuOut {
  float refined[4], normal[4], nearest[4];
  uint32_t lookup[4];  // exact, sample (UINT32_MAX: no lookup), texel i, j
};

// A shape baked with its refinement, written with it (REFN) and opened again; the CPU query reads
// the file, so both sides answer from the same bytes.
struct RefinedShape {
  std::unique_ptr<test::BakedShape> baked;
  Refinement refinement;
  std::optional<File> file;  // (File has no empty state)
  FieldQuery query;
  float groundY = 0;  // the lowest vertex: the ground plane the object stands on
};

inline const RefinedShape& refinedShape(const std::string& name) {
  static std::map<std::string, std::unique_ptr<RefinedShape>> cache;
  std::unique_ptr<RefinedShape>& s = cache[name];
  if (s) return *s;
  s = std::make_unique<RefinedShape>();
  s->baked = test::bakeShape(name, 8, 16, name == "torus-knot");
  const test::BakedShape& b = *s->baked;
  auto r = makeRefinement(b.field.field, b.field.distance, b.mesh.positions, b.mesh.indices);
  EXPECT_TRUE(r.ok()) << r.error().toString();
  if (r.ok()) s->refinement = std::move(*r);
  WriteOptions wo;
  wo.refinement = s->refinement.view();
  wo.layout.maxTextureSize = 64;  // several slices, with a gutter: the fetches cross them
  wo.layout.gutter = 1;
  auto bytes = writeMemory(b.field.field, b.field.distance, b.field.normals, wo);
  EXPECT_TRUE(bytes.ok()) << bytes.error().toString();
  if (bytes.ok()) {
    auto f = File::openBuffer(std::move(*bytes));
    EXPECT_TRUE(f.ok()) << f.error().toString();
    if (f.ok()) {
      s->file.emplace(std::move(*f));
      auto q = FieldQuery::fromFile(*s->file);
      EXPECT_TRUE(q.ok()) << q.error().toString();
      if (q.ok()) s->query = std::move(*q);
    }
  }
  s->groundY = INFINITY;
  for (size_t v = 1; v < b.mesh.positions.size(); v += 3) s->groundY = std::min(s->groundY, b.mesh.positions[v]);
  return *s;
}

enum RaySet { kAimed, kGround, kOnObject, kSets };
inline const char* const kSetNames[kSets] = {"aimed from outside", "ground AO (off object)", "from inside (on object)"};

inline GpuRay gpuRay(Vec3 o, Vec3 d, float tmin, float tmax, float bias) {
  return GpuRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, bias, 0}};
}

// `perSet` rays of each set, set by set.
inline std::vector<GpuRay> makeRays(const RefinedShape& s, uint32_t perSet, uint64_t seed) {
  test::Rng rng(seed);
  const FieldDesc& f = s.file->field();
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  auto at = [&](Vec3 u, float scale) { return Vec3{c.x + u.x * scale, c.y + u.y * scale, c.z + u.z * scale}; };
  std::vector<GpuRay> rays;
  rays.reserve(size_t(perSet) * kSets);
  for (uint32_t r = 0; r < perSet; ++r) {  // from outside, aimed at a point inside (t = 1 there)
    const Vec3 from = at(rng.direction(), R * rng.uniform(1.05f, 3.0f));
    const Vec3 to = at(rng.direction(), R * std::cbrt(rng.uniform()));
    Vec3 d{to.x - from.x, to.y - from.y, to.z - from.z};
    float tmax = INFINITY;
    if (r % 4 == 1) tmax = rng.uniform(0.3f, 1.2f);  // ends inside the sphere: hits near tmax
    if (r % 8 == 2) {
      d = Vec3{d.x * 2.5f, d.y * 2.5f, d.z * 2.5f};
      tmax = tmax / 2.5f;
    }
    rays.push_back(gpuRay(from, d, 0.0f, tmax, -1.0f));
  }
  // Ground AO: points of the plane under the object that lie inside the sphere, cosine-weighted
  // directions up, as vff-experiments ao (origin lifted by 1e-4 R, tmax 2R).
  const float dy = c.y - s.groundY;
  const float disk = std::sqrt(std::max(0.0f, R * R - dy * dy)) * 0.99f;
  for (uint32_t r = 0; r < perSet; ++r) {
    float x, z;
    do {
      x = rng.uniform(-1.0f, 1.0f);
      z = rng.uniform(-1.0f, 1.0f);
    } while (x * x + z * z > 1.0f);
    const Vec3 o{c.x + x * disk, s.groundY + 1e-4f * R, c.z + z * disk};
    rays.push_back(gpuRay(o, rng.cosine({0.0f, 1.0f, 0.0f}), 0.0f, 2.0f * R, -2.0f));
  }
  for (uint32_t r = 0; r < perSet; ++r) {  // from inside, on the object: section 7.3
    const Vec3 o = at(rng.direction(), R * 0.95f * std::cbrt(rng.uniform()));
    rays.push_back(gpuRay(o, rng.direction(), 0.0f, r % 2 ? 0.6f * R : INFINITY, r % 3 == 0 ? 0.0f : -1.0f));
  }
  return rays;
}

inline Ray cpuRay(const GpuRay& g) {
  return Ray{{g.origin[0], g.origin[1], g.origin[2]}, {g.direction[0], g.direction[1], g.direction[2]}, g.range[0],
             g.range[1]};
}

inline QueryOptions cpuOptions(const GpuRay& g, Reconstruction rec) {
  QueryOptions o;
  o.reconstruction = rec;
  o.intraBias = g.range[2];
  if (g.range[2] == -2.0f) o.origin = RayOrigin::kOffObject;  // VFF_OFF_OBJECT
  return o;
}

// A GPU run's answers `out` on `rays` (makeRays(s, perSet, ...)) against the CPU's; prints the
// counts per set.
inline void expectRefinedMatchesCpu(const char* api, const std::string& shape, const RefinedShape& s,
                                    const std::vector<GpuRay>& rays, const std::vector<GpuOut>& out, uint32_t kPerSet) {
  ASSERT_EQ(out.size(), rays.size());
  const FieldDesc& f = s.file->field();
  const float R = f.sphere.radius;
  const uint32_t m = f.mapResolution;
  // The CPU's refined occlusion through the batch call (the any-hit cast), one call per intra
  // bias (the rays of a call share their QueryOptions).
  std::vector<uint8_t> cpuOccluded(rays.size(), 0);
  std::map<float, std::vector<size_t>> byBias;
  for (size_t r = 0; r < rays.size(); ++r) byBias[rays[r].range[2]].push_back(r);
  for (const auto& [bias, which] : byBias) {
    std::vector<Ray> batch;
    for (size_t r : which) batch.push_back(cpuRay(rays[r]));
    std::vector<uint8_t> blocked(batch.size(), 0);
    s.query.occluded(batch, blocked, cpuOptions(rays[which[0]], Reconstruction::kRefined));
    for (size_t q = 0; q < which.size(); ++q) cpuOccluded[which[q]] = blocked[q];
  }

  struct Counts {
    uint64_t hits = 0, flag = 0, occluded = 0, nearestFlag = 0, exact = 0, unsure = 0, unsureExact = 0;
    uint64_t differ = 0, differSame = 0, normals = 0;
    double maxT = 0, maxTExact = 0, maxN = 0;  // maxTExact: over the exact step's hits
  } all[kSets];
  uint64_t failures = 0;
  std::string first;
  auto fail = [&](size_t r, const std::string& why) {
    ++failures;
    if (first.empty()) first = "ray " + std::to_string(r) + ": " + why;
  };
  for (size_t r = 0; r < rays.size(); ++r) {
    Counts& n = all[r / kPerSet];
    const GpuRay& g = rays[r];
    const GpuOut& o = out[r];
    const Ray ray = cpuRay(g);
    const double len = std::sqrt(double(ray.direction.x) * ray.direction.x + double(ray.direction.y) * ray.direction.y +
                                 double(ray.direction.z) * ray.direction.z);
    const QueryOptions qr = cpuOptions(g, Reconstruction::kRefined), qn = cpuOptions(g, Reconstruction::kNearest);
    const QueryHit h = s.query.intersect(ray, qr);
    const QueryHit hn = s.query.intersect(ray, qn);
    const bool gHit = o.refined[0] != 0, gOcc = o.refined[2] != 0, gNearest = o.nearest[0] != 0;
    const bool exact = o.lookup[0] != 0;
    n.exact += exact;
    if (o.normal[3] == 0) fail(r, "vffQueryRefined's answer is not vffIntersectRefined's");
    n.nearestFlag += gNearest != hn.hit;
    n.occluded += gOcc != (cpuOccluded[r] != 0);
    if (gHit != h.hit) {
      ++n.flag;
      continue;
    }
    // The lookup: where it is the CPU's and its texel is unsure, the exact step must answer.
    const LookupSite site = s.query.site(ray, qr);
    const bool sameSite = site.valid && o.lookup[1] == site.sample && o.lookup[2] == site.i && o.lookup[3] == site.j;
    if (sameSite && !h.inside && r / kPerSet != kOnObject &&
        s.file->refinement().isUnsure((uint64_t(site.sample) * m + site.j) * m + site.i)) {
      ++n.unsure;
      n.unsureExact += exact;
      if (!exact) fail(r, "the texel is unsure but the GPU did not take the exact step");
    }
    if (h.hit) {
      ++n.hits;
      const double dt = std::fabs(double(o.refined[1]) - double(h.t)) * len;
      n.maxT = std::max(n.maxT, dt / R);
      if (exact) n.maxTExact = std::max(n.maxTExact, dt / R);
      if (dt > kT * R) {
        fail(r, "t " + std::to_string(o.refined[1]) + " vs the CPU's " + std::to_string(h.t));
        continue;
      }
      if ((o.refined[3] != 0) != h.hasNormal) {
        fail(r, "hasNormal differs");
      } else if (h.hasNormal) {
        ++n.normals;
        const double e = std::max({std::fabs(double(o.normal[0]) - h.normal.x), std::fabs(double(o.normal[1]) - h.normal.y),
                                   std::fabs(double(o.normal[2]) - h.normal.z)});
        n.maxN = std::max(n.maxN, e);
        if (e > kNormal) fail(r, "normal differs by " + std::to_string(e));
      }
    }
    // Where the CPU's refined answer is not its kNearest one, the GPU's must differ from the GPU's
    // kNearest the same way (its nearest answer being the CPU's).
    const bool cpuDiffers = h.hit != hn.hit || (h.hit && std::fabs(double(h.t) - double(hn.t)) * len > kT * R);
    if (cpuDiffers && gNearest == hn.hit) {
      ++n.differ;
      const bool gpuDiffers =
          gHit != gNearest || (gHit && std::fabs(double(o.refined[1]) - double(o.nearest[1])) * len > kT * R);
      n.differSame += gpuDiffers;
      if (!gpuDiffers) fail(r, "the CPU's refined answer differs from kNearest's, the GPU's does not");
      if (!exact) fail(r, "the refined answer differs from kNearest's without the exact step");
    }
  }
  Counts total;
  for (int set = 0; set < kSets; ++set) {
    const Counts& n = all[set];
    std::printf("[ %s ] refined %s, %s: %u rays, %llu hits; exact step %llu (unsure texels %llu, all exact: %llu); "
                "refined != nearest on the CPU %llu, likewise on the GPU %llu; flags differ: intersect %llu, occluded "
                "%llu, nearest %llu; max |dt| %.2g R (exact step's hits %.2g R), %llu normals, max error %.2g\n",
                api, shape.c_str(), kSetNames[set], kPerSet, (unsigned long long)n.hits, (unsigned long long)n.exact,
                (unsigned long long)n.unsure, (unsigned long long)n.unsureExact, (unsigned long long)n.differ,
                (unsigned long long)n.differSame, (unsigned long long)n.flag, (unsigned long long)n.occluded,
                (unsigned long long)n.nearestFlag, n.maxT, n.maxTExact, (unsigned long long)n.normals, n.maxN);
    total.flag += n.flag;
    total.occluded += n.occluded;
    total.exact += n.exact;
    total.differ += n.differ;
    total.unsure += n.unsure;
  }
  EXPECT_EQ(failures, 0u) << first;
  EXPECT_LE(total.flag, kMaxFlagMismatches) << "refined hit flags differ";
  EXPECT_LE(total.occluded, kMaxFlagMismatches) << "refined occlusion differs";
  // The exact step did answer: rays on unsure texels, and rays whose answer it changed.
  EXPECT_GT(total.unsure, 0u);
  EXPECT_GT(total.differ, 0u);
  EXPECT_GT(all[kGround].exact, 0u) << "no ground AO ray took the exact step";
  // Section 7.3's rays never take it.
  EXPECT_EQ(all[kOnObject].exact, 0u);
}

// A run with an empty refinement (triangleCount 0): every ray answered as vffIntersect answers it
// (as the CPU's kRefined without a refinement answers as kNearest).
inline void expectAnsweredAsNearest(const char* api, const std::vector<GpuRay>& rays, const std::vector<GpuOut>& out) {
  ASSERT_EQ(out.size(), rays.size());
  uint64_t hits = 0;
  for (size_t r = 0; r < rays.size(); ++r) {
    const GpuOut& o = out[r];
    hits += o.nearest[0] != 0;
    ASSERT_EQ(o.refined[0], o.nearest[0]) << "ray " << r;
    ASSERT_EQ(o.refined[2], o.nearest[0]) << "ray " << r;
    if (o.nearest[0] != 0) {
      ASSERT_EQ(o.refined[1], o.nearest[1]) << "ray " << r;
    }
    ASSERT_EQ(o.lookup[0], 0u) << "ray " << r;
  }
  std::printf("[ %s ] empty refinement: %zu rays, %llu hits, all answered as vffIntersect\n", api, rays.size(),
              (unsigned long long)hits);
  EXPECT_GT(hits, 0u);
}

}  // namespace vff::refinetest
