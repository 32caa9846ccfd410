// vff/bake/levelset.h - baking a visibility field from an OpenVDB narrow-band level set (.vdb).
//
// The input is a FloatGrid of class "level set": signed distances in world units, negative inside,
// stored in a narrow band of active voxels (as written by OpenVDB's meshToLevelSet,
// createLevelSetSphere, Houdini, Blender ...). The surface is the zero crossing of the grid's
// trilinear interpolation. bakeLevelSet casts exactly the rays bakeField casts (baker.h: one ray
// through each texel centre of each positional sample's inward hemisphere) and intersects each with
// that surface using openvdb::tools::LevelSetRayIntersector (a hierarchical DDA over the narrow
// band, then secant steps on the interpolated distance); the normal at a hit is the normalised
// gradient of the interpolation, taken to world space. Either side of the surface is hit (a ray that
// starts inside finds the crossing out), like the mesh baker's two-sided triangles. The output does
// not depend on the thread count.
//
// The bounding sphere (unless BakeOptions::sphere gives one) is the minimal sphere around the eight
// world-space corners of the active voxels' bounding box: the zero crossing lies inside the band,
// so inside that box.
//
//   auto ls = vff::bake::LevelSet::load("bunny.vdb");          // the first level set grid by name
//   if (!ls) { ... ls.error() ... }
//   auto field = vff::bake::bakeLevelSet(*ls, options);       // options as for bakeField
//
// Errors of load (every message names the file):
//   kIoOpen           the file is missing or unreadable
//   kMeshParse        not an OpenVDB file (wrong magic number), or a corrupt or truncated one
//   kMeshEmpty        the file holds no grid, or the chosen level set has no active voxel
//   kMeshUnsupported  no FloatGrid of class level set (only fog volumes, vector or double grids...),
//                     the grid named by LevelSetLoadOptions::grid is not one, its voxels are not
//                     cubes, its transform is not linear (frustum), or its background (the band's
//                     half width) is not a positive finite distance
//   kInvalidArgument  LevelSetLoadOptions::grid names no grid of the file (the message lists them)
// Reading .vdb files is OpenVDB's own code: it is not hardened against hostile files the way
// libvff's reader is (it checks the magic number and catches OpenVDB's exceptions, no more).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "vff/bake/baker.h"
#include "vff/error.h"
#include "vff/format.h"

namespace vff::bake {

struct LevelSetLoadOptions {
  // The grid to bake; empty: the first FloatGrid of class level set in the order OpenVDB lists the
  // file's grids (by name, as vdb_print prints them).
  std::string grid;
};

struct LevelSetInfo {
  std::string grid;           // the grid's name
  uint64_t activeVoxels = 0;  // voxels of the narrow band
  double voxelSize = 0;       // edge of a voxel in world units
  double halfWidth = 0;       // the band's half width in voxels (background / voxelSize)
  double boundsMin[3] = {0, 0, 0};  // world-space box around the active voxel centres
  double boundsMax[3] = {0, 0, 0};
  uint64_t fileXxh3 = 0;  // XXH3-64 of the file's bytes (provenance)
};

// A level set loaded from a .vdb file, ready to bake. Move-only; const methods are thread-safe.
class LevelSet {
 public:
  static Result<LevelSet> load(const std::string& path, const LevelSetLoadOptions& options = {});
  LevelSet(LevelSet&&) noexcept;
  LevelSet& operator=(LevelSet&&) noexcept;
  ~LevelSet();

  const LevelSetInfo& info() const noexcept;
  struct Impl;  // opaque (holds the OpenVDB grid)
  explicit LevelSet(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
  friend Result<BakedField> bakeLevelSet(const LevelSet&, const BakeOptions&);
};

// True when the file starts with OpenVDB's magic number (a .vdb file); false when it does not or
// cannot be read.
bool looksLikeVdb(const std::string& path);

// The field description a bake of this level set with these options produces: the sphere of the
// active voxels' bounds unless options.sphere is set, and the counts and encodings of the options.
Result<FieldDesc> describeLevelSetBake(const LevelSet& levelSet, const BakeOptions& options);

// Bakes the field from the level set (distances along each ray to the zero crossing; with
// options.normals the gradient's direction at the hit). Errors: invalid options as describeBake,
// kOutOfMemory.
Result<BakedField> bakeLevelSet(const LevelSet& levelSet, const BakeOptions& options);

}  // namespace vff::bake
