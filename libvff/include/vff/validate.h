// vff/validate.h - the validator: every problem in a file, each with its stable ID.
//
// validate() checks everything File::open checks, and more, but does not stop at the first
// problem: it reports every one it can find, each with the spec's numeric ID (the vff::Code), the
// section and the byte offset. It also decodes every block, checks every checksum and every
// padding byte. The command-line `vff-inspect --validate` and the fuzz targets call it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/reader.h"

namespace vff {

enum class Severity : uint8_t { kWarning = 0, kError = 1 };
VFF_API const char* severityName(Severity s) noexcept;  // "warning", "error"

struct Issue {
  Code code = Code::kOk;
  Severity severity = Severity::kError;
  uint32_t section = 0;
  uint64_t offset = kNoOffset;
  std::string message;
};

struct ValidateOptions {
  ReadOptions limits;       // its checksum policy is ignored: the validator checks everything
  bool decodeBlocks = true;  // decode every compressed block and check every value
};

struct VFF_API Report {
  std::vector<Issue> issues;
  bool valid() const noexcept;        // no issue of severity kError
  bool has(Code code) const noexcept;  // some issue carries this code
};

VFF_API Report validate(std::span<const uint8_t> bytes, const ValidateOptions& options = {});
VFF_API Report validateFile(const std::string& path, const ValidateOptions& options = {});

}  // namespace vff
