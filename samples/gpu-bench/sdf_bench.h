// sdf_bench.h - vff-gpu-bench's distance-field mode (--sdf): the ground AO of ao_scene.h rendered by
// the field's GLSL (vff_query.glsl, kNearest and kInterpolated) and by the distance-field peer's
// GLSL (vff_sdf.glsl: sphere tracing of an SdfField's NanoVDB grid; hit or miss, and the cone
// estimate with vff-experiments ao's options) at equal memory, each against
// the exact image (Embree casts of the mesh on the same rays), with the CPU's time for the same
// image by the same method (FieldQuery, SdfField, Embree) as the baseline, in one table.
//
// Memory: the distance field is built (SdfField::build) with the field's payload bytes
// (FieldQuery::payloadBytes: its distance maps as stored) as its budget, which counts an engine's
// brick layout of the grid (sdf_field.h: 8^3 leaves of the band plus a 4-byte indirection entry
// per block); the table also gives what each GPU path holds: the field's texture bytes and the
// NanoVDB buffer (its tree's internal nodes on top of the same leaves).
#pragma once

#include "ao_scene.h"
#include "vff/bake/mesh.h"
#include "vff/gl/loader.h"
#include "vff/vff.h"

namespace vff::harness {

struct SdfBenchOptions {
  int size = 512, spp = 256;
  unsigned threads = 1;
  float bandVoxels = 8.0f;  // vffx::SdfBuildOptions::bandVoxels
  float aoDistance = 2.0f;  // AO range, multiples of R
};

// `gpu` is the field's upload (vff::gl::GpuField), `fieldProgram` the field's AO program (kAoShader
// after vff_query.glsl), `mesh` the object the field was baked from (object space). Prints the
// table; returns an exit code (0, or 4 for a build, GL or shader failure).
int benchSdf(const File& file, const FieldQuery& cpu, const bake::Mesh& mesh, float groundY,
             const gl::GpuField& gpuField, unsigned fieldProgram, const SdfBenchOptions& o);

}  // namespace vff::harness
