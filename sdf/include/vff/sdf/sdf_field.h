// vff/sdf/sdf_field.h - the production peer of a visibility field: a per-object signed distance field
// queried by sphere tracing, as engines do it (Unreal's mesh distance fields and distance-field
// shadows), at a memory budget chosen to equal a field's payload.
//
// Building (sdf_build.cpp). OpenVDB's meshToVolume (through meshToSignedDistanceField) makes a
// narrow-band level set of the object's triangles, `bandVoxels` voxels wide on each side of the
// surface; a flood fill gives the voxels and tiles beyond the band the sign of their side, with the
// band's width as their magnitude. Why a narrow band and not a full one: at equal memory the sparse
// band buys smaller voxels (the accuracy an engine wants at the surface), and a sphere tracer only
// needs a lower bound of the distance away from it, which the clamped value is (an engine's sparse
// distance field clamps the same way). The band's width is a trade: at equal memory a wider band
// costs resolution but lengthens the steps near the surface and lets the cone estimate see further
// (an engine's coarser mips play that part); vff-experiments --sdf-band sets it. The level set is then copied into a read-only NanoVDB grid,
// by default with 8-bit values (nanovdb::Fp8: per 8^3 leaf a minimum and a step, one byte a voxel,
// as the field stores one byte a ray), or float values.
//
// Memory. What is budgeted is an engine's sparse layout of the same voxels (Unreal's: 8^3 bricks
// and an indirection table): every 8^3 leaf of the band, 512 values (plus, for Fp8, the leaf's
// minimum and step: 8 bytes), and a 4-byte indirection entry per 8^3 block of the active box. The
// voxel size is searched for the largest grid not over the budget (a few builds: a band's bytes
// scale as the surface area over the voxel size squared). Also reported: the NanoVDB buffer that
// this implementation reads (the same leaves; its tree's internal nodes add a fixed overhead an
// engine's flat table does not have), and the dense grid of the same voxels, nx * ny * nz * the
// bytes of a value over the index box of the active voxels (a volume texture's size).
//
// Tracing (sdf_field.cpp). A ray is taken to object space (the transform, as vff::Instance does),
// clipped to the grid's box (outside it, the trace starts at the box), and stepped along by the
// trilinearly sampled distance, or over a whole block of the tree with no surface voxel when it is
// in one (the empty-space skipping of NanoVDB's own ray marcher and of an engine's sparse bricks:
// without it, a narrow band's clamped distance makes the steps a few voxels long far from the
// surface): a step is at least `minStepVoxels`, a hit is a sample below
// `hitVoxels` (both in voxels), and a ray that takes `maxSteps` steps without either is a miss (as
// a shader that runs out of steps leaves the pixel lit). The cone estimate for soft shadows and AO
// (Unreal's distance-field shadows, Quilez's penumbra) keeps the minimum over the steps of
// 0.5 + 0.5 d / (t tan(half-angle)), clamped to [0, 1]: the open share of the cone's disc at t as a
// ramp over its radius, a half where the axis grazes the surface (the form without the half, d / (t
// tan), takes a cone whose axis touches the surface for fully covered, which darkens every
// penumbra by half a cone), the trace going on inside until the disc is covered (0), or until it
// is deeper inside than the band reaches (then taken as covered: the depth is unknown there). Rays starting on the object's own surface skip
// `startVoxels` first (the engine's self-shadow bias: the distance there is off by about a voxel).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>

#include "vff/bake/mesh.h"
#include "vff/error.h"
#include "vff/query.h"

