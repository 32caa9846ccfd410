// npy.h - the NumPy .npy files vff-query reads and writes: little-endian float32 matrices, C order.
//
//   vff::query_tool::NpyMatrix m;
//   if (auto e = readNpyMatrix(bytes, "rays.npy", &m)) ...;        // (N, C) '<f4'
//   std::vector<uint8_t> out = npyMatrixBytes(values, rows, cols);  // format 1.0 header + data
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vff::query_tool {

struct NpyMatrix {
  uint64_t rows = 0;
  uint64_t cols = 0;
  std::span<const uint8_t> data;  // rows * cols little-endian float32, a view into the input bytes
};

// Parses a .npy file of format 1.0, 2.0 or 3.0 holding a 2-D '<f4' array in C order. On failure
// returns the problem as one sentence ("expected dtype '<f4', found '<f8'"); nothing on success.
std::optional<std::string> readNpyMatrix(std::span<const uint8_t> bytes, NpyMatrix* out);

// A .npy file (format 1.0) holding `values` as a (rows, cols) '<f4' array.
std::vector<uint8_t> npyMatrixBytes(std::span<const float> values, uint64_t rows, uint64_t cols);
// The header alone of that file (its size a multiple of 64): the data follows it.
std::vector<uint8_t> npyMatrixHeader(uint64_t rows, uint64_t cols);

}  // namespace vff::query_tool
