// partial_rules.h - the numbered rules of partial results and their merge (spec/partial.md section
// 3.2): one ID, name and exit code each, in the order vff-bake --merge checks them. A refusal prints
// "PART: NAME (ID): message"; the IDs never change meaning and are never reused.
#pragma once

#include <cstdint>
#include <string>

#include "cli.h"

namespace vff::bake_tool {

enum class PartialRule : uint16_t {
  kOutputIsPart = 12001,   // merge-output-is-part: -o is none of the parts (usage)
  kNotPartial = 12002,     // partial-missing: META is an object with "vff.partial"
  kNotObject = 12003,      // partial-object: "vff.partial" is an object with an integer "version"
  kVersion = 12004,        // partial-version: "version" is 1
  kKeyMissing = 12005,     // partial-key-missing: every key of section 2 is there
  kKeyType = 12006,        // partial-key-type: every value has its type and range
  kKeyUnknown = 12007,     // partial-key-unknown: no key beyond section 2's
  kMapCount = 12008,       // partial-map-count: "mapCount" is FDSC's mapCount
  kRange = 12009,          // partial-range: mapBegin < mapEnd <= mapCount
  kCodec = 12010,          // partial-codec: "codec" is "stored" or "zstd"
  kZstdLevel = 12011,      // partial-zstd-level: zstdLevel >= 1 when codec is "zstd"
  kFiller = 12012,         // partial-filler: every map outside the range is a filler
  kGeometry = 12013,       // merge-geometry: the first part's vff.source.geometryHash
  kVersionOfBake = 12014,  // merge-version: the first part's vff.generatorVersion
  kFieldOptions = 12015,   // merge-options: the first part's FDSC and LAYT limits
  kBlockOptions = 12016,   // merge-block-options: the first part's codec, zstdLevel, mapsPerBlock
  kMeta = 12017,           // merge-meta: the first part's META without "vff.partial"
  kGap = 12018,            // merge-gap: the sorted ranges leave no map out
  kOverlap = 12019,        // merge-overlap: no map is in two parts
};

struct PartialRuleInfo {
  PartialRule rule;
  const char* name;
  int exitCode;
};

// Every rule in check order (spec/partial.md section 3.2's table).
inline constexpr PartialRuleInfo kPartialRules[] = {
    {PartialRule::kOutputIsPart, "merge-output-is-part", cli::kExitUsage},
    {PartialRule::kNotPartial, "partial-missing", cli::kExitInvalidFile},
    {PartialRule::kNotObject, "partial-object", cli::kExitInvalidFile},
    {PartialRule::kVersion, "partial-version", cli::kExitUnsupported},
    {PartialRule::kKeyMissing, "partial-key-missing", cli::kExitInvalidFile},
    {PartialRule::kKeyType, "partial-key-type", cli::kExitInvalidFile},
    {PartialRule::kKeyUnknown, "partial-key-unknown", cli::kExitInvalidFile},
    {PartialRule::kMapCount, "partial-map-count", cli::kExitInvalidFile},
    {PartialRule::kRange, "partial-range", cli::kExitInvalidFile},
    {PartialRule::kCodec, "partial-codec", cli::kExitUnsupported},
    {PartialRule::kZstdLevel, "partial-zstd-level", cli::kExitInvalidFile},
    {PartialRule::kFiller, "partial-filler", cli::kExitInvalidFile},
    {PartialRule::kGeometry, "merge-geometry", cli::kExitInvalidFile},
    {PartialRule::kVersionOfBake, "merge-version", cli::kExitInvalidFile},
    {PartialRule::kFieldOptions, "merge-options", cli::kExitInvalidFile},
    {PartialRule::kBlockOptions, "merge-block-options", cli::kExitInvalidFile},
    {PartialRule::kMeta, "merge-meta", cli::kExitInvalidFile},
    {PartialRule::kGap, "merge-gap", cli::kExitInvalidFile},
    {PartialRule::kOverlap, "merge-overlap", cli::kExitInvalidFile},
};

constexpr const PartialRuleInfo& partialRuleInfo(PartialRule r) {
  for (const PartialRuleInfo& i : kPartialRules)
    if (i.rule == r) return i;
  return kPartialRules[0];  // unreachable: every enumerator has its row
}

// "NAME (ID)", as a refusal prints the rule.
inline std::string partialRuleTag(PartialRule r) {
  return std::string(partialRuleInfo(r).name) + " (" + std::to_string(int(r)) + ")";
}

}  // namespace vff::bake_tool
