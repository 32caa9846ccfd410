#include "vff/error.h"

#include <cstdio>

namespace vff {

const char* codeName(Code code) noexcept {
  switch (code) {
    case Code::kOk: return "ok";
    case Code::kIoOpen: return "io-open";
    case Code::kIoRead: return "io-read";
    case Code::kIoWrite: return "io-write";
    case Code::kTooSmall: return "too-small";
    case Code::kBadMagic: return "bad-magic";
    case Code::kUnsupportedVersion: return "unsupported-version";
    case Code::kUnknownIncompatFeature: return "unknown-incompat-feature";
    case Code::kHeaderSize: return "header-size";
    case Code::kFileSizeMismatch: return "file-size-mismatch";
    case Code::kHeaderReserved: return "header-reserved";
    case Code::kChecksumAlgorithm: return "checksum-algorithm";
    case Code::kHeaderChecksum: return "header-checksum";
    case Code::kSectionTable: return "section-table";
    case Code::kSectionCount: return "section-count";
    case Code::kRoCompatFeature: return "ro-compat-feature";
    case Code::kSectionBounds: return "section-bounds";
    case Code::kSectionAlignment: return "section-alignment";
    case Code::kSectionOrder: return "section-order";
    case Code::kUnknownRequired: return "unknown-required-section";
    case Code::kDuplicateSection: return "duplicate-section";
    case Code::kMissingSection: return "missing-section";
    case Code::kSectionCodec: return "section-codec";
    case Code::kSectionChecksum: return "section-checksum";
    case Code::kSectionReserved: return "section-reserved";
    case Code::kSectionSize: return "section-size";
    case Code::kSectionDecode: return "section-decode";
    case Code::kPadding: return "padding";
    case Code::kSectionVersion: return "section-version";
    case Code::kSectionLimit: return "section-limit";
    case Code::kSphere: return "sphere";
    case Code::kPositionScheme: return "position-scheme";
    case Code::kMapCount: return "map-count";
    case Code::kDirectionScheme: return "direction-scheme";
    case Code::kMapResolution: return "map-resolution";
    case Code::kFrameConvention: return "frame-convention";
    case Code::kDistanceEncoding: return "distance-encoding";
    case Code::kMissCode: return "miss-code";
    case Code::kNormalEncoding: return "normal-encoding";
    case Code::kFieldReserved: return "field-reserved";
    case Code::kDecodedLimit: return "decoded-limit";
    case Code::kPlaneHeader: return "plane-header";
    case Code::kPlanePresence: return "plane-presence";
    case Code::kBlockBounds: return "block-bounds";
    case Code::kBlockAlignment: return "block-alignment";
    case Code::kBlockOrder: return "block-order";
    case Code::kBlockRawSize: return "block-raw-size";
    case Code::kBlockCodec: return "block-codec";
    case Code::kBlockFilter: return "block-filter";
    case Code::kBlockChecksum: return "block-checksum";
    case Code::kBlockDecode: return "block-decode";
    case Code::kBlockReserved: return "block-reserved";
    case Code::kFeatureBit: return "feature-bit";
    case Code::kValueRange: return "value-range";
    case Code::kLayoutTarget: return "layout-target";
    case Code::kLayoutTile: return "layout-tile";
    case Code::kLayoutGeometry: return "layout-geometry";
    case Code::kLayoutReserved: return "layout-reserved";
    case Code::kMetadataJson: return "metadata-json";
    case Code::kMetadataNotObject: return "metadata-not-object";
    case Code::kRefineHeader: return "refine-header";
    case Code::kRefineUnsure: return "refine-unsure";
    case Code::kRefineMesh: return "refine-mesh";
    case Code::kMeshFormat: return "mesh-format";
    case Code::kMeshParse: return "mesh-parse";
    case Code::kMeshUnsupported: return "mesh-unsupported";
    case Code::kMeshEmpty: return "mesh-empty";
    case Code::kMeshNonFinite: return "mesh-non-finite";
    case Code::kMeshDegenerate: return "mesh-degenerate";
    case Code::kMeshIndex: return "mesh-index";
    case Code::kSceneJson: return "scene-json";
    case Code::kSceneVersion: return "scene-version";
    case Code::kSceneValue: return "scene-value";
    case Code::kSceneUri: return "scene-uri";
    case Code::kSceneFieldIndex: return "scene-field-index";
    case Code::kInvalidArgument: return "invalid-argument";
    case Code::kOutOfRange: return "out-of-range";
    case Code::kBadState: return "bad-state";
    case Code::kOutOfMemory: return "out-of-memory";
    case Code::kUnsupported: return "unsupported";
  }
  return "unknown";
}

std::string sectionTagName(uint32_t tag) {
  std::string s(4, '?');
  for (int i = 0; i < 4; ++i) {
    auto c = char((tag >> (8 * i)) & 0xFF);
    if (c >= 0x20 && c < 0x7F) s[size_t(i)] = c;
  }
  return s;
}

std::string Error::toString() const {
  std::string s;
  if (offset != kNoOffset) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "@0x%llx ", static_cast<unsigned long long>(offset));
    s += buf;
  }
  if (section != 0) {
    s.append("[").append(sectionTagName(section)).append("] ");
  }
  s.append(codeName(code)).append(" (").append(std::to_string(unsigned(code))).append("): ").append(message);
  return s;
}

Error makeError(Code code, std::string message, uint32_t section, uint64_t offset) {
  Error e;
  e.code = code;
  e.section = section;
  e.offset = offset;
  e.message = std::move(message);
  return e;
}

}  // namespace vff
