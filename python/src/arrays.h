// arrays.h - the numpy arrays a batch answers into: allocated together, in huge pages.
#pragma once

#include <pybind11/numpy.h>

#include <cstddef>
#include <initializer_list>
#include <vector>

namespace vff::python {

// One block of memory for several new arrays, released when the last of them is. A batch of a
// million rays answers into tens of MiB that nothing has touched yet: in 4 KiB pages the first
// write to each page is a fault, taken by the threads that answer; the block asks the kernel for
// 2 MiB pages instead (madvise MADV_HUGEPAGE, where transparent huge pages are "always" or
// "madvise"), and falls back to plain pages where it cannot. The last large blocks released are
// kept (up to two, 1 GiB) for the next batches of about their size.
class ArrayBlock {
 public:
  // Room for arrays of these sizes in bytes, each 64-byte aligned.
  explicit ArrayBlock(std::initializer_list<size_t> bytes);
  // Array `index` of the block as a numpy array of `shape` (C order), sharing the block.
  template <class T>
  pybind11::array_t<T> array(size_t index, std::vector<pybind11::ssize_t> shape) const {
    return pybind11::array_t<T>(std::move(shape), static_cast<T*>(data(index)), owner_);
  }

 private:
  void* data(size_t index) const;
  std::vector<size_t> offsets_;
  void* base_ = nullptr;
  pybind11::capsule owner_;
};

}  // namespace vff::python
