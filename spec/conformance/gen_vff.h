// gen_vff.h - a .vff held in memory and edited by hand: how the conformance generator makes each
// invalid vector (one fault, the checksums it did not mean to break re-sealed) and the valid
// vectors with an unknown section or feature bit (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <xxhash.h>

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "gen_bytes.h"
#include "vff/vff.h"

namespace vff::gen {

// Offsets follow spec/format.md: header (64 B) with the section table offset at 40, the count at 48
// and the header checksum at 56; 64-byte table entries (tag, flags, offset @8, storedSize @16,
// rawSize @24, codec @32, sectionVersion @34, checksum @40); plane sections start with a 32-byte
// header (mapCount, mapBytes, mapsPerBlock, blockCount) and 32-byte block entries (offset relative
// to the section @0, storedSize @8, rawSize @16, codec @20, filter @21, checksum @24).
struct Vff {
  Bytes b;

  uint64_t tableOffset() const { return ld64(b, 40); }
  uint32_t count() const { return ld32(b, 48); }
  uint64_t entryAt(uint32_t i) const { return tableOffset() + uint64_t(i) * kSectionEntrySize; }
  int indexOf(uint32_t tag) const {
    for (uint32_t i = 0; i < count(); ++i)
      if (ld32(b, entryAt(i)) == tag) return int(i);
    return -1;
  }
  uint64_t entry(uint32_t tag) const {
    const int i = indexOf(tag);
    if (i < 0) die("mutation needs a '" + sectionTagName(tag) + "' section");
    return entryAt(uint32_t(i));
  }
  uint64_t sec(uint32_t tag) const { return ld64(b, entry(tag) + 8); }
  uint64_t secSize(uint32_t tag) const { return ld64(b, entry(tag) + 16); }
  uint64_t blockEntry(uint32_t tag, uint32_t i) const {
    return sec(tag) + kPlaneHeaderSize + uint64_t(i) * kBlockEntrySize;
  }
  uint64_t blockRel(uint32_t tag, uint32_t i) const { return ld64(b, blockEntry(tag, i)); }
  uint64_t block(uint32_t tag, uint32_t i) const { return sec(tag) + blockRel(tag, i); }
  uint64_t blockSize(uint32_t tag, uint32_t i) const { return ld64(b, blockEntry(tag, i) + 8); }
  uint32_t blockCount(uint32_t tag) const { return ld32(b, sec(tag) + 12); }

  void setFileSize() { st64(b, 16, b.size()); }

  // Re-computes every block checksum that can be computed (blocks inside their section).
  void sealBlocks() {
    for (uint32_t i = 0; i < count() && inRange(entryAt(i), kSectionEntrySize, b.size()); ++i) {
      const uint64_t e = entryAt(i);
      const uint32_t tag = ld32(b, e);
      if (tag != kTagDistance && tag != kTagNormal) continue;
      const uint64_t off = ld64(b, e + 8), size = ld64(b, e + 16);
      if (!inRange(off, size, b.size()) || size < kPlaneHeaderSize) continue;
      const uint32_t n = ld32(b, off + 12);
      for (uint32_t k = 0; k < n && kPlaneHeaderSize + uint64_t(k + 1) * kBlockEntrySize <= size; ++k) {
        const uint64_t be = off + kPlaneHeaderSize + uint64_t(k) * kBlockEntrySize;
        const uint64_t rel = ld64(b, be), stored = ld64(b, be + 8);
        if (inRange(rel, stored, size)) st64(b, be + 24, xxh(std::span(b).subspan(off + rel, stored)));
      }
    }
  }
  void sealSections() {
    for (uint32_t i = 0; i < count() && inRange(entryAt(i), kSectionEntrySize, b.size()); ++i) {
      const uint64_t e = entryAt(i);
      const uint64_t off = ld64(b, e + 8), size = ld64(b, e + 16);
      if (inRange(off, size, b.size())) st64(b, e + 40, xxh(std::span(b).subspan(off, size)));
    }
  }
  void sealHeader() {
    const uint64_t t = tableOffset(), n = uint64_t(count()) * kSectionEntrySize;
    if (b.size() < kHeaderSize || n > (64u << 10) || !inRange(t, n, b.size())) return;
    XXH3_state_t* s = XXH3_createState();
    XXH3_64bits_reset(s);
    XXH3_64bits_update(s, b.data(), 56);
    XXH3_64bits_update(s, b.data() + t, n);
    st64(b, 56, XXH3_64bits_digest(s));
    XXH3_freeState(s);
  }
  void sealAll() {
    sealBlocks();
    sealSections();
    sealHeader();
  }

