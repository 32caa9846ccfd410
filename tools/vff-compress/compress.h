// compress.h - what vff-compress's parts share: re-writing a field block by block with new codec
// options, and the benchmark.
#pragma once

#include <string>
#include <vector>

#include "vff/vff.h"

namespace vff::compress {

// What one rewrite did, per plane, for the report.
struct PlaneReport {
  bool present = false;
  uint64_t rawBytes = 0;
  uint64_t storedBytes = 0;
  std::vector<uint64_t> blockStored;  // stored bytes of each block
  uint32_t filtered = 0;              // blocks with a filter
  uint32_t zstd = 0;                  // blocks with codec zstd
};

// --bc4: what re-encoding the distance plane as bc4-diameter changed, over every hit texel, in codes
// (steps of 2R / 254). Misses and hits are kept exactly (the encoder's guarantee, checked here).
struct Bc4Report {
  bool done = false;
  uint64_t hits = 0;
  uint64_t changed = 0;     // hits whose code changed
  uint32_t maxError = 0;    // largest |new code - old code|
  double sumSquared = 0;    // sum of (new - old)^2, for the RMS
};

// The input's refinement (REFN, vff/refine.h), if it has one: copied where the maps are kept as
// they decode, remade from its own triangles and margin where --bc4 changed them (the unsure texels
// are those of the new maps).
struct RefinementReport {
  bool present = false;
  bool remade = false;
  uint32_t unsureBefore = 0;
  uint32_t unsureAfter = 0;
};

struct Report {
  PlaneReport planes[2];
  Bc4Report bc4;
  RefinementReport refinement;
  uint64_t fileBytes = 0;
  double seconds = 0;
};

// Re-writes `in` to `out` with `options` (codec, level, filter, G; the layout limits and metadata
// are taken from `in`), streaming one source block at a time so memory stays at a few blocks.
// With `bc4`, the distance plane of an unorm8-diameter field is re-encoded as bc4-diameter (the
// field, its layout (2d-array, no gutter) and `options` must already say so). Then reads `out`
// back and fills `report`. A refinement is kept (see RefinementReport).
Status rewrite(const File& in, const std::string& out, const FieldDesc& field, const WriteOptions& options,
               bool bc4, Report* report);

// The benchmark: for each field file, the distance payload through our lossless codec, zstd -19 and
// xz -9 on the raw payload, and OpenEXR ZIP, PIZ and DWAA on the EXR export; prints the table.
// With `candidates`, also the sizes of the other filters hits-med was chosen over. Returns a cli
// exit code.
int benchmark(const std::vector<std::string>& files, int repeat, const std::string& tmpDir, bool candidates);

}  // namespace vff::compress
