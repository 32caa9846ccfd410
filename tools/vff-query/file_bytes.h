// file_bytes.h - a regular file read whole into memory of its own, in 2 MiB pages where the system
// gives them (Linux's transparent huge pages).
//
//   auto bytes = vff::query_tool::FileBytes::read("bunny.vff");   // Result<FileBytes>
//   vff::File::openMemory(bytes->bytes());                        // borrows them
//
// Why not a mapping of the file: vff-query reads all of its inputs whole (the field's checksums
// are verified at open, and every ray is read), and the field's lookups then touch its pages at
// random. A file mapping is faulted in and held in the TLB 4 KiB at a time; a copy in huge pages
// is faulted in a few times per file and held by a few TLB entries. Where the system has no huge
// pages the copy is plain anonymous memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "vff/error.h"

namespace vff::query_tool {

class FileBytes {
 public:
  // kIoOpen when the path cannot be opened or is not a regular file; kIoRead when reading fails;
  // kOutOfMemory when no memory of the file's size can be had. The messages name the path.
  static Result<FileBytes> read(const std::string& path);
  // The same from a descriptor the caller opened and keeps (read from its current offset, which
  // must be the start); `path` only names the file in messages.
  static Result<FileBytes> read(int fd, const std::string& path);

  FileBytes() = default;
  FileBytes(FileBytes&& o) noexcept;
  FileBytes& operator=(FileBytes&& o) noexcept;
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  ~FileBytes();

  std::span<const uint8_t> bytes() const noexcept { return {data_, size_}; }

 private:
  void release() noexcept;
  uint8_t* data_ = nullptr;   // within the mapping
  size_t size_ = 0;           // the file's bytes
  void* map_ = nullptr;       // the anonymous mapping (aligned up inside for huge pages)
  size_t mapSize_ = 0;
};

}  // namespace vff::query_tool
