// The GLSL normals, kInterpolated reconstruction and ground AO (gpu/glsl/vff_query.glsl,
// gpu/harness/ao_scene.h) against the CPU query, on a headless EGL context.
//
// * Normals: for every ray where the GPU and FieldQuery::intersect (kNearest) both hit at the same
//   t (within 1e-5 R), the GPU normal must be within 1e-5 of the CPU's (each component).
// * kInterpolated: hit flags must agree except where the CPU's vote is within kVoteEps of a tie
//   (visibility within kVoteEps of 0.5: hits and misses weigh the same up to rounding); t within
//   kInterpT R and visibility within kInterpVis, everything else fails.
// * AO: a 64 x 64 ground image, 64 rays per pixel, kNearest and kInterpolated, compared on the 8-bit
//   scale with the CPU image computed from the same rays.
#include <gtest/gtest.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "ao_gl.h"
#include "ao_scene.h"
#include "baked_fields.h"
#include "field_cases.h"
#include "egl_context.h"
#include "gl_test.h"
#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/gl/loader.h"
#include "vff/vff.h"

namespace vff {
namespace {

using gputest::kInterpT, gputest::kInterpVis, gputest::kNormalEps, gputest::kVoteEps;  // field_cases.h

GLuint buildProgram(const char* defines, const std::string& body) {
  std::string log;
  const GLuint prog = harness::buildQueryProgram(defines, body, &log);
  EXPECT_NE(prog, 0u) << log;
  return prog;
}

// One ray per invocation: both reconstructions.
const std::string kMain = "struct TestOut { vec4 nearest; vec4 nearestNormal; vec4 interp; vec4 interpNormal; };\n" +
                          test::rayShaderHead(3, 4) + R"(
  VffHit a = vffIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  float vis;
  VffHit b = vffQuery(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, true, vis);
  TestOut o;
  o.nearest = vec4(a.hit ? 1.0 : 0.0, a.t, a.hasNormal ? 1.0 : 0.0, 0.0);
  o.nearestNormal = vec4(a.normal, 0.0);
  o.interp = vec4(b.hit ? 1.0 : 0.0, b.t, b.hasNormal ? 1.0 : 0.0, vis);
  o.interpNormal = vec4(b.normal, 0.0);
  outs[id] = o;
}
)";

struct GpuRay {
  float origin[4], direction[4], range[4];
};
struct GpuOut {
  float nearest[4], nearestNormal[4], interp[4], interpNormal[4];
};