  // Appends a section after the last one (at the next 4096-byte boundary) with a new table entry.
  void appendSection(uint32_t tag, uint32_t flags, std::span<const uint8_t> data, uint16_t codec = 0,
                     uint64_t rawSize = ~uint64_t{0}) {
    const uint64_t end = tableOffset() + uint64_t(count() + 1) * kSectionEntrySize;
    for (uint32_t i = 0; i < count(); ++i)
      if (ld64(b, entryAt(i) + 8) < end) die("no room in the section table");
    const uint64_t off = alignUp(b.size(), kSectionAlignment);
    b.resize(off);
    b.insert(b.end(), data.begin(), data.end());
    const uint64_t e = entryAt(count());
    std::fill(b.begin() + std::ptrdiff_t(e), b.begin() + std::ptrdiff_t(e + kSectionEntrySize), 0);
    st32(b, e, tag);
    st32(b, e + 4, flags);
    st64(b, e + 8, off);
    st64(b, e + 16, data.size());
    st64(b, e + 24, rawSize == ~uint64_t{0} ? data.size() : rawSize);
    st16(b, e + 32, codec);
    st16(b, e + 34, 1);
    st32(b, 48, count() + 1);
    setFileSize();
    sealAll();
  }

  // Removes a section's entry and bytes (the file is cut after the last remaining section).
  void removeSection(uint32_t tag) {
    const int idx = indexOf(tag);
    if (idx < 0) die("no section to remove");
    const uint64_t off = sec(tag), size = secSize(tag);
    std::fill(b.begin() + std::ptrdiff_t(off), b.begin() + std::ptrdiff_t(off + size), 0);
    const uint32_t n = count();
    for (uint32_t i = uint32_t(idx); i + 1 < n; ++i)
      std::copy_n(b.begin() + std::ptrdiff_t(entryAt(i + 1)), kSectionEntrySize,
                  b.begin() + std::ptrdiff_t(entryAt(i)));
    std::fill_n(b.begin() + std::ptrdiff_t(entryAt(n - 1)), kSectionEntrySize, 0);
    st32(b, 48, n - 1);
    uint64_t end = 0;
    for (uint32_t i = 0; i + 1 < n; ++i) end = std::max(end, ld64(b, entryAt(i) + 8) + ld64(b, entryAt(i) + 16));
    b.resize(end);
    setFileSize();
    sealAll();
  }

  // Replaces the stored bytes of the last block of plane `tag`, which must be the file's last
  // section: the block, section and file sizes follow, and everything is re-sealed.
  void replaceLastBlock(uint32_t tag, std::span<const uint8_t> stored) {
    const uint64_t e = entry(tag), off = sec(tag);
    if (off + secSize(tag) != b.size()) die("replaceLastBlock: '" + sectionTagName(tag) + "' is not the last section");
    const uint32_t last = blockCount(tag) - 1;
    const uint64_t rel = blockRel(tag, last);
    b.resize(off + rel);
    b.insert(b.end(), stored.begin(), stored.end());
    st64(b, blockEntry(tag, last) + 8, stored.size());
    st64(b, e + 16, rel + stored.size());
    st64(b, e + 24, rel + stored.size());
    setFileSize();
    sealAll();
  }

  // Replaces the stored bytes of section `tag`, which must be the file's last section, with `stored`
  // and its rawSize with `rawSize`: the file's size follows, and everything is re-sealed.
  void replaceLastSection(uint32_t tag, std::span<const uint8_t> stored, uint64_t rawSize) {
    const uint64_t e = entry(tag), off = sec(tag);
    if (off + secSize(tag) != b.size()) die("replaceLastSection: '" + sectionTagName(tag) + "' is not the last section");
    b.resize(off);
    b.insert(b.end(), stored.begin(), stored.end());
    st64(b, e + 16, stored.size());
    st64(b, e + 24, rawSize);
    setFileSize();
    sealAll();
  }

  // Replaces a stored section's bytes (it must keep fitting before the next section).
  void replaceStored(uint32_t tag, std::string_view text) {
    const uint64_t e = entry(tag), off = sec(tag), old = secSize(tag);
    std::fill(b.begin() + std::ptrdiff_t(off), b.begin() + std::ptrdiff_t(off + old), 0);
    if (off + text.size() > b.size()) b.resize(off + text.size());
    std::copy(text.begin(), text.end(), b.begin() + std::ptrdiff_t(off));
    st64(b, e + 16, text.size());
    st64(b, e + 24, text.size());
    setFileSize();
    sealAll();
  }
};

}  // namespace vff::gen
