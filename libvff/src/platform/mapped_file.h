// mapped_file.h - a read-only memory mapping of a whole file (private).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "vff/error.h"

namespace vff::detail {

class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();
  // `populate`: the caller reads the whole file at once (verifying every checksum), so the mapping
  // gets its page tables in one go (MAP_POPULATE) instead of a page fault per few pages.
  Status open(const std::string& path, bool populate = false);
  std::span<const uint8_t> bytes() const noexcept { return {data_, size_}; }

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  void* map_ = nullptr;
};

}  // namespace vff::detail
