#include "vff/reader.h"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <new>

#include "codec/codec.h"
#include "container/le.h"
#include "platform/mapped_file.h"
#include "container/parser.h"

namespace vff {

const char* planeName(Plane p) noexcept { return p == Plane::kDistance ? "distance" : "normal"; }

namespace {

// Stops at the first error; warnings do not stop a reader.
class FirstErrorSink final : public detail::IssueSink {
 public:
  bool add(Code code, Severity severity, uint32_t section, uint64_t offset, std::string message) override {
    if (severity == Severity::kWarning) return true;
    if (first.code == Code::kOk) first = makeError(code, std::move(message), section, offset);
    return false;
  }
  Error first;
};

// Leaves new elements uninitialised: a decode buffer then takes memory only where the decoder
// writes, so a block whose frame fails early costs next to nothing whatever its rawSize.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
};

struct BlockCache {
  std::once_flag once;
  std::vector<uint8_t, UninitAllocator<uint8_t>> data;  // decoded bytes (compressed blocks only)
  Error error;
};

}  // namespace

struct VFF_HIDDEN File::Impl {  // (VFF_HIDDEN: not exported with its class, vff/export.h)
  detail::MappedFile mapped;
  std::vector<uint8_t> owned;
  std::span<const uint8_t> bytes;
  ReadOptions options;
  detail::ParsedFile parsed;
  std::unique_ptr<BlockCache[]> cache[2];

  Result<std::span<const uint8_t>> block(Plane p, uint32_t bi) const {
    const PlaneInfo& pi = parsed.planes[size_t(p)];
    if (!pi.present)
      return makeError(Code::kPlanePresence, std::string("the file has no ") + planeName(p) + " plane");
    if (bi >= pi.blocks.size()) return makeError(Code::kOutOfRange, "block index out of range");
    const BlockInfo& b = pi.blocks[bi];
    const uint32_t tag = p == Plane::kDistance ? kTagDistance : kTagNormal;
    BlockCache& c = cache[size_t(p)][bi];
    const bool lazy = options.checksums == ChecksumPolicy::kLazy;
    auto stored = bytes.subspan(b.offset, b.storedSize);
    if (b.codec == Codec::kStored && !lazy) return stored;  // zero-copy
    std::call_once(c.once, [&] {
      if (lazy && detail::xxh3(stored) != b.checksum) {
        c.error = makeError(Code::kBlockChecksum, "block " + std::to_string(bi) + " checksum does not match", tag, b.offset);
        return;
      }
      if (b.codec == Codec::kStored) return;
      if (b.filter == Filter::kNone) {  // a frame that cannot hold rawSize bytes fails before the allocation
        if (Status st = detail::checkZstdFrame(stored, b.rawSize, Code::kBlockDecode); !st) {
          c.error = makeError(Code::kBlockDecode, "block " + std::to_string(bi) + ": " + st.error().message, tag, b.offset);
          return;
        }
      }
      try {
        c.data.resize(b.rawSize);
      } catch (const std::bad_alloc&) {
        c.error = makeError(Code::kOutOfMemory, "cannot allocate a decoded block", tag, b.offset);
        return;
      }
      Status st = detail::decodeBlock(b.codec, b.filter, {parsed.field.mapResolution}, stored, c.data, Code::kBlockDecode);
      if (!st) {
        c.error = makeError(Code::kBlockDecode, "block " + std::to_string(bi) + ": " + st.error().message, tag, b.offset);
        decltype(c.data)().swap(c.data);
      }
    });
    if (c.error.code != Code::kOk) return c.error;
    if (b.codec == Codec::kStored) return stored;
    return std::span<const uint8_t>(c.data);
  }
};

