// gen_bytes.h - the conformance generator's byte helpers: problems found, hashes, little-endian
// fields and zstd frames (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vff::gen {

using Bytes = std::vector<uint8_t>;

// The zstd level of every zstd vector (recorded in manifest.json).
inline constexpr int kZstdLevel = 19;

// Reports a disagreement and carries on (the generator exits 1 at the end when there was any).
void fail(const std::string& what);
// The number of fail() calls so far.
int failureCount();
// Reports an error the generator cannot continue after, and exits 1.
[[noreturn]] void die(const std::string& what);

// 16 lowercase hex digits.
std::string hex64(uint64_t v);
// XXH3-64, the format's checksum.
uint64_t xxh(std::span<const uint8_t> b);
uint64_t alignUp(uint64_t v, uint64_t a);

// Little-endian fields at byte offset o (bounds-checked: a bad offset throws).
uint16_t ld16(const Bytes& b, uint64_t o);
uint32_t ld32(const Bytes& b, uint64_t o);
uint64_t ld64(const Bytes& b, uint64_t o);
void st16(Bytes& b, uint64_t o, uint16_t v);
void st32(Bytes& b, uint64_t o, uint32_t v);
void st64(Bytes& b, uint64_t o, uint64_t v);

// [off, off + size) lies within [0, limit), without overflow.
bool inRange(uint64_t off, uint64_t size, uint64_t limit);

// A zstd frame of `raw` at kZstdLevel with its content size and no checksum or dictionary ID.
Bytes zstdFrame(std::span<const uint8_t> raw);
// The content of a zstd frame that declares its size (dies on anything else).
Bytes zstdContent(std::span<const uint8_t> frame);

}  // namespace vff::gen
