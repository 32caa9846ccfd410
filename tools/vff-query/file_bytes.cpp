// file_bytes.cpp - FileBytes (file_bytes.h).
#include "file_bytes.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace vff::query_tool {

namespace {

constexpr size_t kHugePage = size_t{2} << 20;

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

FileBytes::FileBytes(FileBytes&& o) noexcept
    : data_(std::exchange(o.data_, nullptr)),
      size_(std::exchange(o.size_, 0)),
      map_(std::exchange(o.map_, nullptr)),
      mapSize_(std::exchange(o.mapSize_, 0)) {}

FileBytes& FileBytes::operator=(FileBytes&& o) noexcept {
  if (this != &o) {
    release();
    data_ = std::exchange(o.data_, nullptr);
    size_ = std::exchange(o.size_, 0);
    map_ = std::exchange(o.map_, nullptr);
    mapSize_ = std::exchange(o.mapSize_, 0);
  }
  return *this;
}

FileBytes::~FileBytes() { release(); }

void FileBytes::release() noexcept {
  if (map_) ::munmap(map_, mapSize_);
  map_ = nullptr, data_ = nullptr, size_ = 0, mapSize_ = 0;
}

Result<FileBytes> FileBytes::read(const std::string& path) {
  // O_NONBLOCK: a FIFO would otherwise block the open until a writer came, before read(fd) below
  // could refuse it as not a regular file; a regular file's reads ignore the flag.
  const Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (fd.get() < 0) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  return read(fd.get(), path);
}

Result<FileBytes> FileBytes::read(int fd, const std::string& path) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return makeError(Code::kIoRead, path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) return makeError(Code::kIoOpen, path + ": not a regular file");
  FileBytes b;
  b.size_ = size_t(st.st_size);
  if (b.size_ == 0) return b;
  // Room to align the start up to a huge page: only whole aligned 2 MiB ranges become huge pages.
  b.mapSize_ = b.size_ + kHugePage;
  void* m = ::mmap(nullptr, b.mapSize_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) {
    b.mapSize_ = 0, b.size_ = 0;
    return makeError(Code::kOutOfMemory, path + ": no memory for its " + std::to_string(st.st_size) + " bytes");
  }
  b.map_ = m;
  const uintptr_t at = (reinterpret_cast<uintptr_t>(m) + kHugePage - 1) & ~uintptr_t(kHugePage - 1);
  b.data_ = reinterpret_cast<uint8_t*>(at);
#ifdef MADV_HUGEPAGE
  (void)::madvise(b.data_, size_t(static_cast<uint8_t*>(m) + b.mapSize_ - b.data_), MADV_HUGEPAGE);  // (a hint)
#endif
  for (size_t done = 0; done < b.size_;) {
    const ssize_t n = ::read(fd, b.data_ + done, b.size_ - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return makeError(Code::kIoRead, path + ": " + std::strerror(errno));
    if (n == 0) return makeError(Code::kIoRead, path + ": the file ended at byte " + std::to_string(done) +
                                                    " of the " + std::to_string(b.size_) + " it had at open");
    done += size_t(n);
  }
  return b;
}

}  // namespace vff::query_tool
