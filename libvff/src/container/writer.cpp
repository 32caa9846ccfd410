#include "vff/writer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>

#include "codec/codec.h"
#include "container/json_text.h"
#include "vff/reader.h"
#include "container/le.h"
#include "platform/parallel.h"

namespace vff {
namespace {

using detail::alignUp;
using detail::store;
using detail::storeF32;

std::string errnoText(const std::string& what) { return what + ": " + std::strerror(errno); }

// Where the bytes go: a temporary file (positioned writes) or memory.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual Status write(uint64_t offset, std::span<const uint8_t> bytes) = 0;
  virtual Status read(uint64_t offset, std::span<uint8_t> out) = 0;
};

class MemorySink final : public Sink {
 public:
  Status write(uint64_t offset, std::span<const uint8_t> bytes) override {
    if (buf.size() < offset + bytes.size()) buf.resize(offset + bytes.size());
    std::copy(bytes.begin(), bytes.end(), buf.begin() + std::ptrdiff_t(offset));
    return {};
  }
  Status read(uint64_t offset, std::span<uint8_t> out) override {
    std::copy_n(buf.begin() + std::ptrdiff_t(offset), out.size(), out.begin());
    return {};
  }
  std::vector<uint8_t> buf;
};

class FileSink final : public Sink {
 public:
  ~FileSink() override { discard(); }
  Status create(const std::string& path) {
    dest = path;
    const size_t slash = path.find_last_of('/');
    dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
    const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    if (base.empty()) return makeError(Code::kInvalidArgument, "'" + path + "' names no file");
    static std::atomic<unsigned> counter{0};
    for (int attempt = 0; attempt < 100; ++attempt) {
      tmp = dir + "/." + base + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
      fd = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd >= 0) return {};
      if (errno != EEXIST) break;
    }
    return makeError(Code::kIoWrite, errnoText("cannot create a temporary file next to " + path));
  }
  Status write(uint64_t offset, std::span<const uint8_t> bytes) override {
    size_t done = 0;
    while (done < bytes.size()) {
      ssize_t n = pwrite(fd, bytes.data() + done, bytes.size() - done, off_t(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return makeError(Code::kIoWrite, errnoText(dest + ": write failed"));
      done += size_t(n);
    }
    return {};
  }
  Status read(uint64_t offset, std::span<uint8_t> out) override {
    size_t done = 0;
    while (done < out.size()) {
      ssize_t n = pread(fd, out.data() + done, out.size() - done, off_t(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return makeError(Code::kIoWrite, errnoText(dest + ": read-back failed"));
      done += size_t(n);
    }
    return {};
  }
  Status commit(bool sync) {
    if (sync && fsync(fd) != 0) return makeError(Code::kIoWrite, errnoText(dest + ": fsync failed"));
    if (::close(fd) != 0) {
      fd = -1;
      return makeError(Code::kIoWrite, errnoText(dest + ": close failed"));
    }
    fd = -1;
    if (std::rename(tmp.c_str(), dest.c_str()) != 0)
      return makeError(Code::kIoWrite, errnoText("cannot rename the temporary file to " + dest));
    tmp.clear();
    if (sync) {
      int d = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
      if (d >= 0) {
        fsync(d);
        ::close(d);
      }
    }
    return {};
  }
  void discard() noexcept {
    if (fd >= 0) ::close(fd);
    fd = -1;
    if (!tmp.empty()) ::unlink(tmp.c_str());
    tmp.clear();
  }
  std::string dest, dir, tmp;
  int fd = -1;
};

struct PlaneState {
  bool enabled = false;
  uint64_t mapBytes = 0;
  uint32_t g = 0;            // maps per block
  uint32_t blockCount = 0;
  uint32_t mapsWritten = 0;
  uint32_t blocksDone = 0;
  uint64_t sectionOffset = 0;
  uint64_t nextBlock = 0;    // relative offset of the next block
  std::vector<uint8_t> pending;  // raw bytes of the current, incomplete block
  std::vector<uint8_t> index;    // block entries
  bool anyZstd = false;
  bool anyFilter = false;
  bool done = false;
};

std::vector<uint8_t> encodeField(const FieldDesc& f) {
  std::vector<uint8_t> b(kFieldDescSize, 0);
  storeF32(&b[0], f.sphere.center[0]);
  storeF32(&b[4], f.sphere.center[1]);
  storeF32(&b[8], f.sphere.center[2]);
  storeF32(&b[12], f.sphere.radius);
  store<uint32_t>(&b[16], uint32_t(f.positionScheme));
  store<uint32_t>(&b[20], f.positionParam);
  store<uint32_t>(&b[24], f.mapCount);
  store<uint32_t>(&b[28], uint32_t(f.directionScheme));
  store<uint32_t>(&b[32], f.mapResolution);
  store<uint32_t>(&b[36], uint32_t(f.frame));
  store<uint32_t>(&b[40], uint32_t(f.distanceEncoding));
  store<uint32_t>(&b[44], missCode(f.distanceEncoding));
  store<uint32_t>(&b[48], uint32_t(f.normalEncoding));
  return b;
}

std::vector<uint8_t> encodeLayout(const LayoutDesc& l) {
  std::vector<uint8_t> b(kLayoutDescSize, 0);
  const uint32_t v[] = {uint32_t(l.target), l.gutter,      l.tileSize,    l.tilesPerRow,    l.tilesPerColumn,
                        l.sliceWidth,       l.sliceHeight, l.sliceCount,  l.maxTextureSize, l.maxLayers};
  for (size_t i = 0; i < std::size(v); ++i) store<uint32_t>(&b[4 * i], v[i]);
  return b;
}

}  // namespace

struct VFF_HIDDEN Writer::Impl {  // (VFF_HIDDEN: not exported with its class, vff/export.h)
  FieldDesc field;
  WriteOptions options;
  LayoutDesc layout;
  std::unique_ptr<Sink> sink;
  FileSink* file = nullptr;  // when writing to a file
  MemorySink* memory = nullptr;
  std::vector<SectionInfo> sections;  // the section table as a reader lists it (vff/reader.h)
  PlaneState planes[2];
  uint64_t cursor = 0;
  uint64_t mapsWritten = 0;  // for options.progress
  bool finished = false;
  bool failed = false;
  std::string metaPending;  // canonical metadata JSON, written by writePrologue()
  std::vector<uint8_t> refinePending;  // REFN's raw bytes, written by finish() after the planes

  // The sections that precede the planes: FDSC, LAYT and META.
  Status writePrologue() {
    Status st = addSection(kTagField, kSectionRequired, encodeField(field), Codec::kStored);
    if (st) st = addSection(kTagLayout, kSectionRequired, encodeLayout(layout), Codec::kStored);
    if (st && !metaPending.empty()) {
      auto bytes = std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(metaPending.data()), metaPending.size());
      st = addSection(kTagMetadata, kSectionCopySafe, bytes, options.codec);
    }
    return st;
  }

  Status fail(Error e) {
    failed = true;
    return e;
  }

  Status addSection(uint32_t tag, uint32_t flags, std::span<const uint8_t> raw, Codec codec) {
    SectionInfo s;
    s.tag = tag;
    s.flags = flags;
    s.offset = cursor;
    s.rawSize = raw.size();
    std::vector<uint8_t> stored;
    Status st = detail::compress(codec, options.zstdLevel, raw, &stored);
    if (!st) return st;
    if (codec != Codec::kStored && stored.size() >= raw.size()) {
      codec = Codec::kStored;
      stored.assign(raw.begin(), raw.end());
    }
    s.codec = codec;
    s.storedSize = stored.size();
    s.checksum = detail::xxh3(stored);
    st = sink->write(cursor, stored);
    if (!st) return st;
    cursor = alignUp(cursor + stored.size(), kSectionAlignment);
    sections.push_back(s);
    return {};
  }

  void beginPlane(Plane p) {
    PlaneState& ps = planes[size_t(p)];
    ps.sectionOffset = cursor;
    ps.nextBlock = alignUp(kPlaneHeaderSize + uint64_t(ps.blockCount) * kBlockEntrySize, kBlockAlignment);
    ps.index.assign(uint64_t(ps.blockCount) * kBlockEntrySize, 0);
  }

  // Encodes and writes complete raw blocks (in order), compressing them on several threads, a
  // window of blocks at a time: at least one block per thread and kWindowBytes of raw bytes, so
  // that the compressed blocks held at once stay within about that (a frame kept is smaller than
  // its block) while each thread's zstd context serves many blocks.
  static constexpr uint64_t kWindowBytes = 32u << 20;
  Status writeBlocks(Plane p, const std::vector<std::span<const uint8_t>>& raws) {
    const unsigned threads = parallel::resolveThreads(options.threads);
    for (size_t first = 0; first < raws.size();) {
      size_t n = 0;
      uint64_t bytes = 0;
      while (first + n < raws.size() && (n < threads || bytes < kWindowBytes)) bytes += raws[first + n++].size();
      Status st = writeWindow(p, std::span<const std::span<const uint8_t>>(raws).subspan(first, n), threads);
      if (!st) return st;
      first += n;
      if (options.progress) {
        const uint64_t mapBytes = p == Plane::kDistance ? distanceMapBytes(field.distanceEncoding, field.mapResolution)
                                                        : normalMapBytes(field.normalEncoding, field.mapResolution);
        for (size_t i = first - n; i < first; ++i) mapsWritten += raws[i].size() / mapBytes;
        const uint64_t planesPresent = field.normalEncoding == NormalEncoding::kNone ? 1 : 2;
        options.progress(mapsWritten, uint64_t(field.mapCount) * planesPresent);
      }
    }
    return {};
  }

  Status writeWindow(Plane p, std::span<const std::span<const uint8_t>> raws, unsigned threads) {
    PlaneState& ps = planes[size_t(p)];
    std::vector<std::vector<uint8_t>> stored(raws.size());
    std::vector<Codec> codecs(raws.size(), options.codec);
    std::vector<Filter> filters(raws.size(), Filter::kNone);
    std::vector<Status> status(raws.size());
    const Filter tryFilter = p == Plane::kDistance ? options.filter : Filter::kNone;
    if (options.codec == Codec::kStored) {
      for (size_t i = 0; i < raws.size(); ++i) codecs[i] = Codec::kStored;
    } else {
      // One block per chunk, each block's results at its index (the order written below).
      parallel::parallelFor(raws.size(), 1, threads, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
          status[i] = detail::compress(options.codec, options.zstdLevel, raws[i], &stored[i]);
          if (status[i] && tryFilter != Filter::kNone) {  // keep the filtered frame only when smaller
            std::vector<uint8_t> filtered;
            status[i] = detail::compress(options.codec, options.zstdLevel,
                                         detail::applyFilter(tryFilter, {field.mapResolution}, raws[i]), &filtered);
            if (status[i] && filtered.size() < stored[i].size()) {
              stored[i].swap(filtered);
              filters[i] = tryFilter;
            }
          }
          if (status[i] && stored[i].size() >= raws[i].size()) {  // incompressible: store it
            codecs[i] = Codec::kStored;
            filters[i] = Filter::kNone;
            std::vector<uint8_t>().swap(stored[i]);
          }
        }
      });
    }
    for (size_t i = 0; i < raws.size(); ++i) {
      if (!status[i]) return status[i];
      std::span<const uint8_t> bytes = codecs[i] == Codec::kStored ? raws[i] : std::span<const uint8_t>(stored[i]);
      uint8_t* e = &ps.index[uint64_t(ps.blocksDone) * kBlockEntrySize];
      store<uint64_t>(e, ps.nextBlock);
      store<uint64_t>(e + 8, bytes.size());
      store<uint32_t>(e + 16, uint32_t(raws[i].size()));
      e[20] = uint8_t(codecs[i]);
      e[21] = uint8_t(filters[i]);
      if (filters[i] != Filter::kNone) ps.anyFilter = true;
      store<uint64_t>(e + 24, detail::xxh3(bytes));
      if (codecs[i] == Codec::kZstd) ps.anyZstd = true;
      Status st = sink->write(ps.sectionOffset + ps.nextBlock, bytes);
      if (!st) return st;
      ps.nextBlock = ps.nextBlock + bytes.size();
      if (++ps.blocksDone < ps.blockCount) ps.nextBlock = alignUp(ps.nextBlock, kBlockAlignment);
    }
    return {};
  }

