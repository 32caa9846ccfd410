// vff/error.h - errors as values.
//
// Every fallible libvff call returns a vff::Result<T> (or vff::Status, a Result<void>). No exception
// crosses the library API. An Error carries:
//   - code:    a stable numeric identifier (vff::Code). File problems use the validation IDs of the
//              format specification (spec/validation.md), grouped by thousands:
//              1xxx I/O, 2xxx identity, 3xxx header, 4xxx section table, 5xxx field description,
//              6xxx planes and blocks, 7xxx packed layout, 8xxx metadata, 9xxx API usage,
//              10xxx mesh input (baking), 11xxx scene descriptions (spec/scene.md).
//   - section: the FourCC of the section concerned (0 when none), see sectionTagName().
//   - offset:  the absolute byte offset in the file where the problem was found (kNoOffset if none).
//   - message: one human-readable sentence without a trailing newline.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <variant>

#include "vff/export.h"

namespace vff {

enum class Code : uint32_t {
  kOk = 0,
  // 1xxx: input/output
  kIoOpen = 1001,         // the file cannot be opened
  kIoRead = 1002,         // reading or mapping failed
  kIoWrite = 1003,        // writing, syncing or renaming failed
  // 2xxx: file identity
  kTooSmall = 2001,                // shorter than the 64-byte header
  kBadMagic = 2002,                // not a .vff file
  kUnsupportedVersion = 2003,      // versionMajor is not 1
  kUnknownIncompatFeature = 2004,  // incompatFeatures has a bit this reader does not implement
  // 3xxx: header
  kHeaderSize = 3001,          // headerSize is not 64
  kFileSizeMismatch = 3002,    // fileSize differs from the actual size (truncated or appended)
  kHeaderReserved = 3003,      // a reserved header field is not zero
  kChecksumAlgorithm = 3004,   // unknown checksumAlgorithm
  kHeaderChecksum = 3005,      // headerChecksum does not match
  kSectionTable = 3006,        // section table offset, entry size or extent is invalid
  kSectionCount = 3007,        // sectionCount is zero or above the reader's limit
  kRoCompatFeature = 3008,     // roCompatFeatures has an unknown bit (warning: read-only use)
  // 4xxx: section table and sections
  kSectionBounds = 4001,       // a section lies (partly) outside the file
  kSectionAlignment = 4002,    // a section offset is not a multiple of 4096
  kSectionOrder = 4003,        // sections overlap or are not in increasing offset order
  kUnknownRequired = 4004,     // a section marked REQUIRED has a tag this reader does not know
  kDuplicateSection = 4005,    // a section tag appears twice
  kMissingSection = 4006,      // a required section (FDSC, LAYT, DIST) is absent
  kSectionCodec = 4007,        // unknown section codec, or a codec not allowed for this section
  kSectionChecksum = 4008,     // the section checksum does not match its stored bytes
  kSectionReserved = 4009,     // a reserved section-entry field or flag bit is not zero
  kSectionSize = 4010,         // storedSize/rawSize inconsistent or wrong for the section type
  kSectionDecode = 4011,       // a compressed section does not decode to rawSize bytes
  kPadding = 4012,             // a padding byte between structures is not zero
  kSectionVersion = 4013,      // unsupported sectionVersion for a known section
  kSectionLimit = 4014,        // a section is larger than the reader's limit
  // 5xxx: field description (FDSC)
  kSphere = 5001,              // centre or radius is not finite, or radius <= 0
  kPositionScheme = 5002,      // unknown positional-sample scheme or invalid parameter
  kMapCount = 5003,            // mapCount does not match the scheme, or exceeds a limit
  kDirectionScheme = 5004,     // unknown direction scheme
  kMapResolution = 5005,       // mapResolution is 0, too large, or not allowed for the encoding
  kFrameConvention = 5006,     // unknown tangent-frame convention
  kDistanceEncoding = 5007,    // unknown distance encoding
  kMissCode = 5008,            // missCode differs from the encoding's reserved miss code
  kNormalEncoding = 5009,      // unknown normal encoding
  kFieldReserved = 5010,       // a reserved FDSC field is not zero
  kDecodedLimit = 5011,        // the declared payload exceeds the reader's byte limit
  // 6xxx: planes (DIST, NORM) and blocks
  kPlaneHeader = 6001,         // plane header inconsistent with FDSC (mapCount, mapBytes, blockCount)
  kPlanePresence = 6002,       // NORM present without a normal encoding, or absent with one
  kBlockBounds = 6003,         // a block lies outside its section
  kBlockAlignment = 6004,      // a block offset is not a multiple of 64
  kBlockOrder = 6005,          // blocks overlap, are out of order, or leave gaps
  kBlockRawSize = 6006,        // rawSize differs from (maps in block) x mapBytes
  kBlockCodec = 6007,          // unknown block codec, or stored block with storedSize != rawSize
  kBlockFilter = 6008,         // unknown block filter
  kBlockChecksum = 6009,       // block checksum does not match its stored bytes
  kBlockDecode = 6010,         // a compressed block does not decode to exactly rawSize bytes
  kBlockReserved = 6011,       // a reserved block-entry field is not zero
  kFeatureBit = 6012,          // a codec is used without its incompatFeatures bit
  kValueRange = 6013,          // a stored value is outside the encoding's range
  // 7xxx: packed slice layout (LAYT)
  kLayoutTarget = 7001,        // unknown texture target
  kLayoutTile = 7002,          // tile size, gutter or encoding constraints violated
  kLayoutGeometry = 7003,      // tiles per row/column, slice size or slice count inconsistent
  kLayoutReserved = 7004,      // a reserved LAYT field is not zero
  // 8xxx: metadata (META)
  kMetadataJson = 8001,        // not valid UTF-8 JSON
  kMetadataNotObject = 8002,   // the JSON value is not an object
  kRefineHeader = 8501,        // REFN: header size, counts, margin, reserved bytes or total size wrong
  kRefineUnsure = 8502,        // REFN: unsureTexels is not the number of bits set, or padding is not zero
  kRefineMesh = 8503,          // REFN: a vertex index out of range, or a position not finite or outside the sphere
  // 10xxx: mesh input (the baker's front end)
  kMeshFormat = 10001,         // unknown mesh file extension
  kMeshParse = 10002,          // the mesh file cannot be parsed
  kMeshUnsupported = 10003,    // content the importer cannot bake (non-triangle primitives, compression)
  kMeshEmpty = 10004,          // no triangles
  kMeshNonFinite = 10005,      // a vertex coordinate is NaN or infinite
  kMeshDegenerate = 10006,     // every triangle has zero area
  kMeshIndex = 10007,          // an index or accessor points outside its data
  // 11xxx: scene descriptions (spec/scene.md)
  kSceneJson = 11001,          // not one JSON object
  kSceneVersion = 11002,       // not a vff-scene, or a version this reader does not implement
  kSceneValue = 11003,         // a member is missing or has a value the spec does not allow
  kSceneUri = 11004,           // a field's uri is not a file reference the spec allows
  kSceneFieldIndex = 11005,    // an instance's field index is not one of the fields
  // 9xxx: API usage and resources (not file problems)
  kInvalidArgument = 9001,     // a caller-supplied argument is invalid
  kOutOfRange = 9002,          // an index is out of range
  kBadState = 9003,            // the call is not allowed in the object's current state
  kOutOfMemory = 9004,         // an allocation failed
  kUnsupported = 9005,         // the operation is not supported for this field
};

// Stable kebab-case name of a code ("header-checksum"); "unknown" for values not listed above.
VFF_API const char* codeName(Code code) noexcept;

// A FourCC section tag as four printable characters ("DIST"); non-printable bytes become '?'.
VFF_API std::string sectionTagName(uint32_t tag);

inline constexpr uint64_t kNoOffset = ~uint64_t{0};

struct VFF_API Error {
  Code code = Code::kOk;
  uint32_t section = 0;          // FourCC, 0 when not tied to a section
  uint64_t offset = kNoOffset;   // absolute file offset, kNoOffset when not tied to a place
  std::string message;

  // "@0x40 [DIST] header-checksum (3005): message" - the place, the code and the message.
  std::string toString() const;
};

// Either a value or an Error. Check ok() before value(); value() on an error is a caller bug.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}  // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  bool ok() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &std::get<0>(v_); }
  const T* operator->() const { return &std::get<0>(v_); }
  T& operator*() & { return std::get<0>(v_); }
  const Error& error() const& { return std::get<1>(v_); }
  Error&& error() && { return std::get<1>(std::move(v_)); }

 private:
  std::variant<T, Error> v_;
};

template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : error_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  bool ok() const noexcept { return error_.code == Code::kOk; }
  explicit operator bool() const noexcept { return ok(); }
  const Error& error() const& { return error_; }
  Error&& error() && { return std::move(error_); }

 private:
  Error error_;
};

using Status = Result<void>;

// Builds an Error; used by the library and handy for callers that wrap libvff.
VFF_API Error makeError(Code code, std::string message, uint32_t section = 0, uint64_t offset = kNoOffset);

}  // namespace vff
