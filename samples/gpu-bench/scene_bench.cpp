// scene_bench.cpp - vff-gpu-bench --scene N (scene_bench.h): N instances of the field on a grid over
// the ground, turned and scaled at random; the ground AO of the scene on the GPU (vff_scene.glsl)
// against the CPU vff::Scene's batch visibility, and a frame's instance update on both sides.
#include "ao_gl.h"
#include "scene_bench.h"

#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "egl_context.h"
#include "vff/gl/scene_loader.h"

namespace vff::harness {
namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Instance i of frame `frame`: on a square grid with 2.5 R spacing, standing on the ground
// (y = groundY in object space, scaled about it), turned about y.
RigidTransform placement(const FieldDesc& f, float groundY, int i, int side, int frame, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float R = f.sphere.radius, spacing = 2.5f * R;
  const float scale = 0.7f + 0.5f * u(rng), angle = 6.2831853f * u(rng) + 0.1f * float(frame);
  const float x = (float(i % side) - 0.5f * float(side - 1)) * spacing;
  const float z = (float(i / side) - 0.5f * float(side - 1)) * spacing;
  return RigidTransform::fromAxisAngle({0, 1, 0}, angle, {x, groundY * (1.0f - scale), z}, scale);
}

}  // namespace

int benchScene(const File& file, const FieldQuery& cpu, float groundY, const SceneBenchOptions& o) {
  const FieldDesc& f = file.field();
  const int side = std::max(1, int(std::ceil(std::sqrt(double(o.instances)))));
  std::mt19937 rng(1u);
  Scene scene;
  for (int i = 0; i < o.instances; ++i)
    if (auto id = scene.add(&cpu, placement(f, groundY, i, side, 0, rng)); !id) {
      std::fprintf(stderr, "vff-gpu-bench: %s\n", id.error().toString().c_str());
      return 4;
    }
  if (Status s = scene.commit(); !s) {
    std::fprintf(stderr, "vff-gpu-bench: %s\n", s.error().toString().c_str());
    return 4;
  }
  const gl::SceneField fields[] = {{&file, &cpu}};
  auto gpu = gl::loadScene(fields);
  if (!gpu) {
    std::fprintf(stderr, "vff-gpu-bench: %s\n", gpu.error().toString().c_str());
    return 4;
  }
  // A frame: every instance moves, the CPU commits, the GPU takes the new instances and hierarchy.
  constexpr int kFrames = 8;
  double commitS = 0, updateS = 0;
  for (int frame = 1; frame <= kFrames; ++frame) {
    for (int i = 0; i < o.instances; ++i) (void)scene.setTransform(uint32_t(i), placement(f, groundY, i, side, frame, rng));
    const auto t0 = Clock::now();
    (void)scene.commit();
    const auto t1 = Clock::now();
    if (Status s = gpu->update(scene); !s) {
      std::fprintf(stderr, "vff-gpu-bench: %s\n", s.error().toString().c_str());
      return 4;
    }
    glFinish();
    commitS += seconds(t0, t1);
    updateS += seconds(t1, Clock::now());
  }
  // The ground under the whole grid: the AO scene of a sphere that bounds it.
  FieldDesc bounds = f;
  bounds.sphere.radius = 0.5f * (float(side) * 2.5f + 1.0f) * f.sphere.radius;
  bounds.sphere.center[0] = bounds.sphere.center[2] = 0;
  AoScene ao = makeAoScene(bounds, groundY, o.size);
  ao.eps = 1e-4f * f.sphere.radius;  // the rays of the single-field render: eps and tmax of one R
  ao.tmax = o.aoDistance * f.sphere.radius;

  std::string log;
  const GLuint prog = harness::buildProgram(sceneAoShaderSource(), &log);
  if (!prog) {
    std::fprintf(stderr, "vff-gpu-bench: scene shader: %s\n", log.c_str());
    return 4;
  }
  const AoBuffers aoBuffers(ao);
  useSceneAo(*gpu, aoBuffers, prog);
  std::printf("\nscene: %d instances of the field on a %dx%d grid; a frame moves all of them: CPU commit %.3g ms, "
              "GPU update %.3g ms (mean of %d)\n",
              o.instances, side, side, 1e3 * commitS / kFrames, 1e3 * updateS / kFrames, kFrames);
  std::printf("scene ground AO %dx%d, %d rays/px, tmax %g R; GPU (vff_scene.glsl) vs CPU vff::Scene on %u thread(s)\n",
              o.size, o.size, o.spp, double(o.aoDistance), o.threads);
  std::printf("| query | GPU s | CPU s | GPU/CPU | mean AO | max | RMS |\n|---|---|---|---|---|---|---|\n");
  for (int interp = 0; interp < 2; ++interp) {
    std::vector<float> g;
    const double gpuS = renderAo(ao, aoBuffers, o.spp, interp, &g);
    const auto c0 = Clock::now();
    const std::vector<float> c =
        cpuAo(scene, ao, o.spp, interp ? Reconstruction::kInterpolated : Reconstruction::kNearest, o.threads);
    const double cpuS = seconds(c0, Clock::now());
    const AoDiff d = compareAo(c, g);
    std::printf("| %s | %.2f | %.2f | %.2f | %.4f | %.0f | %.4f |\n",
                interp ? "interpolated visibility" : "nearest occluded", gpuS, cpuS, cpuS / gpuS, d.meanA, d.max, d.rms);
    std::fflush(stdout);
  }
  glDeleteProgram(prog);
  return glGetError() == GL_NO_ERROR ? 0 : 4;
}

}  // namespace vff::harness