  Status endPlane(Plane p) {
    PlaneState& ps = planes[size_t(p)];
    std::vector<uint8_t> head(kPlaneHeaderSize, 0);
    store<uint32_t>(&head[0], field.mapCount);
    store<uint32_t>(&head[4], uint32_t(ps.mapBytes));
    store<uint32_t>(&head[8], ps.g);
    store<uint32_t>(&head[12], ps.blockCount);
    Status st = sink->write(ps.sectionOffset, head);
    if (!st) return st;
    st = sink->write(ps.sectionOffset + kPlaneHeaderSize, ps.index);
    if (!st) return st;
    SectionInfo s;
    s.tag = p == Plane::kDistance ? kTagDistance : kTagNormal;
    s.flags = p == Plane::kDistance ? kSectionRequired : 0;
    s.offset = ps.sectionOffset;
    s.storedSize = s.rawSize = ps.nextBlock;
    // Checksum of the whole section, read back in pieces.
    detail::Xxh3Stream h;
    std::vector<uint8_t> buf(std::min<uint64_t>(s.storedSize, 1u << 20));
    for (uint64_t at = 0; at < s.storedSize; at += buf.size()) {
      std::span<uint8_t> piece(buf.data(), size_t(std::min<uint64_t>(buf.size(), s.storedSize - at)));
      st = sink->read(s.offset + at, piece);
      if (!st) return st;
      h.update(piece);
    }
    s.checksum = h.digest();
    sections.push_back(s);
    cursor = alignUp(s.offset + s.storedSize, kSectionAlignment);
    ps.done = true;
    return {};
  }

