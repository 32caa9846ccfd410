// vff/reader.h - opening and reading .vff files.
//
// The reader is safe on untrusted input: every offset and size is checked (overflow-safe) against
// the file size and the caller's limits before anything is allocated, and every failure is returned
// as an Error with the validation ID of the rule that failed (spec/validation.md).
//
//   vff::Result<vff::File> f = vff::File::open("bunny.vff");
//   if (!f) { fprintf(stderr, "%s\n", f.error().toString().c_str()); return 1; }
//   auto map = f->mapData(vff::Plane::kDistance, 17);  // zero-copy for stored blocks
//
// Thread safety: a File may be read from several threads at once (decoded blocks are cached under a
// lock and never move once decoded).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"
#include "vff/refine.h"

namespace vff {

enum class Plane : uint8_t { kDistance = 0, kNormal = 1 };
VFF_API const char* planeName(Plane p) noexcept;  // "distance", "normal"

enum class ChecksumPolicy : uint8_t {
  kVerifyAll = 0,  // header, every section and every block at open (XXH3: cheap next to reading the bytes)
  kLazy = 1,       // header and non-plane sections at open; each block when it is first decoded
  kNone = 2,       // only structural checks (for files already validated)
};

// Limits that protect a reader from hostile files. Zero-initialised fields are not "no limit":
// use the defaults below, or tighten them.
struct ReadOptions {
  uint32_t maxSections = 64;
  uint64_t maxMaps = uint64_t{1} << 24;         // positional samples (the largest scheme count)
  uint32_t maxMapResolution = 4096;             // M
  uint64_t maxPayloadBytes = uint64_t{1} << 36;  // raw bytes of all planes together (64 GiB)
  uint64_t maxSectionBytes = uint64_t{64} << 20;  // raw size of a non-plane section
  // Raw (decoded) size of one block of a plane (64 MiB): the most a decode allocates at once. A
  // zstd frame of a few KiB can really expand to a block's whole rawSize (up to 4 GiB, and every
  // check on the claim passes), so the limit is enforced at open, before anything is decoded
  // (decoded-limit, 5011, naming the block). The default holds the largest block the writer makes
  // on its own (256 KiB, or one map when a map is larger: at most 4096^2 normals = 64 MiB); a file
  // written with a larger WriteOptions::mapsPerBlock needs a larger limit. Readers that stream
  // block by block (File::decodeBlock into one buffer) then use at most this much for the decoded
  // data; those that keep every block (blockData, mapData, the query) use up to maxPayloadBytes.
  uint64_t maxBlockBytes = uint64_t{64} << 20;
  ChecksumPolicy checksums = ChecksumPolicy::kVerifyAll;
};

struct SectionInfo {
  uint32_t tag = 0;
  uint32_t flags = 0;
  uint64_t offset = 0;
  uint64_t storedSize = 0;
  uint64_t rawSize = 0;
  Codec codec = Codec::kStored;
  uint16_t sectionVersion = 0;
  uint64_t checksum = 0;
  bool known = false;  // a tag this reader understands
};

struct BlockInfo {
  uint64_t offset = 0;  // absolute file offset of the stored bytes
  uint64_t storedSize = 0;
  uint32_t rawSize = 0;
  uint32_t firstMap = 0;
  uint32_t mapCount = 0;
  Codec codec = Codec::kStored;
  Filter filter = Filter::kNone;
  uint64_t checksum = 0;
};

struct PlaneInfo {
  bool present = false;
  uint32_t mapBytes = 0;      // raw bytes per map
  uint32_t mapsPerBlock = 0;  // G; the last block may hold fewer
  uint64_t rawBytes = 0;      // mapCount * mapBytes: the payload
  uint64_t storedBytes = 0;   // sum of the blocks' stored sizes
  std::vector<BlockInfo> blocks;
};

struct FileInfo {
  uint16_t versionMajor = 0;
  uint16_t versionMinor = 0;
  uint64_t fileSize = 0;
  uint64_t incompatFeatures = 0;
  uint64_t roCompatFeatures = 0;
  ChecksumAlgorithm checksumAlgorithm = ChecksumAlgorithm::kInvalid;
  uint64_t headerChecksum = 0;
  std::vector<SectionInfo> sections;  // in table order
};

class VFF_API File {
 public:
  // Maps the file read-only. The file must not change while the File is alive.
  static Result<File> open(const std::string& path, const ReadOptions& options = {});
  // Borrows caller memory; `bytes` must outlive the File and every view it returns.
  static Result<File> openMemory(std::span<const uint8_t> bytes, const ReadOptions& options = {});
  // Takes ownership of a buffer.
  static Result<File> openBuffer(std::vector<uint8_t> bytes, const ReadOptions& options = {});

  File(File&&) noexcept;
  File& operator=(File&&) noexcept;
  ~File();

  const FileInfo& info() const noexcept;
  const FieldDesc& field() const noexcept;
  const LayoutDesc& layout() const noexcept;
  const PlaneInfo& plane(Plane p) const noexcept;
  bool hasNormals() const noexcept { return plane(Plane::kNormal).present; }
  // The metadata JSON text exactly as stored (one JSON object, rule 8001; libvff's writer makes it
  // canonical: sorted keys, no spaces), or empty when there is no META section. Its numbers may lie
  // beyond binary64 range (spec/format.md section 9).
  std::string_view metadata() const noexcept;
  // The refinement (REFN, format 1.3: vff/refine.h), checked when the file was opened; empty when
  // the file has none. Its views live as long as the File.
  const RefinementView& refinement() const noexcept;
  // The whole file's bytes (mapped or borrowed).
  std::span<const uint8_t> bytes() const noexcept;

  // The raw bytes of one map: a view into the file for stored blocks (zero-copy), or into the
  // decoded-block cache for compressed ones (decoded once, on first use). The view lives as long as
  // the File. Errors: kOutOfRange, kPlanePresence, kBlockChecksum (kLazy), kBlockDecode.
  Result<std::span<const uint8_t>> mapData(Plane p, uint32_t map) const;
  // The raw bytes of one block (all its maps, in order), with the same lifetime rules.
  Result<std::span<const uint8_t>> blockData(Plane p, uint32_t block) const;
  // Decodes a block into caller memory without touching the cache (out.size() == rawSize).
  Status decodeBlock(Plane p, uint32_t block, std::span<uint8_t> out) const;

  // Bytes of one packed slice of a plane: sliceWidth * sliceHeight * texel size, where the texel
  // size is 1 (kUnorm8*), 2 (kUnorm16Diameter), 4 (normals); for kBit1 a row holds sliceWidth/8
  // bytes; kBc4Diameter: sliceWidth/4 x sliceHeight/4 blocks of 8 bytes, row-major (the layout
  // glCompressedTexSubImage3D takes). The slice's rows are tightly packed, top row first.
  uint64_t sliceBytes(Plane p) const noexcept;
  // Composes slice `slice` into `out` (size sliceBytes(p)): each map at its placement, gutters
  // replicate the nearest edge texel, unused tiles hold the miss code (distance) or zero (normals).
  Status readSlice(Plane p, uint32_t slice, std::span<uint8_t> out) const;

  struct Impl;  // opaque
  VFF_HIDDEN explicit File(std::unique_ptr<Impl> impl);  // used by the library only (not exported)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace vff
