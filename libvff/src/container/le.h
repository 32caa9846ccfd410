// le.h - little-endian loads and stores, and overflow-safe range checks (private).
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

namespace vff::detail {

template <class T>
inline T byteswapIfBig(T v) noexcept {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    T r;
    auto* s = reinterpret_cast<const unsigned char*>(&v);
    auto* d = reinterpret_cast<unsigned char*>(&r);
    for (size_t i = 0; i < sizeof(T); ++i) d[i] = s[sizeof(T) - 1 - i];
    return r;
  }
  return v;
}

template <class T>
inline T load(const uint8_t* p) noexcept {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return byteswapIfBig(v);
}
template <class T>
inline void store(uint8_t* p, T v) noexcept {
  v = byteswapIfBig(v);
  std::memcpy(p, &v, sizeof(T));
}
inline uint16_t loadU16(const uint8_t* p) noexcept { return load<uint16_t>(p); }
inline uint32_t loadU32(const uint8_t* p) noexcept { return load<uint32_t>(p); }
inline uint64_t loadU64(const uint8_t* p) noexcept { return load<uint64_t>(p); }
inline float loadF32(const uint8_t* p) noexcept { return std::bit_cast<float>(load<uint32_t>(p)); }
inline void storeF32(uint8_t* p, float v) noexcept { store<uint32_t>(p, std::bit_cast<uint32_t>(v)); }

// True when [offset, offset + size) lies inside [0, limit), without overflow.
inline bool inRange(uint64_t offset, uint64_t size, uint64_t limit) noexcept {
  return offset <= limit && size <= limit - offset;
}

inline uint64_t alignUp(uint64_t v, uint64_t a) noexcept { return (v + a - 1) / a * a; }

// a * b, or false when it overflows 64 bits.
inline bool mulOk(uint64_t a, uint64_t b, uint64_t* out) noexcept {
  return !__builtin_mul_overflow(a, b, out);
}

}  // namespace vff::detail
