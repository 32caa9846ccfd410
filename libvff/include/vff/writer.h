// vff/writer.h - writing .vff files: streaming, deterministic, crash-safe.
//
// The writer streams maps into a temporary file in the destination folder and renames it into
// place only when finish() succeeds, so a crash or an error never leaves a partial file under the
// destination name (an existing file there stays untouched until the rename). The same field, maps
// and options always give the same bytes: nothing depends on time, threads or the host.
//
//   vff::Result<vff::Writer> w = vff::Writer::create("out.vff", field, options);
//   w->writeMaps(vff::Plane::kDistance, distanceBytes);   // any number of whole maps, in order
//   w->writeMaps(vff::Plane::kNormal, normalBytes);       // after all distance maps
//   vff::Status s = w->finish();
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"
#include "vff/reader.h"
#include "vff/refine.h"

namespace vff {

struct WriteOptions {
  Codec codec = Codec::kStored;  // block codec of both planes
  int zstdLevel = 19;            // 1..22, used when codec is kZstd
  // G; 0 picks the largest G with G * mapBytes <= 256 KiB (>= 1). A G > 1 whose blocks exceed
  // ReadOptions::maxBlockBytes (64 MiB), which default readers refuse, is kInvalidArgument.
  uint32_t mapsPerBlock = 0;
  // Filter tried on every distance block before the codec (spec/format.md section 4): each block is
  // compressed with and without it and the smaller is kept (a tie keeps the plain block). kHitsMed
  // needs codec kZstd and an 8-bit distance encoding (else kInvalidArgument); a file that uses it is
  // format 1.1 with incompatFeatures bit 1, which 1.0 readers reject.
  Filter filter = Filter::kNone;
  LayoutLimits layout;           // limits for the packed slice layout
  // Metadata as a JSON object text, or empty for none. It is stored canonically (sorted keys,
  // no insignificant whitespace), so equal objects give equal bytes. Keys starting with "vff."
  // are reserved for the names in spec/format.md.
  std::string metadataJson;
  // A refinement (vff/refine.h), written as the section REFN after the planes (format 1.3), with
  // `codec`; borrowed until finish(). Empty: none. It must match the field (else kInvalidArgument).
  RefinementView refinement;
  bool sync = true;  // fsync the file and its folder before and after the rename
  // Threads compressing blocks (0: one per core). The bytes written do not depend on it.
  unsigned threads = 0;
  // Called after each run of blocks is written, from the writing thread, with the maps written so
  // far and the maps of every plane the field has (distance, and normals when present); may be empty.
  std::function<void(uint64_t done, uint64_t total)> progress;
};

class VFF_API Writer {
 public:
  // Starts a file at `path` ("-" is not supported: files need seeking). Fails with
  // kInvalidArgument for an invalid field or options, kIoWrite when the temporary cannot be made.
  static Result<Writer> create(const std::string& path, const FieldDesc& field,
                               const WriteOptions& options = {});
  // Same, but the result is kept in memory; take it with finishToMemory().
  static Result<Writer> createInMemory(const FieldDesc& field, const WriteOptions& options = {});

  Writer(Writer&&) noexcept;
  Writer& operator=(Writer&&) noexcept;
  ~Writer();  // removes the temporary file unless finish() succeeded

  // Appends whole maps (bytes.size() must be a multiple of the plane's map size). All distance
  // maps come first, then (if the field has a normal encoding) all normal maps.
  Status writeMaps(Plane p, std::span<const uint8_t> bytes);
  // Sets (or replaces) the refinement written as REFN when the file is finished: the same as
  // WriteOptions::refinement, for a refinement made after the maps (from them). Copied. Errors:
  // kInvalidArgument when it does not match the field, kBadState after finish().
  Status setRefinement(const RefinementView& refinement);
  // Completes the file: writes the indexes, header and checksums, syncs and renames into place.
  Status finish();
  Result<std::vector<uint8_t>> finishToMemory();
  // Gives up: removes the temporary file. Safe to call more than once.
  void abort() noexcept;

  const LayoutDesc& layout() const noexcept;

  struct Impl;  // opaque
  VFF_HIDDEN explicit Writer(std::unique_ptr<Impl> impl);  // used by the library only (not exported)

 private:
  std::unique_ptr<Impl> impl_;
};

// One call for a field held in memory.
VFF_API Status writeFile(const std::string& path, const FieldDesc& field, std::span<const uint8_t> distance,
                         std::span<const uint8_t> normals = {}, const WriteOptions& options = {});
VFF_API Result<std::vector<uint8_t>> writeMemory(const FieldDesc& field, std::span<const uint8_t> distance,
                                                 std::span<const uint8_t> normals = {},
                                                 const WriteOptions& options = {});

}  // namespace vff
