// vff/format.h - the .vff container: constants, enumerations and the field description.
//
// The normative definition is spec/format.md; every name here is spelled as in the spec's tables.
// A .vff file holds one visibility field: for each positional sample on an object's bounding sphere,
// a square map (mapResolution x mapResolution texels) of the distance from the sphere to the surface
// along inward rays, optionally a normal field with the surface normal at each hit, a packed slice
// layout for GPU textures, and JSON metadata.
#pragma once

#include <cstdint>
#include <string>

#include "vff/error.h"
#include "vff/export.h"

namespace vff {

// ---- Versions and fixed sizes -----------------------------------------------------------------
inline constexpr uint16_t kVersionMajor = 1;
inline constexpr uint16_t kVersionMinor = 3;  // the newest minor version this library reads and writes
inline constexpr uint8_t kMagic[8] = {0x89, 'V', 'F', 'F', 0x0D, 0x0A, 0x1A, 0x0A};
inline constexpr uint32_t kHeaderSize = 64;
inline constexpr uint32_t kSectionEntrySize = 64;
inline constexpr uint64_t kSectionAlignment = 4096;  // every section starts on a 4 KiB boundary
inline constexpr uint64_t kBlockAlignment = 64;      // every block starts on a 64-byte boundary
inline constexpr uint32_t kFieldDescSize = 64;       // FDSC payload
inline constexpr uint32_t kLayoutDescSize = 64;      // LAYT payload
inline constexpr uint32_t kPlaneHeaderSize = 32;     // DIST/NORM plane header
inline constexpr uint32_t kBlockEntrySize = 32;      // DIST/NORM block entry
inline constexpr uint32_t kMaxMapResolution = 16384;  // so a map's bytes fit the u32 mapBytes field

// ---- Feature bits -----------------------------------------------------------------------------
// incompatFeatures: a reader that does not implement a set bit must reject the file.
inline constexpr uint64_t kFeatureZstd = 1u << 0;     // some block or section uses codec zstd
inline constexpr uint64_t kFeatureFilters = 1u << 1;  // some block uses a filter (format 1.1)
inline constexpr uint64_t kFeatureBc4 = 1u << 2;      // the distance encoding is bc4-diameter (format 1.2)
inline constexpr uint64_t kKnownIncompatFeatures = kFeatureZstd | kFeatureFilters | kFeatureBc4;
// roCompatFeatures: none are defined in 1.0.
inline constexpr uint64_t kKnownRoCompatFeatures = 0;

// ---- Checksums --------------------------------------------------------------------------------
enum class ChecksumAlgorithm : uint8_t { kInvalid = 0, kXxh3_64 = 1 };

// ---- Section tags (FourCC, first character in the lowest byte) ------------------------------
constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 |
         uint32_t(uint8_t(d)) << 24;
}
inline constexpr uint32_t kTagField = fourcc('F', 'D', 'S', 'C');     // field description, required
inline constexpr uint32_t kTagLayout = fourcc('L', 'A', 'Y', 'T');    // packed slice layout, required
inline constexpr uint32_t kTagDistance = fourcc('D', 'I', 'S', 'T');  // distance maps, required
inline constexpr uint32_t kTagNormal = fourcc('N', 'O', 'R', 'M');    // normal field, optional
inline constexpr uint32_t kTagMetadata = fourcc('M', 'E', 'T', 'A');  // JSON metadata, optional

// Section flags.
inline constexpr uint32_t kSectionRequired = 1u << 0;  // a reader that does not know the tag must reject
inline constexpr uint32_t kSectionCopySafe = 1u << 1;  // tools may copy an unknown section unchanged
inline constexpr uint32_t kKnownSectionFlags = kSectionRequired | kSectionCopySafe;

