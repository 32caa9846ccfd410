// vk_bench.h - vff-gpu-bench --api vulkan: the field's queries/s through the Vulkan pipeline
// (gpu/vulkan, vff::vk::QueryPipeline: the same vff_query.glsl compiled to SPIR-V), on the same
// random rays as the GL table, beside it.
#pragma once

#include <functional>
#include <vector>

#include "vff/vff.h"

namespace vff::harness {

// Makes n random rays with a seed (main.cpp's makeRandomRays: the GL table's rays).
using RayMaker = std::function<void(size_t n, uint64_t seed, std::vector<Ray>* rays)>;

// Prints the Vulkan device and a table of rays/s (2^20 and 2^21 rays, kNearest occluded and
// kInterpolated visibility; the wall time of the submissions, in parts that fit the device's
// maxStorageBufferRange, best of 2) with the count of answers
// that differ from the CPU's by more than 1e-4. `hlsl`: the kernel built from the generated HLSL
// (vff::vk::ShaderLanguage::kHlsl) instead of the GLSL's. Returns an exit code (4 without a Vulkan
// device, or with hlsl where the build has no HLSL kernels).
int benchVulkanQueries(const File& file, const FieldQuery& cpu, const RayMaker& makeRays, bool hlsl = false);

}  // namespace vff::harness
