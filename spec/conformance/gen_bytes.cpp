// gen_bytes.cpp - the conformance generator's byte helpers (gen_bytes.h).
#include "gen_bytes.h"

#include <xxhash.h>
#include <zstd.h>

#include <cstdio>
#include <cstdlib>

namespace vff::gen {

namespace {
int gFailures = 0;
}  // namespace

void fail(const std::string& what) {
  std::fprintf(stderr, "vff-conformance-gen: error: %s\n", what.c_str());
  ++gFailures;
}

int failureCount() {
  return gFailures;
}

void die(const std::string& what) {
  std::fprintf(stderr, "vff-conformance-gen: error: %s\n", what.c_str());
  std::exit(1);
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

uint64_t xxh(std::span<const uint8_t> b) {
  return XXH3_64bits(b.data(), b.size());
}

uint64_t alignUp(uint64_t v, uint64_t a) {
  return (v + a - 1) / a * a;
}

uint16_t ld16(const Bytes& b, uint64_t o) {
  return uint16_t(b.at(o) | b.at(o + 1) << 8);
}
uint32_t ld32(const Bytes& b, uint64_t o) {
  return uint32_t(ld16(b, o)) | uint32_t(ld16(b, o + 2)) << 16;
}
uint64_t ld64(const Bytes& b, uint64_t o) {
  return uint64_t(ld32(b, o)) | uint64_t(ld32(b, o + 4)) << 32;
}
void st16(Bytes& b, uint64_t o, uint16_t v) {
  b.at(o) = uint8_t(v);
  b.at(o + 1) = uint8_t(v >> 8);
}
void st32(Bytes& b, uint64_t o, uint32_t v) {
  st16(b, o, uint16_t(v));
  st16(b, o + 2, uint16_t(v >> 16));
}
void st64(Bytes& b, uint64_t o, uint64_t v) {
  st32(b, o, uint32_t(v));
  st32(b, o + 4, uint32_t(v >> 32));
}

bool inRange(uint64_t off, uint64_t size, uint64_t limit) {
  return off <= limit && size <= limit - off;
}

Bytes zstdFrame(std::span<const uint8_t> raw) {
  Bytes out(ZSTD_compressBound(raw.size()));
  ZSTD_CCtx* c = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, kZstdLevel);
  ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, 1);
  ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 0);
  ZSTD_CCtx_setParameter(c, ZSTD_c_dictIDFlag, 0);
  const size_t n = ZSTD_compress2(c, out.data(), out.size(), raw.data(), raw.size());
  ZSTD_freeCCtx(c);
  if (ZSTD_isError(n)) die("zstd compression failed");
  out.resize(n);
  return out;
}

Bytes zstdContent(std::span<const uint8_t> frame) {
  const unsigned long long n = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (n == ZSTD_CONTENTSIZE_ERROR || n == ZSTD_CONTENTSIZE_UNKNOWN || n > (1u << 24)) die("not a sized zstd frame");
  Bytes out(n);
  if (ZSTD_decompress(out.data(), out.size(), frame.data(), frame.size()) != n) die("zstd frame does not decode");
  return out;
}

}  // namespace vff::gen
