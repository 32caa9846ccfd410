// sdf_bench.cpp - vff-gpu-bench --sdf (sdf_bench.h).
#include "sdf_bench.h"

#include <GL/glcorearb.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "vff/bake/embree_reference.h"
#include "egl_context.h"
#include "ao_gl.h"
#include "scene_bench.h"
#include "sdf_ao.h"
#include "sdf_gl.h"

namespace vff::harness {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point a) {
  return std::chrono::duration<double>(Clock::now() - a).count();
}

// The query cpuAo calls for the exact image: Embree's occlusion test on the mesh.
struct ExactAoQuery {
  const bake::EmbreeReference* exact = nullptr;
  bool visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions&) const {
    for (size_t i = 0; i < rays.size() && i < out.size(); ++i)
      out[i] = exact->occluded(rays[i].origin, rays[i].direction, rays[i].tmin, rays[i].tmax) ? 0.0f : 1.0f;
    return true;
  }
};

double mib(uint64_t bytes) {
  return double(bytes) / 1048576.0;
}

}  // namespace

int benchSdf(const File& file, const FieldQuery& cpu, const bake::Mesh& mesh, float groundY,
             const gl::GpuField& gpuField, unsigned fieldProgram, const SdfBenchOptions& o) {
  const FieldDesc& f = file.field();
  const uint64_t budget = cpu.payloadBytes();
  const auto b0 = Clock::now();
  auto built = vffx::SdfField::build(mesh, {.budgetBytes = budget, .bandVoxels = o.bandVoxels});
  if (!built) {
    std::fprintf(stderr, "vff-gpu-bench: error: distance field: %s\n", built.error().toString().c_str());
    return 4;
  }
  const vffx::SdfField& sdf = *built;
  std::printf(
      "\ndistance field: fp8, voxel %.4g R, band %.3g voxels, built in %.1f s (%d builds) for the field's payload "
      "of %.2f MiB\n",
      double(sdf.voxelSize() / f.sphere.radius), double(sdf.bandVoxels()), secondsSince(b0), sdf.builds(), mib(budget));
  auto gpuSdf = vffx::gl::uploadSdf(sdf);
  if (!gpuSdf) {
    std::fprintf(stderr, "vff-gpu-bench: error: %s\n", gpuSdf.error().toString().c_str());
    return 4;
  }
  std::string log;
  const GLuint sdfProgram = harness::buildProgram(
      sdfAoShaderSource(sdf, harness::readGlsl("vff_query.glsl"), harness::readGlsl("vff_sdf.glsl")), &log);
  if (!sdfProgram) {
    std::fprintf(stderr, "vff-gpu-bench: error: vff_sdf.glsl: %s\n", log.c_str());
    return 4;
  }

  const int size = o.size, spp = o.spp;
  const AoScene s = makeAoScene(f, groundY, size, o.aoDistance);
  const AoBuffers aoBuffers(s);
  gpuField.bind();
  gpuSdf->bind();

  const bake::EmbreeReference exact(mesh);
  auto c0 = Clock::now();
  const std::vector<float> ref = cpuAo(ExactAoQuery{&exact}, s, spp, Reconstruction::kNearest, o.threads);
  const double exactS = secondsSince(c0);

  std::printf(
      "\nground AO %dx%d, %d rays/px, tmax %g R, at equal memory; max and RMS against the exact image (Embree) on "
      "the 8-bit scale; CPU: the same image by the same method on %u thread(s)\n",
      size, size, spp, double(o.aoDistance), o.threads);
  std::printf("| AO by | memory | GPU frame s | CPU s | max | RMS |\n|---|---|---|---|---|---|\n");
  std::printf("| exact (Embree) | mesh, %zu triangles | - | %.3f | 0 | 0 |\n", mesh.triangleCount(), exactS);
  glUseProgram(fieldProgram);
  for (int interp = 0; interp < 2; ++interp) {
    std::vector<float> g;
    const double gpuS = renderAo(s, aoBuffers, spp, interp, &g);
    c0 = Clock::now();
    (void)cpuAo(cpu, s, spp, interp ? Reconstruction::kInterpolated : Reconstruction::kNearest, o.threads);
    const double cpuS = secondsSince(c0);
    const AoDiff d = compareAo(ref, g);
    std::printf("| field GLSL, %s | payload %.2f MiB (texture %.2f MiB) | %.3f | %.3f | %.0f | %.3f |\n",
                interp ? "interpolated" : "nearest", mib(budget), mib(gpuField.textureBytes()), gpuS, cpuS, d.max,
                d.rms);
    std::fflush(stdout);
  }
  glUseProgram(sdfProgram);
  // As vff-experiments ao: hit or miss beside the field's nearest row, the cone estimate (one of
  // spp equal cones over the hemisphere) beside its interpolated row.
  for (const bool cone : {false, true}) {
    const vffx::SdfTraceOptions so = vffx::sdfOptions(cone, false, vffx::hemisphereConeTan(spp));
    if (vff::Status st = gpuSdf->setTraceOptions(so); !st) {
      std::fprintf(stderr, "vff-gpu-bench: error: %s\n", st.error().toString().c_str());
      return 4;
    }
    gpuSdf->bind();
    std::vector<float> g;
    const double gpuS = renderAo(s, aoBuffers, spp, cone ? 1 : 0, &g);
    c0 = Clock::now();
    (void)cpuAo(SdfAoQuery{&sdf, so}, s, spp, Reconstruction::kNearest, o.threads);
    const double cpuS = secondsSince(c0);
    const AoDiff d = compareAo(ref, g);
    std::printf("| distance field GLSL, %s | bricks %.2f MiB (NanoVDB %.2f MiB) | %.3f | %.3f | %.0f | %.3f |\n",
                cone ? "cone estimate" : "hit or miss", mib(sdf.bytes()), mib(gpuSdf->gridBytes()), gpuS, cpuS, d.max,
                d.rms);
    std::fflush(stdout);
  }
  glDeleteProgram(sdfProgram);
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    std::fprintf(stderr, "vff-gpu-bench: error: --sdf: GL error 0x%04x\n", unsigned(e));
    return 4;
  }
  return 0;
}

}  // namespace vff::harness
