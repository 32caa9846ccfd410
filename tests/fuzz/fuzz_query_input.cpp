// Fuzz target: vff-query's input readers (tools/vff-query, library vff_query_input). The first byte
// picks the reader, the rest is the input:
//   0  ray lines (parseRayLines) with the command line's bounds 0..inf;
//   1  ray lines with bounds 0.25..8 (the command line refuses tmin > tmax before reading rays);
//   2  a .npy matrix (readNpyMatrix).
// Ray lines: every ray read passes rayIsGood (a bad one is reported instead); a reported line and
// column lie inside the input; their messages are printable ASCII (bytes outside it are shown as
// \xHH). .npy: a matrix read has exactly its data bytes, checkRay and rayIsGood agree on each row
// of a matrix of 6 or 8 columns, and npyMatrixBytes of what was read reads back equal.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "npy.h"
#include "rays.h"

namespace {

using namespace vff::query_tool;

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "query_input: %s\n%s\n", what, detail.c_str());
  std::abort();
}

// `printable`: rays.h promises that messages about ray lines show the input's bytes outside
// printable ASCII as \xHH. (readNpyMatrix's messages quote header values as they are: see
// regressions/query_input/crash-b949ec845e72e6fca9c968ce929f446ef916e293, a BEL byte in 'descr'.)
void checkMessage(const std::string& m, std::string_view input, bool printable) {
  if (m.empty()) fail("an empty message", m);
  for (char c : m)
    if (printable && (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f))
      fail("a message with a byte outside printable ASCII", m);
  // (A message may quote the input, which may hold those words itself.)
  if (m.find("internal error") != std::string::npos && input.find("internal error") == std::string_view::npos)
    fail("an internal error", m);
}

void rayLines(std::string_view text, float tmin, float tmax) {
  const ParsedRays parsed = parseRayLines(text, tmin, tmax);
  for (const vff::Ray& r : parsed.rays)
    if (!rayIsGood(r) || checkRay(r)) fail("a bad ray was read", std::string(text.substr(0, 200)));
  if (!parsed.error) return;
  const LineError& e = *parsed.error;
  uint64_t lines = 1;
  for (char c : text) lines += c == '\n';
  if (e.line < 1 || e.line > lines) fail("the reported line is outside the input", e.message);
  if (e.column < 1) fail("the reported column is not 1-based", e.message);
  checkMessage(e.message, text, true);
}

void npy(std::span<const uint8_t> bytes) {
  NpyMatrix m;
  if (std::optional<std::string> e = readNpyMatrix(bytes, &m)) {
    checkMessage(*e, {reinterpret_cast<const char*>(bytes.data()), bytes.size()}, false);
    return;
  }
  if (m.data.size() != m.rows * m.cols * 4) fail("a matrix of the wrong size", "");
  std::vector<float> values(m.rows * m.cols);
  if (!values.empty()) std::memcpy(values.data(), m.data.data(), m.data.size());
  // (Rays only of 6 or 8 columns: vff-query refuses other shapes after reading.)
  for (uint64_t r = 0; r < m.rows && (m.cols == 6 || m.cols == 8); ++r) {
    const float* v = values.data() + r * m.cols;
    vff::Ray ray{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, 0.0f, std::numeric_limits<float>::infinity()};
    if (m.cols == 8) ray.tmin = v[6], ray.tmax = v[7];
    const auto bad = checkRay(ray);
    if (bad.has_value() == rayIsGood(ray)) fail("checkRay and rayIsGood disagree", "");
    if (bad && (bad->second < 0 || bad->second > 7)) fail("checkRay names no number of the ray", bad->first);
  }
  const std::vector<uint8_t> again = npyMatrixBytes(values, m.rows, m.cols);
  NpyMatrix back;
  if (std::optional<std::string> e = readNpyMatrix(again, &back)) fail("npyMatrixBytes is not read back", *e);
  if (back.rows != m.rows || back.cols != m.cols || back.data.size() != m.data.size() ||
      (!m.data.empty() && std::memcmp(back.data.data(), m.data.data(), m.data.size()) != 0))
    fail("npyMatrixBytes reads back different", "");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  switch (data[0] % 3) {
    case 0: rayLines(text, 0.0f, std::numeric_limits<float>::infinity()); break;
    case 1: rayLines(text, 0.25f, 8.0f); break;
    default: npy({data + 1, size - 1}); break;
  }
  return 0;
}
