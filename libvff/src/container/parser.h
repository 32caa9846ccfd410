// parser.h - the structural parser shared by File::open and validate() (private).
//
// It walks a file in the order of spec/validation.md and reports each problem to a sink. The reader's
// sink stops at the first error; the validator's sink collects everything. The parser itself stops
// where going on is impossible (no header, no section table, no field description).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vff/reader.h"
#include "vff/refine.h"
#include "vff/validate.h"

namespace vff::detail {

class IssueSink {
 public:
  virtual ~IssueSink() = default;
  // Returns false to stop parsing.
  virtual bool add(Code code, Severity severity, uint32_t section, uint64_t offset, std::string message) = 0;
};

struct ParseOptions {
  ReadOptions limits;
  bool verifySectionChecksums = true;  // non-plane sections
  bool verifyPlaneChecksums = true;    // plane sections and their blocks
};

struct ParsedFile {
  FileInfo info;
  FieldDesc field;
  bool fieldOk = false;
  LayoutDesc layout;
  bool layoutOk = false;
  PlaneInfo planes[2];
  std::string metadata;
  // REFN (format.md section 14), decoded, and the view into it the parse checked.
  std::vector<uint8_t> refinementRaw;
  RefinementView refinement;
  // Byte ranges [begin, end) the structures cover; what lies between must be zero padding.
  std::vector<std::pair<uint64_t, uint64_t>> covered;
};

// Parses `bytes`. Returns true when the file is usable (every error-severity issue reported is
// one the caller chose to continue past, and the field, layout and distance plane were read).
bool parseFile(std::span<const uint8_t> bytes, const ParseOptions& options, IssueSink& sink, ParsedFile* out);

// Checks, from its header and block headers alone, that `stored` is exactly one zstd frame that
// declares `rawSize` bytes and whose blocks can hold that many (raw and RLE blocks count exactly,
// compressed ones at the frame's maximum block size). A reader calls it before allocating
// `rawSize` bytes, so a frame that lies about its size costs nothing. Fails with `failCode`.
Status checkZstdFrame(std::span<const uint8_t> stored, uint64_t rawSize, Code failCode);

// Index of the block holding `map` in a plane; maps are grouped by mapsPerBlock.
inline uint32_t blockOfMap(const PlaneInfo& p, uint32_t map) noexcept { return map / p.mapsPerBlock; }

}  // namespace vff::detail
