// scene_bench.h - vff-gpu-bench's scene mode (--scene N): the ground AO under N instances of the
// field, rendered through gpu/glsl/vff_scene.glsl (vff::gl::GpuScene) and with the CPU vff::Scene
// on the same rays in the same run, plus the per-frame cost of moving every instance (Scene::commit
// and GpuScene::update).
#pragma once

#include <string>
#include <vector>

#include "ao_scene.h"
#include "vff/vff.h"

namespace vff::harness {

struct SceneBenchOptions {
  int instances = 16;
  int size = 512, spp = 256;
  unsigned threads = 1;
  float aoDistance = 2.0f;  // AO range, multiples of the field's R
};

// Prints the scene's table; returns an exit code (0, or 4 for a GL or shader failure).
int benchScene(const File& file, const FieldQuery& cpu, float groundY, const SceneBenchOptions& o);

}  // namespace vff::harness
