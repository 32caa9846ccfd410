// vdb.h - the OpenVDB side of vff-convert (vdb.cpp, the only unit of the tool that includes OpenVDB):
// a field's packed slices as a sparse grid and back.
//
// Layout of the .vdb (see README.md, "The OpenVDB file"): the packed slices of the field's own layout
// (spec/format.md section 10, the same images as the EXR export, gutters included) stacked along z:
// texel (x, y) of slice s is voxel (x, y, s), index space = world space (voxel size 1).
//   grid "distance"  FloatGrid, class unknown: the decoded distance in object units at every hit
//                    (active voxel); misses and unused tiles are inactive background (+infinity, as
//                    the EXR's Y: "no surface at any distance"). bit1 hits hold 0.
//   grid "normal"    (with a normal field) Vec3fGrid, vector type invariant: the object-space unit
//                    normal at every hit (active), background 0 0 0.
// Grid metadata: "vff.plane" (string, "distance" / "normal") on both; on "distance" also the string
// "vff.field" (JSON {"format":"vff-convert-vdb/1", "field", "layout", "metadata", "codec",
// "mapsPerBlock"}, the members of the EXR export's attribute) and the string "vff.provenance" (JSON
// array: the source META's "vff.provenance" entries followed by this export's entry).
#pragma once

#include <cstdint>
#include <string>

#include "convert.h"

namespace vff::convert {

struct VdbWriteOptions {
  std::string sourceName;   // the input's file name (no folders), for the provenance entry
  uint64_t sourceXxh3 = 0;  // XXH3-64 of the input file's bytes
  std::string sourceFormat = "vff";  // "vff" or "exr"
};

struct VdbWriteReport {
  uint64_t activeVoxels = 0;  // of the distance grid: the hit texels of the slices (gutters included)
};

// Writes `data` as a .vdb (layout above) through a temporary file in the same folder and a rename.
// OpenVDB puts a random UUID in every file header; it is replaced by one derived from the file's
// other bytes, so the same field gives the same bytes. Errors: kIoWrite naming the file,
// kMetadataJson when the META is not a JSON object or its "vff.provenance" is not an array,
// kOutOfMemory.
Status writeVdb(const std::string& path, const FieldData& data, const VdbWriteOptions& options,
                VdbWriteReport* report = nullptr);

struct VdbReadReport {
  uint64_t activeVoxels = 0;    // of the distance grid
  uint64_t inexactTexels = 0;   // hits whose value is not what the exporter writes for any code
  uint64_t inexactNormals = 0;  // normals that are not a decoded oct-snorm16 normal
};

// Reads a .vdb written by writeVdb back into raw planes: each active voxel's distance is encoded
// again with encodeDistance (exact for every encoding: the exporter writes binary32 decoded values),
// each normal with encodeNormal (exact, seam duplicates included); `report` counts values that were
// not exact. Errors: kIoOpen; kBadMagic for a file that is not a .vdb; kSectionDecode for one that
// OpenVDB cannot read (corrupt, truncated);
// kMissingSection when no grid carries "vff.field"; kMetadataJson or the libvff rule for a bad
// "vff.field"; kLayoutGeometry when a grid is missing, of the wrong type, or has active voxels
// outside the slices; kDecodedLimit above 8 GiB of maps.
Result<FieldData> readVdb(const std::string& path, VdbReadReport* report);

// True when the file starts with OpenVDB's magic number.
bool looksLikeVdb(const std::string& path);

}  // namespace vff::convert