  Status writeMaps(Plane p, std::span<const uint8_t> bytes) {
    if (finished || failed) return makeError(Code::kBadState, "the writer is finished or has failed");
    PlaneState& ps = planes[size_t(p)];
    if (!ps.enabled)
      return makeError(Code::kBadState, std::string("the field has no ") + planeName(p) + " plane");
    if (ps.done) return makeError(Code::kBadState, std::string("all ") + planeName(p) + " maps are already written");
    if (p == Plane::kNormal && !planes[0].done)
      return makeError(Code::kBadState, "write every distance map before the normal maps");
    if (bytes.size() % ps.mapBytes != 0)
      return makeError(Code::kInvalidArgument, "write whole maps: " + std::to_string(bytes.size()) +
                                                   " bytes is not a multiple of " + std::to_string(ps.mapBytes));
    const uint64_t maps = bytes.size() / ps.mapBytes;
    if (maps > uint64_t(field.mapCount) - ps.mapsWritten)
      return makeError(Code::kInvalidArgument, "more maps than the field's mapCount");
    if (ps.mapsWritten == 0 && ps.pending.empty()) beginPlane(p);
    // Complete the pending block first, then take whole blocks straight from the caller's bytes.
    std::vector<std::span<const uint8_t>> whole;
    const uint64_t blockBytes = uint64_t(ps.g) * ps.mapBytes;
    uint64_t at = 0;
    std::vector<uint8_t> firstBlock;
    const uint64_t total = uint64_t(field.mapCount) * ps.mapBytes;
    auto blockSizeAt = [&](uint64_t rawOffset) { return std::min(blockBytes, total - rawOffset); };
    const uint64_t already = uint64_t(ps.mapsWritten) * ps.mapBytes;  // raw bytes received so far
    if (!ps.pending.empty() || already % blockBytes != 0) {
      const uint64_t blockStart = already - ps.pending.size();
      const uint64_t want = blockSizeAt(blockStart) - ps.pending.size();
      const uint64_t take = std::min<uint64_t>(want, bytes.size());
      ps.pending.insert(ps.pending.end(), bytes.begin(), bytes.begin() + std::ptrdiff_t(take));
      at = take;
      if (ps.pending.size() == blockSizeAt(blockStart)) {
        firstBlock.swap(ps.pending);
        whole.emplace_back(firstBlock);
      }
    }
    while (at < bytes.size()) {
      const uint64_t size = blockSizeAt(already + at);
      if (bytes.size() - at < size) {
        ps.pending.assign(bytes.begin() + std::ptrdiff_t(at), bytes.end());
        at = bytes.size();
        break;
      }
      whole.emplace_back(bytes.subspan(at, size));
      at += size;
    }
    Status st = writeBlocks(p, whole);
    if (!st) return fail(std::move(st).error());
    ps.mapsWritten += uint32_t(maps);
    if (ps.mapsWritten == field.mapCount) {
      st = endPlane(p);
      if (!st) return fail(std::move(st).error());
    }
    return {};
  }

