// The distance-field peer's GLSL sphere tracer (gpu/glsl/vff_sdf.glsl through PNanoVDB, uploaded by
// gpu/sdf/sdf_gl.h) against the CPU tracer (sdf/src/sdf_field.cpp) on the same rays and
// the same grid, on a headless EGL context.
//
// Tolerances. Both tracers run in binary32 (the grid's float map, float samples and steps), the
// same operations in the same order; they can part only where the GPU rounds differently (llvmpipe
// contracts a * b + c into fused multiply-adds, its length() and divisions are not the CPU's to the
// last bit). A sample within rounding of hitVoxels then hits on one side and takes one more step
// (at least minStepVoxels) on the other, and a step whose length rounds differently can land on
// either side of a block's exit. So: hit flags may differ on at most kMaxFlipShare of the rays; where
// both hit, t within kTightVoxels voxels on at least kTightShare of them, and within kLooseVoxels
// (one step below the hit threshold plus the threshold itself) on all; the cone estimate within
// kConeVis on all but kMaxFlipShare of the rays. The AO images (same rays: ao_scene.h) within kAoMax
// levels of 255 per pixel, RMS kAoRms.
#include <GL/glcorearb.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "ao_gl.h"
#include "sdf_ao.h"
#include "vff/sdf/sdf_field.h"
#include "dispatch.h"
#include "egl_context.h"
#include "gl_test.h"
#include "sdf_gl.h"
#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vff/bake/sphere.h"

namespace {

using vff::Vec3;

constexpr double kMaxFlipShare = 0.002;
constexpr double kTightVoxels = 1e-4;
constexpr double kTightShare = 0.99;
constexpr double kLooseVoxels = 0.5;
constexpr double kAoMax = 8.0;  // one ray of 32 answered differently
constexpr double kAoRms = 0.25;
constexpr double kConeVis = 1e-4;  // the cone estimate, where the traces agree

const char* kRayMain = R"(
layout(local_size_x = 64) in;
struct TestRay { vec4 origin; vec4 direction; };  // origin.w tmin, direction.w tmax
layout(std430, binding = 3) readonly buffer TestRays { TestRay rays[]; };
layout(std430, binding = 4) writeonly buffer TestOuts { vec4 outs[]; };
void main() {
  uint id = gl_GlobalInvocationID.x;
  if (id >= uint(rays.length())) return;
  TestRay r = rays[id];
  VffSdfHit h = vffSdfIntersect(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w);
  outs[id] = vec4(h.hit ? 1.0 : 0.0, h.t, float(h.steps), vffSdfVisibility(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w));
}
)";

vffx::SdfField buildSdf(const vff::bake::Mesh& m, uint64_t budget, vffx::SdfValues values) {
  auto sdf = vffx::SdfField::build(m, {.budgetBytes = budget, .values = values});
  if (!sdf) ADD_FAILURE() << sdf.error().toString();
  return std::move(*sdf);
}

vff::Sphere boundingSphere(const vff::bake::Mesh& m) {
  return vff::bake::minimalEnclosingSphere(m.positions);
}

// Rays from outside the sphere aimed at points inside it (3 in 4), and from inside (1 in 4); some
// with non-unit directions and a finite tmax.
std::vector<vff::Ray> makeRays(const vff::Sphere& s, uint32_t n, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(0, 1);
  auto dir = [&] {
    Vec3 v{nd(g), nd(g), nd(g)};
    const float l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return Vec3{v.x / l, v.y / l, v.z / l};
  };
  const Vec3 c{s.center[0], s.center[1], s.center[2]};
  const float R = s.radius;
  std::vector<vff::Ray> rays(n);
  for (uint32_t i = 0; i < n; ++i) {
    Vec3 o, d;
    float tmax = INFINITY;
    if (i % 4 != 3) {
      const Vec3 a = dir(), b = dir();
      const float r0 = R * (1.1f + u(g)), r1 = R * 0.8f * std::cbrt(u(g));
      o = {c.x + a.x * r0, c.y + a.y * r0, c.z + a.z * r0};
      d = {c.x + b.x * r1 - o.x, c.y + b.y * r1 - o.y, c.z + b.z * r1 - o.z};
      if (i % 8 == 2) d = {d.x * 0.4f, d.y * 0.4f, d.z * 0.4f};
      if (i % 16 == 4) tmax = 1.2f * u(g);
    } else {
      const Vec3 a = dir();
      const float r0 = R * 0.9f * std::cbrt(u(g));
      o = {c.x + a.x * r0, c.y + a.y * r0, c.z + a.z * r0};
      d = dir();
    }
    rays[i] = vff::Ray{o, d, 0.0f, tmax};
  }
  return rays;
}

