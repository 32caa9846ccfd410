// sdf_ao.h - the ground AO of ao_scene.h traced through the distance-field peer: the CPU side
// (SdfField's batch, for harness::cpuAo) and the compute shader's text (vff_sdf.glsl in place of
// the field's queries). Shared by vff-gpu-bench --sdf and tests/gpu/test_gpu_sdf.cpp.
//
// kAoShader's nearest path (aoInterpolated 0) answers hit or miss (vffSdfOccluded: the mean of
// 1 - occluded, as the field's kNearest row); its interpolated path (1) calls vffSdfVisibility, the
// cone estimate when the uploaded block asks for one (SdfField::visibility on the CPU: the
// experiments' counterpart of the field's kInterpolated row, ao.cpp).
#pragma once

#include <span>
#include <string>

#include "ao_scene.h"
#include "vff/sdf/sdf_field.h"
#include "sdf_gl.h"

namespace vff::harness {

// The query cpuAo calls: SdfField's batch visibility with the given trace options.
struct SdfAoQuery {
  const vffx::SdfField* sdf = nullptr;
  vffx::SdfTraceOptions options;
  bool visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions&) const {
    sdf->visibility(rays, out, options);
    return true;
  }
};

// The whole compute shader: "#version 430", the grid's defines, vff_query.glsl (for vffFrame; its
// field resources are declared but unused), vff_sdf.glsl with PNanoVDB pasted in, kAoShader with
// its queries as sphere tracing.
inline std::string sdfAoShaderSource(const vffx::SdfField& sdf, const std::string& queryGlsl,
                                     const std::string& sdfGlsl) {
  return "#version 430\n" + vffx::gl::sdfShaderDefines(sdf) + queryGlsl + "\n" + vffx::gl::sdfShaderSource(sdfGlsl) +
         "\n#define AO_OCCLUDED(o, d) vffSdfOccluded(o, d, 0.0, aoTmax)\n"
         "#define AO_VISIBILITY(o, d) vffSdfVisibility(o, d, 0.0, aoTmax)\n" +
         kAoShader;
}

}  // namespace vff::harness