  Status finish() {
    if (finished || failed) return makeError(Code::kBadState, "the writer is finished or has failed");
    for (int p = 0; p < 2; ++p)
      if (planes[p].enabled && !planes[p].done)
        return makeError(Code::kBadState, std::string("only ") + std::to_string(planes[p].mapsWritten) + " of " +
                                              std::to_string(field.mapCount) + " " + planeName(Plane(p)) +
                                              " maps were written");
    if (!refinePending.empty()) {
      Status st = addSection(kTagRefinement, 0, refinePending, options.codec);
      if (!st) return fail(std::move(st).error());
      refinePending.clear();
    }
    uint64_t incompat = 0;
    for (const auto& s : sections)
      if (s.codec == Codec::kZstd) incompat |= kFeatureZstd;
    if (planes[0].anyZstd || planes[1].anyZstd) incompat |= kFeatureZstd;
    if (planes[0].anyFilter || planes[1].anyFilter) incompat |= kFeatureFilters;
    if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) incompat |= kFeatureBc4;
    const SectionInfo& last = sections.back();
    const uint64_t fileSize = last.offset + last.storedSize;
    std::vector<uint8_t> head(kHeaderSize + sections.size() * kSectionEntrySize, 0);
    std::copy(std::begin(kMagic), std::end(kMagic), head.begin());
    store<uint16_t>(&head[8], kVersionMajor);
    // The lowest version that holds the file: 1.3 with a refinement, else 1.2 with a 1.2 feature
    // (bc4-diameter), else 1.1 with a 1.1 feature (a filter), else 1.0.
    bool refined = false;
    for (const auto& s : sections) refined = refined || s.tag == kTagRefinement;
    store<uint16_t>(&head[10], uint16_t(refined                     ? 3
                                        : (incompat & kFeatureBc4)     ? 2
                                        : (incompat & kFeatureFilters) ? 1
                                                                       : 0));
    store<uint32_t>(&head[12], kHeaderSize);
    store<uint64_t>(&head[16], fileSize);
    store<uint64_t>(&head[24], incompat);
    store<uint64_t>(&head[32], 0);
    store<uint64_t>(&head[40], kHeaderSize);
    store<uint32_t>(&head[48], uint32_t(sections.size()));
    store<uint16_t>(&head[52], uint16_t(kSectionEntrySize));
    head[54] = uint8_t(ChecksumAlgorithm::kXxh3_64);
    for (size_t i = 0; i < sections.size(); ++i) {
      uint8_t* e = &head[kHeaderSize + i * kSectionEntrySize];
      const SectionInfo& s = sections[i];
      store<uint32_t>(e, s.tag);
      store<uint32_t>(e + 4, s.flags);
      store<uint64_t>(e + 8, s.offset);
      store<uint64_t>(e + 16, s.storedSize);
      store<uint64_t>(e + 24, s.rawSize);
      store<uint16_t>(e + 32, uint16_t(s.codec));
      store<uint16_t>(e + 34, 1);
      store<uint64_t>(e + 40, s.checksum);
    }
    detail::Xxh3Stream h;
    h.update(std::span<const uint8_t>(head).subspan(0, 56));
    h.update(std::span<const uint8_t>(head).subspan(kHeaderSize));
    store<uint64_t>(&head[56], h.digest());
    Status st = sink->write(0, head);
    if (!st) return fail(std::move(st).error());
    if (file) {
      st = file->commit(options.sync);
      if (!st) return fail(std::move(st).error());
    }
    finished = true;
    return {};
  }
};