File::File(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
File::File(File&&) noexcept = default;
File& File::operator=(File&&) noexcept = default;
File::~File() = default;

namespace {

Result<File> finishOpen(std::unique_ptr<File::Impl> impl, const ReadOptions& options,
                        Result<File> (*make)(std::unique_ptr<File::Impl>)) {
  impl->options = options;
  detail::ParseOptions po;
  po.limits = options;
  po.verifySectionChecksums = options.checksums != ChecksumPolicy::kNone;
  po.verifyPlaneChecksums = options.checksums == ChecksumPolicy::kVerifyAll;
  FirstErrorSink sink;
  const bool ok = detail::parseFile(impl->bytes, po, sink, &impl->parsed);
  if (sink.first.code != Code::kOk) return sink.first;
  if (!ok) return makeError(Code::kInvalidArgument, "file is not usable");
  for (int p = 0; p < 2; ++p) {
    const size_t n = impl->parsed.planes[p].blocks.size();
    if (n) impl->cache[p] = std::make_unique<BlockCache[]>(n);
  }
  return make(std::move(impl));
}

}  // namespace

Result<File> File::open(const std::string& path, const ReadOptions& options) {
  auto impl = std::make_unique<Impl>();
  Status st = impl->mapped.open(path, options.checksums == ChecksumPolicy::kVerifyAll);
  if (!st) return std::move(st).error();
  impl->bytes = impl->mapped.bytes();
  return finishOpen(std::move(impl), options, [](std::unique_ptr<Impl> i) -> Result<File> { return File(std::move(i)); });
}

Result<File> File::openMemory(std::span<const uint8_t> bytes, const ReadOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->bytes = bytes;
  return finishOpen(std::move(impl), options, [](std::unique_ptr<Impl> i) -> Result<File> { return File(std::move(i)); });
}

Result<File> File::openBuffer(std::vector<uint8_t> bytes, const ReadOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->owned = std::move(bytes);
  impl->bytes = impl->owned;
  return finishOpen(std::move(impl), options, [](std::unique_ptr<Impl> i) -> Result<File> { return File(std::move(i)); });
}

const FileInfo& File::info() const noexcept { return impl_->parsed.info; }
const FieldDesc& File::field() const noexcept { return impl_->parsed.field; }
const LayoutDesc& File::layout() const noexcept { return impl_->parsed.layout; }
const PlaneInfo& File::plane(Plane p) const noexcept { return impl_->parsed.planes[size_t(p)]; }
std::string_view File::metadata() const noexcept { return impl_->parsed.metadata; }
const RefinementView& File::refinement() const noexcept { return impl_->parsed.refinement; }
std::span<const uint8_t> File::bytes() const noexcept { return impl_->bytes; }

Result<std::span<const uint8_t>> File::blockData(Plane p, uint32_t block) const { return impl_->block(p, block); }

Result<std::span<const uint8_t>> File::mapData(Plane p, uint32_t map) const {
  const PlaneInfo& pi = plane(p);
  if (map >= field().mapCount) return makeError(Code::kOutOfRange, "map " + std::to_string(map) + " out of range");
  if (!pi.present) return makeError(Code::kPlanePresence, std::string("the file has no ") + planeName(p) + " plane");
  const uint32_t bi = detail::blockOfMap(pi, map);
  auto blk = impl_->block(p, bi);
  if (!blk) return std::move(blk).error();
  const uint64_t at = uint64_t(map - pi.blocks[bi].firstMap) * pi.mapBytes;
  return blk->subspan(at, pi.mapBytes);
}

Status File::decodeBlock(Plane p, uint32_t block, std::span<uint8_t> out) const {
  const PlaneInfo& pi = plane(p);
  if (!pi.present) return makeError(Code::kPlanePresence, std::string("the file has no ") + planeName(p) + " plane");
  if (block >= pi.blocks.size()) return makeError(Code::kOutOfRange, "block index out of range");
  const BlockInfo& b = pi.blocks[block];
  if (out.size() != b.rawSize) return makeError(Code::kInvalidArgument, "output size differs from the block's rawSize");
  auto stored = impl_->bytes.subspan(b.offset, b.storedSize);
  if (impl_->options.checksums == ChecksumPolicy::kLazy && detail::xxh3(stored) != b.checksum)
    return makeError(Code::kBlockChecksum, "block checksum does not match", p == Plane::kDistance ? kTagDistance : kTagNormal, b.offset);
  if (b.codec == Codec::kZstd && b.filter == Filter::kNone)
    if (Status st = detail::checkZstdFrame(stored, b.rawSize, Code::kBlockDecode); !st)
      return makeError(Code::kBlockDecode, st.error().message, p == Plane::kDistance ? kTagDistance : kTagNormal, b.offset);
  Status st = detail::decodeBlock(b.codec, b.filter, {field().mapResolution}, stored, out, Code::kBlockDecode);
  if (!st) return makeError(Code::kBlockDecode, st.error().message, p == Plane::kDistance ? kTagDistance : kTagNormal, b.offset);
  return {};
}

uint64_t File::sliceBytes(Plane p) const noexcept {
  const LayoutDesc& l = layout();
  const uint64_t texels = uint64_t(l.sliceWidth) * l.sliceHeight;
  if (p == Plane::kNormal) return hasNormals() ? texels * 4 : 0;
  switch (field().distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord: return texels;
    case DistanceEncoding::kUnorm16Diameter: return texels * 2;
    case DistanceEncoding::kBit1: return texels / 8;
    case DistanceEncoding::kBc4Diameter: return texels / 2;
    case DistanceEncoding::kInvalid: break;
  }
  return 0;
}

Status File::readSlice(Plane p, uint32_t slice, std::span<uint8_t> out) const {
  const LayoutDesc& l = layout();
  const FieldDesc& f = field();
  if (!plane(p).present) return makeError(Code::kPlanePresence, std::string("the file has no ") + planeName(p) + " plane");
  if (slice >= l.sliceCount) return makeError(Code::kOutOfRange, "slice " + std::to_string(slice) + " out of range");
  if (out.size() != sliceBytes(p)) return makeError(Code::kInvalidArgument, "output size differs from sliceBytes()");
  const bool bit1 = p == Plane::kDistance && f.distanceEncoding == DistanceEncoding::kBit1;
  // bc4: the rows below are rows of 4x4 blocks (8 bytes each); such fields have no gutter.
  const bool bc4 = p == Plane::kDistance && f.distanceEncoding == DistanceEncoding::kBc4Diameter;
  // Bytes per texel (bit1: a texel column of 8 map texels is one byte).
  const uint32_t tb = p == Plane::kNormal ? 4 : f.distanceEncoding == DistanceEncoding::kUnorm16Diameter ? 2 : 1;
  const uint32_t m = f.mapResolution;
  const uint64_t rowBytes = bit1 ? l.sliceWidth / 8 : bc4 ? uint64_t(l.sliceWidth) * 2 : uint64_t(l.sliceWidth) * tb;
  const uint64_t mapRowBytes = bit1 ? m / 8 : bc4 ? uint64_t(m) * 2 : uint64_t(m) * tb;
  const uint32_t mapRows = bc4 ? m / 4 : m;
  // Empty tiles: the miss code (all ones for unorm encodings, and a block of all-ones bytes is all
  // misses in bc4; zero bits for bit1) or zero normals.
  const uint8_t fill = (p == Plane::kDistance && !bit1) ? 0xFF : 0x00;
  std::fill(out.begin(), out.end(), fill);
  const uint64_t perSlice = uint64_t(l.tilesPerRow) * l.tilesPerColumn;
  const uint32_t first = uint32_t(std::min<uint64_t>(f.mapCount, slice * perSlice));
  const uint32_t last = uint32_t(std::min<uint64_t>(f.mapCount, first + perSlice));
  const uint32_t g = l.gutter;
  for (uint32_t map = first; map < last; ++map) {
    auto data = mapData(p, map);
    if (!data) return std::move(data).error();
    const TilePlacement tp = placeMap(l, map);
    const uint64_t x0 = bit1 ? tp.x / 8 : bc4 ? uint64_t(tp.x) * 2 : uint64_t(tp.x) * tb;
    const uint64_t y0 = bc4 ? tp.y / 4 : tp.y;
    for (uint32_t j = 0; j < mapRows; ++j)
      std::memcpy(&out[(y0 + j) * rowBytes + x0], data->data() + j * mapRowBytes, mapRowBytes);
    if (g == 0) continue;
    // Gutters: replicate the edge texels outwards, first along rows, then whole rows.
    for (uint32_t j = 0; j < m; ++j) {
      uint8_t* row = &out[(tp.y + j) * rowBytes];
      for (uint32_t k = 1; k <= g; ++k) {
        std::memcpy(row + (uint64_t(tp.x) - k) * tb, row + uint64_t(tp.x) * tb, tb);
        std::memcpy(row + (uint64_t(tp.x) + m - 1 + k) * tb, row + (uint64_t(tp.x) + m - 1) * tb, tb);
      }
    }
    const uint64_t spanBytes = uint64_t(m + 2 * g) * tb;
    const uint64_t xs = uint64_t(tp.x - g) * tb;
    for (uint32_t k = 1; k <= g; ++k) {
      std::memcpy(&out[(tp.y - k) * rowBytes + xs], &out[tp.y * rowBytes + xs], spanBytes);
      std::memcpy(&out[(tp.y + m - 1 + k) * rowBytes + xs], &out[(tp.y + m - 1) * rowBytes + xs], spanBytes);
    }
  }
  return {};
}

}  // namespace vff
