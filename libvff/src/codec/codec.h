// codec.h - checksums and block codecs (private).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/format.h"
#include "codec/filter.h"

namespace vff::detail {

uint64_t xxh3(std::span<const uint8_t> bytes) noexcept;

// Streaming XXH3-64 over several pieces.
class Xxh3Stream {
 public:
  Xxh3Stream();
  ~Xxh3Stream();
  Xxh3Stream(const Xxh3Stream&) = delete;
  Xxh3Stream& operator=(const Xxh3Stream&) = delete;
  void update(std::span<const uint8_t> bytes) noexcept;
  uint64_t digest() const noexcept;

 private:
  void* state_;
};

// Compresses `raw` with the codec into `out` (replacing its contents). kStored copies.
Status compress(Codec codec, int level, std::span<const uint8_t> raw, std::vector<uint8_t>* out);

// Decodes exactly out.size() bytes. The stored bytes must be exactly one frame whose declared
// content size equals out.size(); anything else is an error with code `failCode`.
Status decompress(Codec codec, std::span<const uint8_t> stored, std::span<uint8_t> out,
                  Code failCode);

// Decodes a plane block's stored bytes (its codec, then its filter) into exactly out.size() bytes
// (the block's rawSize). A filtered frame may declare at most filteredBound() bytes, so a hostile
// one cannot make the decoder allocate more than that.
Status decodeBlock(Codec codec, Filter filter, const BlockShape& shape, std::span<const uint8_t> stored,
                   std::span<uint8_t> out, Code failCode);

}  // namespace vff::detail