Writer::Writer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&&) noexcept = default;
Writer::~Writer() { abort(); }

namespace {

Result<std::unique_ptr<Writer::Impl>> prepare(const FieldDesc& field, const WriteOptions& options) {
  Status st = checkFieldDesc(field);
  if (!st) return makeError(st.error().code, "invalid field: " + st.error().message);
  if (options.codec != Codec::kStored && options.codec != Codec::kZstd)
    return makeError(Code::kInvalidArgument, "unknown codec");
  if (options.codec == Codec::kZstd && (options.zstdLevel < 1 || options.zstdLevel > 22))
    return makeError(Code::kInvalidArgument, "zstd level must be in [1, 22]");
  if (options.filter != Filter::kNone) {
    if (options.filter != Filter::kHitsMed) return makeError(Code::kInvalidArgument, "unknown filter");
    if (options.codec != Codec::kZstd)
      return makeError(Code::kInvalidArgument, "a block filter needs codec zstd");
    if (!detail::filterApplies(options.filter, Plane::kDistance, field))
      return makeError(Code::kInvalidArgument, std::string("filter ") + filterName(options.filter) +
                                                   " does not apply to the distance encoding " +
                                                   distanceEncodingName(field.distanceEncoding));
  }
  auto layout = computeLayout(field, options.layout);
  if (!layout) return std::move(layout).error();
  auto impl = std::make_unique<Writer::Impl>();
  impl->field = field;
  impl->options = options;
  impl->options.refinement = {};  // (encoded below: the writer keeps no borrowed view)
  impl->layout = *layout;
  const uint64_t mapBytes[2] = {distanceMapBytes(field.distanceEncoding, field.mapResolution),
                                normalMapBytes(field.normalEncoding, field.mapResolution)};
  for (int p = 0; p < 2; ++p) {
    PlaneState& ps = impl->planes[p];
    ps.enabled = mapBytes[p] > 0;
    if (!ps.enabled) continue;
    ps.mapBytes = mapBytes[p];
    uint64_t g = options.mapsPerBlock ? options.mapsPerBlock : std::max<uint64_t>(1, (256u << 10) / mapBytes[p]);
    g = std::min<uint64_t>(g, field.mapCount);
    // A block of several maps stays within what a reader accepts by default (one map is always
    // allowed: the largest, 4096^2 normals, is exactly the limit), so the writer never makes a file
    // that its own reader refuses with decoded-limit (5011).
    const uint64_t readerLimit = ReadOptions{}.maxBlockBytes;
    if (g > 1 && g * mapBytes[p] > readerLimit)
      return makeError(Code::kInvalidArgument, "mapsPerBlock " + std::to_string(g) + " x " + std::to_string(mapBytes[p]) +
                                                   "-byte maps gives blocks of " + std::to_string(g * mapBytes[p]) +
                                                   " bytes, above the " + std::to_string(readerLimit) +
                                                   " bytes a reader accepts by default (ReadOptions::maxBlockBytes)");
    ps.g = uint32_t(g);
    ps.blockCount = uint32_t((uint64_t(field.mapCount) + g - 1) / g);
  }
  std::string meta;
  if (!options.metadataJson.empty()) {
    auto j = nlohmann::json::parse(options.metadataJson, nullptr, false);
    // Valid META (rule 8001) that nlohmann cannot hold, a number beyond binary64, is content this
    // writer does not support; anything else it refuses is not JSON.
    if (j.is_discarded()) {
      if (detail::checkJsonText(options.metadataJson, detail::kMaxJsonDepth).problem.empty())
        return makeError(Code::kUnsupported,
                         "metadataJson holds a number beyond the binary64 range, which the writer cannot canonicalise");
      return makeError(Code::kMetadataJson, "metadataJson is not JSON (RFC 8259)");
    }
    if (!j.is_object()) return makeError(Code::kMetadataNotObject, "metadataJson must be a JSON object");
    try {
      meta = j.dump();
    } catch (const std::exception& e) {
      return makeError(Code::kMetadataJson, std::string("metadataJson: ") + e.what());
    }
  }
  if (!options.refinement.empty()) {
    auto raw = encodeRefinement(field, options.refinement);
    if (!raw) return std::move(raw).error();
    impl->refinePending = std::move(*raw);
  }
  // Sections before the planes: FDSC, LAYT, META; REFN after them (setRefinement may add it later:
  // the table's room is counted for it, and at most 6 entries fit the first 4096 bytes anyway).
  const size_t count = 3 + (impl->planes[1].enabled ? 1 : 0) + (meta.empty() ? 0 : 1) + 1;
  impl->cursor = alignUp(kHeaderSize + count * kSectionEntrySize, kSectionAlignment);
  impl->sections.reserve(count);
  impl->metaPending = std::move(meta);
  return impl;
}

}  // namespace

