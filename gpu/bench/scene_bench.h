// scene_bench.h - vff-gpu-bench's scene mode (--scene N): the ground AO under N instances of the
// field, rendered through gpu/glsl/vff_scene.glsl (vff::gl::GpuScene) and with the CPU vff::Scene
// on the same rays in the same run, plus the per-frame cost of moving every instance (Scene::commit
// and GpuScene::update).
#pragma once

#include <string>
#include <vector>

#include "ao_scene.h"
#include "vff/vff.h"

namespace vff::gpubench {

struct SceneBenchOptions {
  int instances = 16;
  int size = 512, spp = 256;
  unsigned threads = 1;
};

// Runs the AO shader program in use (uniforms as kAoShader's; buffers bound at 5, 6, 7) over the
// scene's pixels in bands; the image in *image; returns the seconds of the dispatches (main.cpp).
double renderGpuAo(const AoScene& s, int spp, int interp, unsigned imageBuffer, std::vector<float>* image);

// Prints the scene's table; returns an exit code (0, or 4 for a GL or shader failure).
int benchScene(const File& file, const FieldQuery& cpu, float groundY, const SceneBenchOptions& o);

}  // namespace vff::gpubench