GLuint buildSdfProgram(const vffx::SdfField& sdf, const std::string& body) {
  std::string log;
  const std::string src = "#version 430\n" + vffx::gl::sdfShaderDefines(sdf) +
                          vffx::gl::sdfShaderSource(vff::harness::readGlsl("vff_sdf.glsl")) + body;
  const GLuint prog = vff::harness::buildProgram(src, &log);
  EXPECT_NE(prog, 0u) << log;
  return prog;
}

// kRayMain over `rays` with the grid uploaded with `options`: hit, t, steps, visibility per ray.
std::vector<float> runRays(const vffx::SdfField& sdf, const vffx::SdfTraceOptions& options,
                           const std::vector<vff::Ray>& rays) {
  auto gpu = vffx::gl::uploadSdf(sdf, options);
  EXPECT_TRUE(gpu) << gpu.error().toString();
  if (!gpu) return {};
  EXPECT_EQ(gpu->gridBytes(), sdf.nanovdbBytes());
  const GLuint prog = buildSdfProgram(sdf, kRayMain);
  if (!prog) return {};
  std::vector<float> in(rays.size() * 8);
  for (size_t i = 0; i < rays.size(); ++i) {
    const vff::Ray& r = rays[i];
    const float v[8] = {r.origin.x,    r.origin.y,    r.origin.z,    r.tmin,
                        r.direction.x, r.direction.y, r.direction.z, r.tmax};
    std::copy(v, v + 8, &in[i * 8]);
  }
  gpu->bind();
  glUseProgram(prog);
  std::vector<float> out = vff::test::dispatchRays<float>(std::span<const float>(in), rays.size(), 4, 3, 4);
  glDeleteProgram(prog);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

// GPU against CPU on `rays` through one grid; prints the counts.
void compareTracers(const char* what, const vffx::SdfField& sdf, const std::vector<vff::Ray>& rays) {
  const std::vector<float> out = runRays(sdf, {}, rays);
  ASSERT_EQ(out.size(), rays.size() * 4);
  size_t hits = 0, flips = 0, both = 0, tight = 0;
  double worst = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const vffx::SdfHit c = sdf.intersect(rays[i]);
    const bool g = out[i * 4] != 0;
    EXPECT_EQ(out[i * 4 + 3], g ? 0.0f : 1.0f) << "without a cone, visibility is 0 or 1";
    hits += c.hit;
    if (c.hit != g) {
      ++flips;
      continue;
    }
    if (!c.hit) continue;
    ++both;
    // |t difference| in voxels: t is in multiples of the direction.
    const Vec3& d = rays[i].direction;
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    const double dv = std::fabs(double(out[i * 4 + 1]) - double(c.t)) * len / double(sdf.voxelSize());
    worst = std::max(worst, dv);
    tight += dv <= kTightVoxels;
    EXPECT_LE(dv, kLooseVoxels) << what << " ray " << i << ": CPU t " << c.t << ", GPU t " << out[i * 4 + 1];
  }
  std::printf(
      "[ gpu ] sdf %s (%s, voxel %.4g, NanoVDB %llu bytes): %zu rays, %zu hits; hit flags differ on %zu; "
      "where both hit (%zu): t within %.0e voxels on %zu, worst %.3g voxels\n",
      what, sdf.values() == vffx::SdfValues::kFp8 ? "fp8" : "float", double(sdf.voxelSize()),
      (unsigned long long)sdf.nanovdbBytes(), rays.size(), hits, flips, both, kTightVoxels, tight, worst);
  EXPECT_GT(hits, rays.size() / 4) << "too few hits for the test to mean anything";
  EXPECT_LE(double(flips), kMaxFlipShare * double(rays.size()));
  EXPECT_GE(double(tight), kTightShare * double(both));
}

TEST(GpuSdf, TracerMatchesCpuOnTorusKnot) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const auto rays = makeRays(boundingSphere(m), 2048, 11);
  for (vffx::SdfValues v : {vffx::SdfValues::kFloat, vffx::SdfValues::kFp8})
    compareTracers("torus knot", buildSdf(m, 256 << 10, v), rays);
}

TEST(GpuSdf, TracerMatchesCpuOnBunny) {
  VFF_REQUIRE_GL();
  const std::string path = std::string(VFF_SHARED_MESHES) + "/stanford-bunny.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found (the shared test meshes)";
  auto m = vff::bake::loadMesh(path);
  ASSERT_TRUE(m) << m.error().toString();
  compareTracers("stanford bunny", buildSdf(*m, 512 << 10, vffx::SdfValues::kFp8),
                 makeRays(boundingSphere(*m), 1024, 12));
}