Result<Writer> Writer::create(const std::string& path, const FieldDesc& field, const WriteOptions& options) {
  auto impl = prepare(field, options);
  if (!impl) return std::move(impl).error();
  auto sink = std::make_unique<FileSink>();
  Status st = sink->create(path);
  if (!st) return std::move(st).error();
  (*impl)->file = sink.get();
  (*impl)->sink = std::move(sink);
  st = (*impl)->writePrologue();
  if (!st) return std::move(st).error();
  return Writer(std::move(*impl));
}

Result<Writer> Writer::createInMemory(const FieldDesc& field, const WriteOptions& options) {
  auto impl = prepare(field, options);
  if (!impl) return std::move(impl).error();
  auto sink = std::make_unique<MemorySink>();
  (*impl)->memory = sink.get();
  (*impl)->sink = std::move(sink);
  Status st = (*impl)->writePrologue();
  if (!st) return std::move(st).error();
  return Writer(std::move(*impl));
}

Status Writer::writeMaps(Plane p, std::span<const uint8_t> bytes) {
  if (!impl_) return makeError(Code::kBadState, "moved-from writer");
  return impl_->writeMaps(p, bytes);
}

Status Writer::setRefinement(const RefinementView& refinement) {
  if (!impl_) return makeError(Code::kBadState, "moved-from writer");
  if (impl_->finished || impl_->failed) return makeError(Code::kBadState, "the writer is finished or has failed");
  if (refinement.empty()) {
    impl_->refinePending.clear();
    return {};
  }
  auto raw = encodeRefinement(impl_->field, refinement);
  if (!raw) return std::move(raw).error();
  impl_->refinePending = std::move(*raw);
  return {};
}

