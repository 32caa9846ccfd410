// huge_pages.h - backing large read-mostly tables with 2 MiB pages (internal).
#pragma once

#include <cstddef>

namespace vff::detail {

// Asks the OS to back the whole 2 MiB pages within [p, p + n) with huge pages at once (Linux:
// madvise(MADV_COLLAPSE), kernel 6.1 and later, on private anonymous memory such as a
// std::vector's). A hint: the bytes and their owner stay as they were; where the OS declines
// (file mappings, older kernels, transparent huge pages off, no free huge page) nothing changes.
// Returns the bytes now backed by huge pages (0 where it declined).
//
// FieldQuery reads its maps at random: with 4 KiB pages a field of 16.5 MiB spans more pages than
// the CPU's TLB holds (Embree, its baseline, takes huge pages on Linux by default).
size_t adviseHugePages(const void* p, size_t n) noexcept;

}  // namespace vff::detail
