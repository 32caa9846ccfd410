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

struct Report {
  PlaneReport planes[2];
  uint64_t fileBytes = 0;
  double seconds = 0;
};

// Re-writes `in` to `out` with `options` (codec, level, filter, G; the layout limits and metadata
// are taken from `in`), streaming one source block at a time so memory stays at a few blocks.
// Then reads `out` back and fills `report`.
Status rewrite(const File& in, const std::string& out, const WriteOptions& options, Report* report);

// The benchmark: for each field file, the distance payload through our lossless codec, zstd -19 and
// xz -9 on the raw payload, and OpenEXR ZIP, PIZ and DWAA on the EXR export; prints the table.
// With `candidates`, also the sizes of the other filters hits-med was chosen over. Returns a cli
// exit code.
int benchmark(const std::vector<std::string>& files, int repeat, const std::string& tmpDir, bool candidates);

}  // namespace vff::compress