Status Writer::finish() {
  if (!impl_) return makeError(Code::kBadState, "moved-from writer");
  if (!impl_->file) return makeError(Code::kBadState, "an in-memory writer finishes with finishToMemory()");
  return impl_->finish();
}

Result<std::vector<uint8_t>> Writer::finishToMemory() {
  if (!impl_) return makeError(Code::kBadState, "moved-from writer");
  if (!impl_->memory) return makeError(Code::kBadState, "a file writer finishes with finish()");
  Status st = impl_->finish();
  if (!st) return std::move(st).error();
  return std::move(impl_->memory->buf);
}

void Writer::abort() noexcept {
  if (impl_ && impl_->file && !impl_->finished) impl_->file->discard();
}

const LayoutDesc& Writer::layout() const noexcept { return impl_->layout; }

namespace {
Status writeAll(Writer& w, const FieldDesc& field, std::span<const uint8_t> distance, std::span<const uint8_t> normals) {
  Status st = w.writeMaps(Plane::kDistance, distance);
  if (!st) return st;
  if (field.normalEncoding != NormalEncoding::kNone) {
    st = w.writeMaps(Plane::kNormal, normals);
    if (!st) return st;
  } else if (!normals.empty()) {
    return makeError(Code::kInvalidArgument, "normal maps given for a field without a normal encoding");
  }
  return {};
}
}  // namespace

Status writeFile(const std::string& path, const FieldDesc& field, std::span<const uint8_t> distance,
                 std::span<const uint8_t> normals, const WriteOptions& options) {
  auto w = Writer::create(path, field, options);
  if (!w) return std::move(w).error();
  Status st = writeAll(*w, field, distance, normals);
  if (!st) return st;
  return w->finish();
}

Result<std::vector<uint8_t>> writeMemory(const FieldDesc& field, std::span<const uint8_t> distance,
                                         std::span<const uint8_t> normals, const WriteOptions& options) {
  auto w = Writer::createInMemory(field, options);
  if (!w) return std::move(w).error();
  Status st = writeAll(*w, field, distance, normals);
  if (!st) return std::move(st).error();
  return w->finishToMemory();
}

}  // namespace vff
