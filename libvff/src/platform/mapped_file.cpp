#include "platform/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vff::detail {

MappedFile::~MappedFile() {
  if (map_) munmap(map_, size_);
}

Status MappedFile::open(const std::string& path, bool populate) {
  // O_NONBLOCK: opening a FIFO (or a device) for reading would otherwise wait for a writer before
  // the check below could refuse it; on a regular file the flag changes nothing.
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  struct stat st {};
  if (fstat(fd, &st) != 0) {
    int e = errno;
    ::close(fd);
    return makeError(Code::kIoRead, path + ": " + std::strerror(e));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return makeError(Code::kIoOpen, path + ": not a regular file");
  }
  size_ = size_t(st.st_size);
  if (size_ > 0) {
    void* m = mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | (populate ? MAP_POPULATE : 0), fd, 0);
    if (m == MAP_FAILED) {
      int e = errno;
      ::close(fd);
      size_ = 0;
      return makeError(Code::kIoRead, path + ": mmap: " + std::strerror(e));
    }
    map_ = m;
    data_ = static_cast<const uint8_t*>(m);
  }
  ::close(fd);
  return {};
}

}  // namespace vff::detail
