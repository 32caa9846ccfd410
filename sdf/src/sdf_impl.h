// sdf_impl.h - SdfField's state, shared by its builder (sdf_build.cpp, the only unit that includes
// OpenVDB) and its tracer (sdf_field.cpp, NanoVDB only). Private to vff-experiments.
#pragma once

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/HostBuffer.h>

#include "vff/sdf/sdf_field.h"

namespace vffx {

struct SdfField::Impl {
  nanovdb::GridHandle<nanovdb::HostBuffer> handle;
  SdfValues values = SdfValues::kFp8;
  float voxel = 0;               // object units
  float band = 0;                // half-width of the band, voxels
  uint32_t dims[3] = {0, 0, 0};  // of the active index box
  uint64_t bricks = 0;  // what the budget counts
  uint64_t dense = 0;
  int builds = 0;
  double seconds = 0;
};

}  // namespace vffx
