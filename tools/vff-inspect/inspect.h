// inspect.h - the parts of vff-inspect: statistics over the distance plane, the report as one JSON
// document (spec/inspect-schema.json), its text rendering, and the contact-sheet preview.
//
// The JSON document is the single model of the report: the text output is rendered from it, so
// the two always say the same thing.
#pragma once

#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vff/reader.h"
#include "vff/validate.h"

namespace vff::inspect {

inline constexpr const char* kProg = "vff-inspect";

// ---- Statistics over every distance map ---------------------------------------------------------
struct DistanceStats {
  uint64_t texels = 0;  // texels of the blocks that could be read
  uint64_t hits = 0;
  uint64_t misses = 0;
  // Hit distances in `bins` equal bins over [0, 2R] (bin i: [i, i+1) * 2R / bins, the last one
  // closed). Empty for kBit1, which stores no distance.
  std::vector<uint64_t> bins;
  uint32_t unreadableBlocks = 0;  // blocks skipped because they failed to decode (skipBadBlocks)
};

// The maps a report counts, [begin, end): all of them, or a partial result's range.
struct MapSpan {
  uint32_t begin = 0;
  uint32_t end = UINT32_MAX;
};

// Reads every block of the distance plane that holds a map of `maps` once (zero-copy for stored
// blocks, one reusable buffer for compressed ones) and counts those maps only. `bins` >= 1. With
// skipBadBlocks, a block that cannot be read is counted in unreadableBlocks instead of failing the
// call (used with --validate, which reports the problem).
Result<DistanceStats> distanceStats(const File& file, uint32_t bins, bool skipBadBlocks, MapSpan maps = {});

// A partial result (spec/partial.md: META has "vff.partial"): its range when "vff.partial" is an
// object whose mapBegin, mapEnd and mapCount are integers with mapBegin < mapEnd <= mapCount = FDSC
// mapCount, else a span of the whole field with `known` false. Nothing for a file that is not one.
struct PartialInfo {
  MapSpan range;
  bool known = false;
};
std::optional<PartialInfo> partialInfo(const File& file);

// ---- The report ---------------------------------------------------------------------------------
enum class ChecksumStatus { kVerified, kFailed, kNotVerified };

// How the file's checksums were checked: all verified at open (ChecksumPolicy::kVerifyAll), or
// taken from a validation report (the file then is opened without checksum checks).
struct ChecksumState {
  ChecksumStatus header = ChecksumStatus::kNotVerified;
  std::vector<ChecksumStatus> sections;  // one per FileInfo::sections entry
};
ChecksumState checksumsVerifiedAtOpen(const File& file);
ChecksumState checksumsFromReport(const File& file, const Report& report);

// The summary of an opened file: "format", "sections", "field", "planes", "layout", "partial",
// "statistics", "histogram", "metadata" (see spec/inspect-schema.json). `partial`: partialInfo(file),
// whose range `stats` counted.
nlohmann::json summarize(const File& file, const ChecksumState& checksums, const DistanceStats& stats,
                         uint32_t histogramBins, const std::optional<PartialInfo>& partial);

// {"valid": bool, "errors": n, "warnings": n, "issues": [...]} for a validation report.
nlohmann::json validationJson(const Report& report);

// Renders a report document (summary keys and/or "validation", "preview") as text.
void printText(const nlohmann::json& doc, std::FILE* out);

// ---- Preview ------------------------------------------------------------------------------------
// The contact sheet of the first `maps` maps: a grid of `columns` x `rows` tiles of M x M pixels
// with 1-pixel separators between tiles and around the sheet, so
// width = columns * (M + 1) + 1 and height = rows * (M + 1) + 1, columns = ceil(sqrt(maps)),
// rows = ceil(maps / columns). Hits are grey (near = bright), misses dark blue, separators black.
struct PreviewGeometry {
  uint32_t maps = 0;
  uint32_t columns = 0;
  uint32_t rows = 0;
  uint64_t width = 0;
  uint64_t height = 0;
};
PreviewGeometry previewGeometry(uint32_t mapResolution, uint32_t maps);

// Largest preview we write, in pixels (3 bytes each).
inline constexpr uint64_t kMaxPreviewPixels = uint64_t{1} << 26;

// Renders the first min(maps, mapCount) maps and writes a PNG to `path` atomically.
// Errors: kIoWrite (nothing is left at `path`), a map read error, kInvalidArgument (too large).
Result<PreviewGeometry> writePreview(const File& file, const std::string& path, uint32_t maps);

// ---- glTF assets (gltf.cpp) -----------------------------------------------------------------------
// A glTF input: cli::isGltfInput.

struct GltfInspectOptions {
  bool json = false;         // --format json
  uint32_t histogramBins = 16;
  std::string extractDir;    // --extract: write each valid field's payload there instead of the report
};

// vff-inspect on a glTF asset: the report of its VFF_visibility_field fields (each payload's summary
// as for a .vff file) and every problem of the extension's rules, or with extractDir the payloads
// written to DIR/STEM.meshI.vff (atomically, their bytes unchanged), one path per line. Returns the
// exit code: 3 for an error problem (2 when every error is a uri file that cannot be read), 5 in a
// build without the baker.
int inspectGltf(const std::string& path, const GltfInspectOptions& options);

}  // namespace vff::inspect
