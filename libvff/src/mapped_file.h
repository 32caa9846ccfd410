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
  Status open(const std::string& path);
  std::span<const uint8_t> bytes() const noexcept { return {data_, size_}; }

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  void* map_ = nullptr;
};

}  // namespace vff::detail
