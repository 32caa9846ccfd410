// arrays.cpp - ArrayBlock: numpy arrays over one anonymous mapping, in huge pages where possible.
#include "arrays.h"

#include <sys/mman.h>

#include <mutex>
#include <new>
#include <vector>

namespace vff::python {

namespace {

constexpr size_t kHugePage = size_t{2} << 20;

struct Mapping {
  void* base;
  size_t size;  // 0: from operator new (a small block)
};

// Large mappings released lately, kept for the next batches: a loop over batches of one size then
// writes into memory already backed, as glibc's malloc reuses what is freed (numpy's arrays come
// from it) rather than faulting in and zeroing fresh pages each call.
constexpr size_t kCacheEntries = 2;
constexpr size_t kCacheBytes = size_t{1} << 30;
std::mutex cacheLock;
std::vector<Mapping> cache;

void release(Mapping m) {
  {
    std::lock_guard<std::mutex> lock(cacheLock);
    size_t held = 0;
    for (const Mapping& c : cache) held += c.size;
    if (cache.size() < kCacheEntries && held + m.size <= kCacheBytes) {
      cache.push_back(m);
      return;
    }
  }
  ::munmap(m.base, m.size);
}

// A cached mapping of `size` bytes, or of up to twice that (more would hold memory for nothing).
void* reuse(size_t size, size_t* got) {
  std::lock_guard<std::mutex> lock(cacheLock);
  for (size_t i = 0; i < cache.size(); ++i) {
    if (cache[i].size >= size && cache[i].size <= 2 * size) {
      void* p = cache[i].base;
      *got = cache[i].size;
      cache.erase(cache.begin() + ptrdiff_t(i));
      return p;
    }
  }
  return nullptr;
}

}  // namespace

ArrayBlock::ArrayBlock(std::initializer_list<size_t> bytes) {
  size_t total = 0;
  for (size_t b : bytes) {
    offsets_.push_back(total);
    total += (b + 63) / 64 * 64;
  }
  if (total < kHugePage) {  // (small: plain memory)
    base_ = ::operator new(total ? total : 64, std::align_val_t{64});
    auto* m = new Mapping{base_, 0};
    owner_ = pybind11::capsule(m, [](void* q) {
      auto* mapping = static_cast<Mapping*>(q);
      ::operator delete(mapping->base, std::align_val_t{64});
      delete mapping;
    });
    return;
  }
  // Whole huge pages, and a huge page more to align the start to one.
  size_t size = (total + kHugePage - 1) / kHugePage * kHugePage + kHugePage;
  void* p = reuse(size, &size);
  const bool fresh = p == nullptr;
  if (fresh) {
    p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
  }
  auto* m = new Mapping{p, size};
  owner_ = pybind11::capsule(m, [](void* q) {
    auto* mapping = static_cast<Mapping*>(q);
    release(*mapping);
    delete mapping;
  });
  const uintptr_t start = (reinterpret_cast<uintptr_t>(p) + kHugePage - 1) / kHugePage * kHugePage;
  base_ = reinterpret_cast<void*>(start);
  if (fresh) (void)::madvise(base_, size - (start - reinterpret_cast<uintptr_t>(p)), MADV_HUGEPAGE);
}

void* ArrayBlock::data(size_t index) const { return static_cast<char*>(base_) + offsets_[index]; }

}  // namespace vff::python