// ---- Codecs and filters ------------------------------------------------------------------------
enum class Codec : uint16_t { kStored = 0, kZstd = 1 };
// A filter transforms a block's raw bytes before its codec (spec/format.md section 4).
enum class Filter : uint8_t {
  kNone = 0,
  kHitsMed = 1,  // 1.1: hit mask + median-predicted hit codes; 8-bit distance planes, zstd blocks only
};
VFF_API const char* codecName(Codec codec) noexcept;    // "stored", "zstd", "unknown"
VFF_API const char* filterName(Filter filter) noexcept;  // "none", "hits-med", "unknown"

// ---- Sampling geometry -------------------------------------------------------------------------
// Positional samples on the bounding sphere (spec/geometry.md).
enum class PositionScheme : uint32_t {
  kInvalid = 0,
  kOctaHemi2 = 1,           // two octahedral hemispheres, edges split into n: 2(2n^2+2n+1) maps
  kEqualAreaOctaGrid = 2,   // equal-area octahedral grid of n x n cells: n^2 maps
  kSphericalFibonacci = 3,  // spherical Fibonacci point set: n maps
};
// Inward hemisphere of directions -> square map (spec/geometry.md).
enum class DirectionScheme : uint32_t {
  kInvalid = 0,
  kConcentricEqualArea = 1,  // Shirley-Chiu concentric square->disk, equal-area lift z = 1 - r^2
  kHemiOctahedral = 2,       // hemi-octahedral map (Cigolle et al. 2014)
};
// Tangent frame of each map around the inward normal of its sample.
enum class FrameConvention : uint32_t {
  kInvalid = 0,
  kDuff2017 = 1,  // Duff et al. 2017 branchless orthonormal basis of the inward normal
};
// How a texel of the distance plane stores the distance from the sphere entry to the first hit.
enum class DistanceEncoding : uint32_t {
  kInvalid = 0,
  kUnorm8Diameter = 1,   // u8: round(254 d / 2R), 255 = miss (the paper's encoding)
  kUnorm8Chord = 2,      // u8: round(254 d / chord), chord = 2R cos(alpha) of the texel centre; 255 = miss
  kUnorm16Diameter = 3,  // u16 LE: round(65534 d / 2R), 65535 = miss
  kBit1 = 4,             // 1 bit: 1 = hit, 0 = miss, 8 texels per byte, LSB first
  kBc4Diameter = 5,      // 1.2: unorm8-diameter codes in BC4/RGTC1 blocks of 4x4 texels (8 bytes), lossy;
                         // 255 = miss, exactly; M a multiple of 4; layout 2d-array without gutter
};
// How a texel of the normal plane stores the object-space surface normal at the hit.
enum class NormalEncoding : uint32_t {
  kNone = 0,         // no normal field
  kOctSnorm16 = 1,   // octahedral normal, two snorm16 LE (4 bytes per ray)
};

VFF_API const char* positionSchemeName(PositionScheme s) noexcept;     // "octa-hemi2", ...
VFF_API const char* directionSchemeName(DirectionScheme s) noexcept;   // "concentric-equal-area", ...
VFF_API const char* frameConventionName(FrameConvention f) noexcept;   // "duff2017"
VFF_API const char* distanceEncodingName(DistanceEncoding e) noexcept; // "unorm8-diameter", ...
VFF_API const char* normalEncodingName(NormalEncoding e) noexcept;     // "none", "oct-snorm16"

// The number of positional samples (maps) a scheme yields for its parameter; an error for an unknown
// scheme or an out-of-range parameter (octa-hemi2: 1 <= n <= 1024; ea-octa-grid: 1 <= n <= 2048;
// fibonacci: 1 <= n <= 2^24).
VFF_API Result<uint32_t> positionCount(PositionScheme scheme, uint32_t param);

// The reserved miss code of an encoding (255, 65535, or 0 for kBit1), and the largest hit code.
// kBc4Diameter's codes are those of kUnorm8Diameter (see vff/bc4.h for the blocks).
VFF_API uint32_t missCode(DistanceEncoding e) noexcept;
VFF_API uint32_t maxHitCode(DistanceEncoding e) noexcept;