namespace vffx {

enum class SdfValues : uint8_t { kFp8, kFloat };

// The smallest budget a build accepts: a few bricks.
inline constexpr uint64_t kSdfMinBudget = 4096;

// Empty-space skipping lands a little past a block's exit, t * (1 + kSdfSkipNudge) + kSdfSkipNudge,
// so that the next sample lies outside the block. Also the GLSL tracer's (gpu/glsl/vff_sdf.glsl).
inline constexpr float kSdfSkipNudge = 1e-6f;
// The cone estimate takes a sample deeper inside than this share of the band as covered, and
// divides by the cone's radius at t, t (in voxels) no less than kSdfConeMinDistance.
inline constexpr float kSdfConeDepth = 0.9f;
inline constexpr float kSdfConeMinDistance = 1e-6f;

struct SdfBuildOptions {
  uint64_t budgetBytes = 1u << 20;  // bytes() at most; kSdfMinBudget at least
  SdfValues values = SdfValues::kFp8;
  float bandVoxels = 8.0f;  // half-width of the narrow band, each side, in voxels (see above)
};

struct SdfTraceOptions {
  float hitVoxels = 0.25f;      // a sample below this (in voxels) is a hit
  float minStepVoxels = 0.1f;   // no step is shorter
  int maxSteps = 256;           // then: a miss
  float startVoxels = 0.0f;     // skipped at the ray's start (rays leaving the object's surface)
  bool skipEmpty = true;        // step over the tree's empty blocks at once (see above)
  // The cone estimate, when one of these is positive (visibility() then returns it; intersect() and
  // occluded() do not use it): tan(half-angle) = coneTan, or coneRadiusAtEnd / (tmax * |direction|)
  // (a cone reaching a disc of that radius, world units, at tmax: a spherical light's).
  float coneTan = 0.0f;
  float coneRadiusAtEnd = 0.0f;
};

struct SdfHit {
  bool hit = false;
  float t = 0;         // in multiples of the ray's direction, like vff::QueryHit::t
  vff::Vec3 normal;    // world space, unit: the distance's gradient at the hit (intersect() only)
  int steps = 0;       // samples taken
};

class SdfField {
 public:
  // Builds the grid of the object's mesh (object space) within the budget. Errors:
  // kInvalidArgument (an empty mesh, a budget under a few bricks), kOutOfMemory, kBadState (OpenVDB
  // threw).
  static vff::Result<SdfField> build(const vff::bake::Mesh& objectMesh, const SdfBuildOptions& options);
  SdfField(SdfField&&) noexcept;
  SdfField& operator=(SdfField&&) noexcept;
  ~SdfField();

  vff::RigidTransform transform;  // object -> world, as vff::Instance's; rays below are world rays

  SdfHit intersect(const vff::Ray& ray, const SdfTraceOptions& options = {}) const;
  bool occluded(const vff::Ray& ray, const SdfTraceOptions& options = {}) const;
  // 0 or 1 (not occluded), or the cone estimate when the options ask for it.
  float visibility(const vff::Ray& ray, const SdfTraceOptions& options = {}) const;
  // Batches: one accessor for the batch, the rays on the calling thread (out.size() == rays.size()).
  void occluded(std::span<const vff::Ray> rays, std::span<uint8_t> out, const SdfTraceOptions& options = {}) const;
  void visibility(std::span<const vff::Ray> rays, std::span<float> out, const SdfTraceOptions& options = {}) const;

  uint64_t bytes() const;         // the brick layout's bytes: what the budget counts
  uint64_t nanovdbBytes() const;  // the NanoVDB buffer queried here
  uint64_t denseBytes() const;    // nx * ny * nz * bytes per value over the active index box
  float voxelSize() const;      // object units
  uint32_t dims(int axis) const;
  SdfValues values() const;
  int builds() const;           // meshToVolume runs the budget search took
  double buildSeconds() const;
  float bandVoxels() const;
  // The NanoVDB grid's bytes (one grid, object space; values(): nanovdb::Fp8 or float), as a GPU
  // tracer reads them (gpu/sdf/sdf_gl.h); valid as long as this field.
  std::span<const uint8_t> gridBuffer() const;

  struct Impl;

 private:
  SdfField() = default;
  std::unique_ptr<Impl> impl_;
};

// The distance field's options for one AO or shadow image: the cone estimate when `cone` (the SDF's
// counterpart of the field's interpolated reconstruction); a skip of two voxels at the start of rays
// leaving the object's own surface (the engine's self-shadow bias: the sampled distance is a voxel
// off there).
inline SdfTraceOptions sdfOptions(bool cone, bool fromObject, float coneTan = 0, float coneRadiusAtEnd = 0) {
  SdfTraceOptions so;
  so.startVoxels = fromObject ? 2.0f : 0.0f;
  if (cone) so.coneTan = coneTan, so.coneRadiusAtEnd = coneRadiusAtEnd;
  return so;
}
// tan of the half-angle of one of `rays` equal cones covering the hemisphere (solid angle 2 pi / rays
// each): the cone estimate of an AO image with `rays` rays a pixel.
inline float hemisphereConeTan(int rays) {
  const float c = 1.0f - 1.0f / float(std::max(rays, 1));
  return std::sqrt(std::max(0.0f, 1.0f - c * c)) / std::max(c, 1e-3f);
}

}  // namespace vffx
