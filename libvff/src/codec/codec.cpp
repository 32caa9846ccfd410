#include "codec/codec.h"

#include <xxhash.h>
#include <zstd.h>

#include <memory>
#include <new>
#include <cstring>
#include <string>

namespace vff::detail {

uint64_t xxh3(std::span<const uint8_t> bytes) noexcept {
  return XXH3_64bits(bytes.data(), bytes.size());
}

Xxh3Stream::Xxh3Stream() : state_(XXH3_createState()) {
  XXH3_64bits_reset(static_cast<XXH3_state_t*>(state_));
}
Xxh3Stream::~Xxh3Stream() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }
void Xxh3Stream::update(std::span<const uint8_t> bytes) noexcept {
  XXH3_64bits_update(static_cast<XXH3_state_t*>(state_), bytes.data(), bytes.size());
}
uint64_t Xxh3Stream::digest() const noexcept {
  return XXH3_64bits_digest(static_cast<const XXH3_state_t*>(state_));
}

namespace {

// One compression context per thread, reset before each frame: a level-19 context holds megabytes
// of tables, which were allocated and freed for every block. Only the level and the fixed
// parameters set below shape a frame, so reusing a context gives the same bytes.
ZSTD_CCtx* threadCCtx() {
  thread_local const std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> context(ZSTD_createCCtx(), ZSTD_freeCCtx);
  return context.get();
}

}  // namespace

Status compress(Codec codec, int level, std::span<const uint8_t> raw, std::vector<uint8_t>* out) {
  switch (codec) {
    case Codec::kStored:
      out->assign(raw.begin(), raw.end());
      return {};
    case Codec::kZstd: {
      ZSTD_CCtx* cctx = threadCCtx();
      if (!cctx) return makeError(Code::kOutOfMemory, "cannot create a zstd context");
      ZSTD_CCtx_reset(cctx, ZSTD_reset_session_and_parameters);
      // Fixed parameters: the output depends only on the input, the level and the zstd version.
      ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level);
      ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, 1);
      ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 0);
      ZSTD_CCtx_setParameter(cctx, ZSTD_c_dictIDFlag, 0);
      // The frame goes to a scratch buffer of the worst-case size (not cleared first), and *out
      // gets exactly its bytes: a vector sized to the bound and shrunk would keep the bound's
      // capacity, and a writer holding many compressed blocks at once would hold their raw size.
      const size_t bound = ZSTD_compressBound(raw.size());
      std::unique_ptr<uint8_t[]> frame(new (std::nothrow) uint8_t[bound]);
      if (!frame) return makeError(Code::kOutOfMemory, "cannot allocate " + std::to_string(bound) + " bytes for a zstd frame");
      const size_t n = ZSTD_compress2(cctx, frame.get(), bound, raw.data(), raw.size());
      if (ZSTD_isError(n))
        return makeError(Code::kInvalidArgument, std::string("zstd: ") + ZSTD_getErrorName(n));
      out->assign(frame.get(), frame.get() + n);
      return {};
    }
  }
  return makeError(Code::kInvalidArgument, "unknown codec");
}

namespace {

// One decompression context per thread, reused for every block it decodes (a block is one frame,
// and ZSTD_decompressDCtx starts each frame afresh), rather than one created and freed per block.
ZSTD_DCtx* threadDCtx() {
  thread_local const std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> context(ZSTD_createDCtx(), ZSTD_freeDCtx);
  return context.get();
}

}  // namespace

Status decompress(Codec codec, std::span<const uint8_t> stored, std::span<uint8_t> out,
                  Code failCode) {
  switch (codec) {
    case Codec::kStored:
      if (stored.size() != out.size())
        return makeError(failCode, "stored size " + std::to_string(stored.size()) +
                                       " differs from raw size " + std::to_string(out.size()));
      if (!out.empty()) std::memcpy(out.data(), stored.data(), out.size());
      return {};
    case Codec::kZstd: {
      unsigned long long content = ZSTD_getFrameContentSize(stored.data(), stored.size());
      if (content == ZSTD_CONTENTSIZE_ERROR)
        return makeError(failCode, "not a zstd frame");
      if (content == ZSTD_CONTENTSIZE_UNKNOWN)
        return makeError(failCode, "zstd frame does not declare its content size");
      if (content != out.size())
        return makeError(failCode, "zstd frame declares " + std::to_string(content) +
                                       " bytes, expected " + std::to_string(out.size()));
      size_t frame = ZSTD_findFrameCompressedSize(stored.data(), stored.size());
      if (ZSTD_isError(frame) || frame != stored.size())
        return makeError(failCode, "stored bytes are not exactly one zstd frame");
      ZSTD_DCtx* dctx = threadDCtx();
      if (!dctx) return makeError(Code::kOutOfMemory, "cannot create a zstd context");
      size_t n = ZSTD_decompressDCtx(dctx, out.data(), out.size(), stored.data(), stored.size());
      if (ZSTD_isError(n)) return makeError(failCode, std::string("zstd: ") + ZSTD_getErrorName(n));
      if (n != out.size())
        return makeError(failCode, "zstd frame decoded to " + std::to_string(n) + " bytes, expected " +
                                       std::to_string(out.size()));
      return {};
    }
  }
  return makeError(failCode, "unknown codec " + std::to_string(unsigned(codec)));
}

Status decodeBlock(Codec codec, Filter filter, const BlockShape& shape, std::span<const uint8_t> stored,
                   std::span<uint8_t> out, Code failCode) {
  if (filter == Filter::kNone) return decompress(codec, stored, out, failCode);
  if (codec != Codec::kZstd) return makeError(failCode, "a filtered block must use codec zstd");
  const unsigned long long content = ZSTD_getFrameContentSize(stored.data(), stored.size());
  if (content == ZSTD_CONTENTSIZE_ERROR) return makeError(failCode, "not a zstd frame");
  if (content == ZSTD_CONTENTSIZE_UNKNOWN) return makeError(failCode, "zstd frame does not declare its content size");
  const uint64_t bound = filteredBound(filter, out.size());
  if (content > bound)
    return makeError(failCode, "zstd frame declares " + std::to_string(content) + " bytes, more than the " +
                                   std::to_string(bound) + " a " + filterName(filter) + " block of " +
                                   std::to_string(out.size()) + " bytes can hold");
  // Not zero-filled: zstd writes every byte before the filter reads it.
  std::unique_ptr<uint8_t[]> buffer(new (std::nothrow) uint8_t[size_t(content)]);
  if (!buffer && content) return makeError(Code::kOutOfMemory, "cannot allocate a filtered block");
  const std::span<uint8_t> filtered(buffer.get(), size_t(content));
  if (Status st = decompress(codec, stored, filtered, failCode); !st) return st;
  return unapplyFilter(filter, shape, filtered, out, failCode);
}

}  // namespace vff::detail