// Bytes per map of the distance plane (kBit1: M*M/8, kBc4Diameter: M*M/2) and of the normal plane;
// 0 if invalid.
VFF_API uint64_t distanceMapBytes(DistanceEncoding e, uint32_t mapResolution) noexcept;
VFF_API uint64_t normalMapBytes(NormalEncoding e, uint32_t mapResolution) noexcept;

struct Sphere {
  float center[3] = {0, 0, 0};
  float radius = 0;
};

// The FDSC section: everything needed to interpret the maps.
struct FieldDesc {
  Sphere sphere;
  PositionScheme positionScheme = PositionScheme::kInvalid;
  uint32_t positionParam = 0;  // n for every scheme (see PositionScheme)
  uint32_t mapCount = 0;       // must equal positionCount(positionScheme, positionParam)
  DirectionScheme directionScheme = DirectionScheme::kInvalid;
  uint32_t mapResolution = 0;  // M: each map is M x M texels
  FrameConvention frame = FrameConvention::kDuff2017;
  DistanceEncoding distanceEncoding = DistanceEncoding::kInvalid;
  NormalEncoding normalEncoding = NormalEncoding::kNone;
};

// Checks a FieldDesc against the spec's rules 5001-5010; the error code names the rule.
VFF_API Status checkFieldDesc(const FieldDesc& desc);

// ---- Packed slice layout -------------------------------------------------------------------------
enum class LayoutTarget : uint32_t { kInvalid = 0, kTexture2DArray = 1, kTexture3D = 2 };
VFF_API const char* layoutTargetName(LayoutTarget t) noexcept;  // "2d-array", "3d"

// GPU limits a layout must respect. The defaults are the minimums OpenGL 4.3 guarantees for array
// layers and 3D textures (2048), which also keeps 2D slices within every GL 4.x implementation.
struct LayoutLimits {
  LayoutTarget target = LayoutTarget::kTexture2DArray;
  uint32_t maxTextureSize = 2048;  // max width/height of a slice, in texels
  uint32_t maxLayers = 2048;       // max array layers (2D array) or depth (3D)
  uint32_t gutter = 0;             // texels of edge replication around each tile (0 for kBit1)
};

// The LAYT section. Map i lives in slice i / (tilesPerRow*tilesPerColumn), at tile r = i mod that,
// column r mod tilesPerRow and row r / tilesPerRow; its first texel is at
// (column*tileSize + gutter, row*tileSize + gutter). Slices are sliceWidth x sliceHeight texels.
struct LayoutDesc {
  LayoutTarget target = LayoutTarget::kInvalid;
  uint32_t gutter = 0;
  uint32_t tileSize = 0;        // mapResolution + 2*gutter
  uint32_t tilesPerRow = 0;
  uint32_t tilesPerColumn = 0;
  uint32_t sliceWidth = 0;      // tilesPerRow * tileSize
  uint32_t sliceHeight = 0;     // tilesPerColumn * tileSize
  uint32_t sliceCount = 0;      // ceil(mapCount / (tilesPerRow * tilesPerColumn))
  uint32_t maxTextureSize = 0;  // the limits the layout was made for (informative)
  uint32_t maxLayers = 0;
};

// The canonical layout for a field under the given limits (spec/format.md, "Packed slice layout"):
// as many tiles per row as fit (at most mapCount), as many rows as needed (at most what fits), then
// slices. Fails with kLayoutGeometry naming the limit when the field does not fit.
VFF_API Result<LayoutDesc> computeLayout(const FieldDesc& field, const LayoutLimits& limits);

// Checks a LayoutDesc against a field (rules 7001-7003).
VFF_API Status checkLayout(const LayoutDesc& layout, const FieldDesc& field);

struct TilePlacement {
  uint32_t slice = 0;
  uint32_t x = 0;  // texel column of the map's texel (0,0) in the slice (inside the gutter)
  uint32_t y = 0;  // texel row
};
VFF_API TilePlacement placeMap(const LayoutDesc& layout, uint32_t map) noexcept;

}  // namespace vff
