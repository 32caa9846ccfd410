// vff-gpu-bench --api vulkan (vk_bench.h).
#include "vk_bench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>

#include "vff/vk/context.h"
#include "vff/vk/field.h"
#include "vff/vk/query.h"

namespace vff::harness {

namespace {

int fail(const Error& e) {
  std::fprintf(stderr, "vff-gpu-bench: vulkan: %s\n", e.toString().c_str());
  return 4;
}

std::vector<vk::QueryRay> toQueryRays(const std::vector<Ray>& rays) {
  std::vector<vk::QueryRay> out(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    // intraBias -1: the field's default, as the GL table's shader.
    out[i] = vk::QueryRay{{r.origin.x, r.origin.y, r.origin.z, 0},
                          {r.direction.x, r.direction.y, r.direction.z, 0},
                          {r.tmin, r.tmax, -1.0f, 0}};
  }
  return out;
}

}  // namespace

int benchVulkanQueries(const File& file, const FieldQuery& cpu, const RayMaker& makeRays, bool hlsl) {
  auto ctx = vk::Context::create();  // a GPU first where there is one; VFF_VK_VALIDATION=1 checks the run
  if (!ctx) return fail(ctx.error());
  auto gpu = vk::loadField(*ctx, file);
  if (!gpu) return fail(gpu.error());
  vk::PipelineOptions po;
  po.language = hlsl ? vk::ShaderLanguage::kHlsl : vk::ShaderLanguage::kGlsl;
  auto pipe = vk::QueryPipeline::create(*ctx, gpu->kind(), po);
  if (!pipe) return fail(pipe.error());
  std::printf(
      "\nVulkan: %s; field queries/s through vff::vk::QueryPipeline (kernel from %s) on the GL table's rays\n"
      "(wall time of the submissions: recording, dispatch and fence wait; best of 2)\n",
      ctx->deviceName().c_str(), hlsl ? "HLSL" : "GLSL");
  std::printf("| rays | query | Vulkan rays/s | answers differing from the CPU by > 1e-4 |\n|---|---|---|---|\n");
  // 2^20 and 2^21 rays: the answers take 80 bytes a ray on the host.
  for (int logN = 20; logN <= 21; ++logN) {
    const size_t n = size_t(1) << logN;
    std::vector<Ray> rays;
    makeRays(n, uint64_t(logN), &rays);
    const std::vector<vk::QueryRay> qrays = toQueryRays(rays);
    for (int interp = 0; interp < 2; ++interp) {
      vk::RunOptions ro;
      ro.nearest = interp == 0;
      ro.interpolated = interp != 0;
      // In parts that fit the device's storage buffer range (lavapipe's is smaller than the batch).
      const size_t part = std::max<size_t>(1, ctx->properties().limits.maxStorageBufferRange / sizeof(vk::QueryAnswer));
      double best = 1e30;
      std::vector<vk::QueryAnswer> answers(n);
      for (int rep = 0; rep < 2; ++rep) {
        double total = 0;
        for (size_t first = 0; first < n; first += part) {
          const size_t count = std::min(part, n - first);
          double s = 0;
          auto out = pipe->run(*ctx, *gpu, std::span<const vk::QueryRay>(qrays).subspan(first, count), ro, &s);
          if (!out) return fail(out.error());
          total += s;
          std::copy(out->begin(), out->end(), answers.begin() + std::ptrdiff_t(first));
        }
        best = std::min(best, total);
      }
      std::vector<float> cres(n);
      QueryOptions qo;
      qo.reconstruction = interp ? Reconstruction::kInterpolated : Reconstruction::kNearest;
      cpu.visibility(std::span<const Ray>(rays), std::span<float>(cres), qo);
      size_t differ = 0;
      for (size_t i = 0; i < n; ++i) {
        const float g = interp ? answers[i].visibility : ((answers[i].flags & vk::QueryAnswer::kHit) ? 0.0f : 1.0f);
        differ += std::fabs(g - cres[i]) > 1e-4f;
      }
      std::printf("| 2^%d | %s | %.3g | %zu |\n", logN, interp ? "interpolated visibility" : "nearest occluded",
                  double(n) / best, differ);
      std::fflush(stdout);
    }
  }
  if (ctx->validationEnabled() && (ctx->validationErrors() || ctx->validationWarnings())) {
    std::fprintf(stderr, "vff-gpu-bench: vulkan: validation reported:\n%s", ctx->validationLog().c_str());
    return 4;
  }
  return 0;
}

}  // namespace vff::harness