std::vector<GpuOut> runRays(const gl::GpuField& field, GLuint program, const std::vector<GpuRay>& rays) {
  GLuint bufs[2];
  glGenBuffers(2, bufs);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[0]);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(rays.size() * sizeof(GpuRay)), rays.data(), GL_STATIC_DRAW);
  std::vector<GpuOut> out(rays.size());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[1]);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(out.size() * sizeof(GpuOut)), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, bufs[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, bufs[1]);
  field.bind();
  glUseProgram(program);
  glDispatchCompute(GLuint((rays.size() + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[1]);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(out.size() * sizeof(GpuOut)), out.data());
  glDeleteBuffers(2, bufs);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

using gputest::FieldCase;
using gputest::caseName;
Result<File> bakeFile(const FieldCase& c) { return gputest::bakeFile(c, true); }

class GpuField : public ::testing::TestWithParam<FieldCase> {};

TEST_P(GpuField, NormalsAndInterpolatedMatchCpu) {
  VFF_REQUIRE_GL();
  auto file = bakeFile(GetParam());
  ASSERT_TRUE(file.ok()) << file.error().toString();
  ASSERT_TRUE(file->hasNormals());
  const FieldDesc& f = file->field();
  const float R = f.sphere.radius;
  auto gpu = gl::loadField(*file);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  ASSERT_NE(gpu->normalsTexture(), 0u);
  const GLuint prog = buildProgram(gl::shaderDefines(file->field(), file->layout()), kMain);
  ASSERT_NE(prog, 0u);
  auto cpu = FieldQuery::fromFile(*file);
  ASSERT_TRUE(cpu.ok()) << cpu.error().toString();
  const std::vector<GpuRay> rays = gputest::interpolatedRays<GpuRay>(f, 8192, 77);  // field_cases.h
  const std::vector<GpuOut> out = runRays(*gpu, prog, rays);
  glDeleteProgram(prog);

  uint64_t nHits = 0, nNormals = 0, nExact = 0, nFlag = 0, nFail = 0;
  double nMax = 0;
  uint64_t iRays = 0, iAgree = 0, iTie = 0, iHits = 0, iFail = 0, iNormals = 0;
  double iMaxT = 0, iMaxVis = 0, iMaxN = 0;
  std::string first;
  auto fail = [&](size_t r, const std::string& why) {
    if (first.empty()) first = "ray " + std::to_string(r) + ": " + why;
  };
  for (size_t r = 0; r < rays.size(); ++r) {
    const GpuRay& g = rays[r];
    const Ray ray{{g.origin[0], g.origin[1], g.origin[2]}, {g.direction[0], g.direction[1], g.direction[2]},
                  g.range[0], g.range[1]};
    const double len = std::sqrt(double(ray.direction.x) * ray.direction.x + double(ray.direction.y) * ray.direction.y +
                                 double(ray.direction.z) * ray.direction.z);
    const GpuOut& o = out[r];
    // kNearest and its normal.
    QueryOptions qn;
    qn.intraBias = g.range[2];
    if (g.range[2] == -2.0f) qn.origin = RayOrigin::kOffObject;  // VFF_OFF_OBJECT
    const QueryHit h = cpu->intersect(ray, qn);
    const bool gh = o.nearest[0] != 0;
    if (gh != h.hit) {
      ++nFlag;  // allowed only at a boundary; test_gpu_query.cpp classifies these, here none occur
    } else if (h.hit) {
      ++nHits;
      if (std::fabs(double(o.nearest[1]) - double(h.t)) * len > 1e-5 * R) continue;
      const bool hasN = o.nearest[2] != 0;
      if (hasN != h.hasNormal) {
        ++nFail;
        fail(r, "hasNormal differs");
        continue;
      }
      ++nNormals;
      const double e = std::max({std::fabs(double(o.nearestNormal[0]) - h.normal.x),
                                 std::fabs(double(o.nearestNormal[1]) - h.normal.y),
                                 std::fabs(double(o.nearestNormal[2]) - h.normal.z)});
      nMax = std::max(nMax, e);
      nExact += e == 0;
      if (e > kNormalEps) {
        ++nFail;
        fail(r, "nearest normal differs by " + std::to_string(e));
      }
    }
    // kInterpolated.
    QueryOptions qi = qn;
    qi.reconstruction = Reconstruction::kInterpolated;
    const QueryHit hi = cpu->intersect(ray, qi);
    const float vis = cpu->visibility(ray, qi);
    ++iRays;
    const double dv = std::fabs(double(o.interp[3]) - double(vis));
    iMaxVis = std::max(iMaxVis, dv);
    if (dv > kInterpVis) {
      ++iFail;
      fail(r, "interpolated visibility " + std::to_string(o.interp[3]) + " vs " + std::to_string(vis));
      continue;
    }
    const bool gi = o.interp[0] != 0;
    if (gi != hi.hit) {
      if (std::fabs(double(vis) - 0.5) <= kVoteEps) {
        ++iTie;
      } else {
        ++iFail;
        fail(r, "interpolated hit flag differs, visibility " + std::to_string(vis));
      }
      continue;
    }
    ++iAgree;
    if (!hi.hit) continue;
    ++iHits;
    const double dt = std::fabs(double(o.interp[1]) - double(hi.t)) * len / R;
    iMaxT = std::max(iMaxT, dt);
    if (dt > kInterpT) {
      ++iFail;
      fail(r, "interpolated t differs by " + std::to_string(dt) + " R");
      continue;
    }
    if ((o.interp[2] != 0) != hi.hasNormal) {
      ++iFail;
      fail(r, "interpolated hasNormal differs");
      continue;
    }
    if (hi.hasNormal) {
      ++iNormals;
      const double e = std::max({std::fabs(double(o.interpNormal[0]) - hi.normal.x),
                                 std::fabs(double(o.interpNormal[1]) - hi.normal.y),
                                 std::fabs(double(o.interpNormal[2]) - hi.normal.z)});
      iMaxN = std::max(iMaxN, e);
      if (e > 1e-4) {
        ++iFail;
        fail(r, "interpolated normal differs by " + std::to_string(e));
      }
    }
  }
  std::printf("[ gpu ] %s: kNearest: %llu common hits, %llu normals compared (%llu bit-identical), max |n_gpu - "
              "n_cpu| = %.3g, hit-flag mismatches %llu\n",
              caseName(GetParam()).c_str(), (unsigned long long)nHits, (unsigned long long)nNormals,
              (unsigned long long)nExact, nMax, (unsigned long long)nFlag);
  std::printf("[ gpu ] %s: kInterpolated: %llu rays, agreement %.3f%%, vote ties %llu, failures %llu; %llu hits, "
              "max |t_gpu - t_cpu| = %.3g R, max |vis_gpu - vis_cpu| = %.3g, %llu normals, max diff %.3g\n",
              caseName(GetParam()).c_str(), (unsigned long long)iRays, 100.0 * double(iAgree) / double(iRays),
              (unsigned long long)iTie, (unsigned long long)iFail, (unsigned long long)iHits, iMaxT, iMaxVis,
              (unsigned long long)iNormals, iMaxN);
  EXPECT_EQ(nFail, 0u) << first;
  EXPECT_EQ(nFlag, 0u);
  EXPECT_EQ(iFail, 0u) << first;
  EXPECT_GT(nNormals, rays.size() / 8);
  EXPECT_GT(iHits, rays.size() / 8);
}

// field_cases.h's, which the Vulkan suite (test_vk_query.cpp) runs too.
INSTANTIATE_TEST_SUITE_P(Fields, GpuField, ::testing::ValuesIn(gputest::interpolatedCases()), gputest::caseParamName);

// ---- Ground AO ---------------------------------------------------------------------------------------

// GpuField owns its GL objects through vff::gl::GlName: a move leaves the source empty and the
// objects alive in the target; assigning over a field and release() delete its objects.
TEST(GpuFieldObjects, MovesKeepAndReleaseDeletes) {
  VFF_REQUIRE_GL();
  const gputest::FieldCase c{PositionScheme::kOctaHemi2, DirectionScheme::kHemiOctahedral,
                                DistanceEncoding::kUnorm8Diameter};
  auto file = gputest::bakeFile(c, true);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  auto loaded = gl::loadField(*file);
  ASSERT_TRUE(loaded.ok()) << loaded.error().toString();
  gl::GpuField a = std::move(*loaded);
  const GLuint maps = a.mapsTexture(), normals = a.normalsTexture(), block = a.fieldBuffer(),
               positions = a.positionsBuffer();
  ASSERT_NE(maps, 0u);
  ASSERT_NE(normals, 0u);
  EXPECT_EQ(loaded->mapsTexture(), 0u);  // the moved-from field holds nothing
  EXPECT_EQ(loaded->textureBytes(), 0u);
  gl::GpuField b(std::move(a));
  EXPECT_EQ(a.mapsTexture(), 0u);
  EXPECT_EQ(a.fieldBuffer(), 0u);
  EXPECT_EQ(b.mapsTexture(), maps);
  EXPECT_TRUE(glIsTexture(maps) && glIsTexture(normals) && glIsBuffer(block) && glIsBuffer(positions));
  auto other = gl::loadField(*file);
  ASSERT_TRUE(other.ok());
  b = std::move(*other);  // b's first objects are deleted
  EXPECT_FALSE(glIsTexture(maps) || glIsTexture(normals) || glIsBuffer(block) || glIsBuffer(positions));
  const GLuint second = b.mapsTexture();
  EXPECT_TRUE(glIsTexture(second));
  b.release();
  EXPECT_EQ(b.mapsTexture(), 0u);
  EXPECT_FALSE(glIsTexture(second));
}

TEST(GpuAo, GroundAoMatchesCpu) {
  VFF_REQUIRE_GL();
  const bake::Mesh mesh = bake::makeShape("torus-knot");
  auto scene = bake::Scene::create(mesh);
  ASSERT_TRUE(scene.ok());
  bake::BakeOptions bo;
  bo.positionScheme = PositionScheme::kOctaHemi2;
  bo.positionParam = 8;  // 290 maps
  bo.mapResolution = 32;
  bo.encoding = DistanceEncoding::kUnorm8Diameter;
  auto baked = bake::bakeField(*scene, bo);
  ASSERT_TRUE(baked.ok()) << baked.error().toString();
  auto bytes = writeMemory(baked->field, baked->distance);
  ASSERT_TRUE(bytes.ok());
  auto file = File::openBuffer(std::move(*bytes));
  ASSERT_TRUE(file.ok());
  float minY = INFINITY;
  for (size_t v = 1; v < mesh.positions.size(); v += 3) minY = std::min(minY, mesh.positions[v]);
  constexpr int kSize = 64, kRays = 64;
  const harness::AoScene s = harness::makeAoScene(file->field(), minY, kSize);
  auto gpu = gl::loadField(*file);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  auto cpu = FieldQuery::fromFile(*file);
  ASSERT_TRUE(cpu.ok());
  const GLuint prog = buildProgram("", harness::kAoShader);
  ASSERT_NE(prog, 0u);
  const harness::AoBuffers aoBuffers(s);
  gpu->bind();
  glUseProgram(prog);
  for (Reconstruction r : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    const bool interp = r == Reconstruction::kInterpolated;
    std::vector<float> g;
    (void)harness::renderAo(s, aoBuffers, kRays, interp ? 1 : 0, &g);
    const std::vector<float> c = harness::cpuAo(*cpu, s, kRays, r, 2);
    const harness::AoDiff d = harness::compareAo(c, g);
    std::printf("[ gpu ] ground AO %dx%d, %d rays/px, %s: mean AO %.4f; GPU vs CPU on the 8-bit scale: max %.0f, "
                "RMS %.4f, %llu of %d pixels differ\n",
                kSize, kSize, kRays, interp ? "kInterpolated visibility" : "kNearest occluded", d.meanA, d.max, d.rms,
                (unsigned long long)d.differing, kSize * kSize);
    // Tolerance: at most one ray in 64 answered differently (4 levels) for kNearest; float
    // summation only (1 level) for kInterpolated.
    EXPECT_LE(d.max, interp ? 1.0 : 4.0);
    EXPECT_LE(d.rms, interp ? 0.1 : 0.25);
    EXPECT_LT(d.meanA, 0.99);  // the object does occlude the ground
  }
  glDeleteProgram(prog);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

}  // namespace
}  // namespace vff