// The cone estimate (vffSdfVisibility with the block's coneTan, then coneRadiusAtEnd) against
// SdfField::visibility on the same rays: the minimum over the same steps of the same expression,
// so within rounding where the traces agree.
TEST(GpuSdf, ConeEstimateMatchesCpu) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const vff::Sphere bs = boundingSphere(m);
  const vffx::SdfField sdf = buildSdf(m, 256 << 10, vffx::SdfValues::kFp8);
  // A finite tmax on every ray (coneRadiusAtEnd's cone is set by it): 4 R along the ray.
  std::vector<vff::Ray> rays = makeRays(bs, 2048, 13);
  for (vff::Ray& r : rays)
    r.tmax = std::min(r.tmax, 4.0f * bs.radius /
                                  std::sqrt(r.direction.x * r.direction.x + r.direction.y * r.direction.y +
                                            r.direction.z * r.direction.z));
  vffx::SdfTraceOptions byTan, byRadius;
  byTan.coneTan = vffx::hemisphereConeTan(32);
  byRadius.coneRadiusAtEnd = 0.2f * bs.radius;
  for (const vffx::SdfTraceOptions& o : {byTan, byRadius}) {
    const std::vector<float> out = runRays(sdf, o, rays);
    ASSERT_EQ(out.size(), rays.size() * 4);
    std::vector<float> cpu(rays.size());
    sdf.visibility(rays, cpu, o);
    size_t off = 0, partial = 0;
    double worst = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const double e = std::fabs(double(out[i * 4 + 3]) - double(cpu[i]));
      off += e > kConeVis;
      partial += cpu[i] > 0 && cpu[i] < 1;
      worst = std::max(worst, e);
    }
    std::printf(
        "[ gpu ] sdf cone estimate (%s): %zu rays, %zu with a partial estimate; %zu differ by over %.0e, "
        "worst %.3g\n",
        o.coneTan > 0 ? "coneTan" : "coneRadiusAtEnd", rays.size(), partial, off, kConeVis, worst);
    EXPECT_GT(partial, rays.size() / 8) << "too few partial estimates for the test to mean anything";
    EXPECT_LE(double(off), kMaxFlipShare * double(rays.size()));
  }
}

// The ground AO (ao_scene.h) under the torus knot through the GLSL tracer and the CPU one: hit or
// miss (kAoShader's nearest path) and the cone estimate (its interpolated path, the experiments'
// options: sdfOptions, hemisphereConeTan).
TEST(GpuSdf, GroundAoMatchesCpu) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const vffx::SdfField sdf = buildSdf(m, 256 << 10, vffx::SdfValues::kFp8);
  float minY = INFINITY;
  for (size_t v = 1; v < m.positions.size(); v += 3) minY = std::min(minY, m.positions[v]);
  vff::FieldDesc f;
  f.sphere = boundingSphere(m);
  constexpr int kSize = 32, kRays = 32;
  const vff::harness::AoScene s = vff::harness::makeAoScene(f, minY, kSize);
  auto gpu = vffx::gl::uploadSdf(sdf);
  ASSERT_TRUE(gpu) << gpu.error().toString();
  std::string log;
  const GLuint prog = vff::harness::buildProgram(
      vff::harness::sdfAoShaderSource(sdf, vff::harness::readGlsl("vff_query.glsl"), vff::harness::readGlsl("vff_sdf.glsl")),
      &log);
  ASSERT_NE(prog, 0u) << log;
  const vff::harness::AoBuffers aoBuffers(s);
  for (const bool cone : {false, true}) {
    const vffx::SdfTraceOptions so = vffx::sdfOptions(cone, false, vffx::hemisphereConeTan(kRays));
    ASSERT_TRUE(gpu->setTraceOptions(so));
    gpu->bind();
    glUseProgram(prog);
    std::vector<float> g;
    (void)vff::harness::renderAo(s, aoBuffers, kRays, cone ? 1 : 0, &g);
    ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    const std::vector<float> c =
        vff::harness::cpuAo(vff::harness::SdfAoQuery{&sdf, so}, s, kRays, vff::Reconstruction::kNearest, 2);
    const vff::harness::AoDiff d = vff::harness::compareAo(c, g);
    std::printf(
        "[ gpu ] sdf ground AO %dx%d, %d rays/px, %s: CPU mean AO %.4f (min %.3f); GPU vs CPU on the 8-bit "
        "scale: max %.0f, RMS %.4f, %llu of %d pixels differ\n",
        kSize, kSize, kRays, cone ? "cone estimate" : "hit or miss", d.meanA, d.minA, d.max, d.rms,
        (unsigned long long)d.differing, kSize * kSize);
    EXPECT_LT(d.minA, 0.9) << "the knot should occlude some of the ground";
    EXPECT_LE(d.max, kAoMax);
    EXPECT_LE(d.rms, kAoRms);
  }
  glDeleteProgram(prog);
}

}  // namespace
