// npy.cpp - reading and writing the .npy files of npy.h (the format of numpy.lib.format).
#include "npy.h"
#include "rays.h"

#include <bit>
#include <cstring>
#include <string_view>

namespace vff::query_tool {

namespace {

static_assert(std::endian::native == std::endian::little, "the .npy data is read in place as '<f4'");

constexpr uint8_t kNpyMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};

// The text after `key` in the header dictionary, up to the next ',' or '}' (a tuple kept whole).
std::optional<std::string_view> dictValue(std::string_view header, std::string_view key) {
  const size_t k = header.find(key);
  if (k == std::string_view::npos) return std::nullopt;
  size_t p = header.find(':', k + key.size());
  if (p == std::string_view::npos) return std::nullopt;
  ++p;
  while (p < header.size() && header[p] == ' ') ++p;
  size_t end = p;
  if (end < header.size() && header[end] == '(') {
    end = header.find(')', end);
    if (end == std::string_view::npos) return std::nullopt;
    ++end;
  } else {
    while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
  }
  std::string_view v = header.substr(p, end - p);
  while (!v.empty() && v.back() == ' ') v.remove_suffix(1);
  return v;
}

// "(1000, 6)" -> {1000, 6}; nothing unless it is a tuple of exactly two integers.
std::optional<std::pair<uint64_t, uint64_t>> parseShape(std::string_view t) {
  if (t.size() < 2 || t.front() != '(' || t.back() != ')') return std::nullopt;
  t = t.substr(1, t.size() - 2);
  uint64_t dims[3] = {};
  int n = 0;
  size_t i = 0;
  while (i < t.size()) {
    while (i < t.size() && t[i] == ' ') ++i;
    if (i == t.size()) break;
    if (t[i] < '0' || t[i] > '9' || n == 3) return std::nullopt;
    uint64_t v = 0;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') {
      if (v > (uint64_t{1} << 40)) return std::nullopt;
      v = v * 10 + uint64_t(t[i++] - '0');
    }
    dims[n++] = v;
    while (i < t.size() && t[i] == ' ') ++i;
    if (i < t.size() && t[i] == ',') ++i;
  }
  if (n != 2) return std::nullopt;
  return std::pair{dims[0], dims[1]};
}

// Whether the header is the dict literal numpy writes: '{', items 'key': value separated by commas
// (a comma inside a tuple belongs to it; one may trail), '}', then blanks and a newline; each of the
// keys descr, fortran_order and shape exactly once and no other. The values are checked apart.
std::optional<std::string> checkDict(std::string_view h) {
  while (!h.empty() && (h.back() == ' ' || h.back() == '\n')) h.remove_suffix(1);
  if (h.size() < 2 || h.front() != '{' || h.back() != '}') return "is not a dict literal {...}";
  const std::string_view inner = h.substr(1, h.size() - 2);
  bool seen[3] = {};
  const std::string_view keys[3] = {"'descr'", "'fortran_order'", "'shape'"};
  size_t start = 0;
  int depth = 0;
  for (size_t i = 0; i <= inner.size(); ++i) {
    const char c = i < inner.size() ? inner[i] : ',';
    if (c == '(') ++depth;
    if (c == ')' && --depth < 0) return "has an unbalanced ')'";
    if (c != ',' || depth > 0) continue;
    std::string_view item = inner.substr(start, i - start);
    start = i + 1;
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    if (item.empty()) {
      if (i >= inner.size() - 1 || inner.substr(i + 1).find_first_not_of(' ') == std::string_view::npos) continue;
      return "has an empty item";  // (only the last, a trailing comma, may be empty)
    }
    const size_t colon = item.find(':');
    if (colon == std::string_view::npos) return "has an item without ':'";
    std::string_view key = item.substr(0, colon);
    while (!key.empty() && key.back() == ' ') key.remove_suffix(1);
    int which = -1;
    for (int k = 0; k < 3; ++k)
      if (key == keys[k]) which = k;
    if (which < 0) return "has a key other than 'descr', 'fortran_order' and 'shape'";
    if (seen[which]) return "names " + std::string(key) + " twice";
    seen[which] = true;
  }
  if (depth != 0) return "has an unbalanced '('";
  if (!seen[0] || !seen[1] || !seen[2]) return "lacks descr, fortran_order or shape";
  return std::nullopt;
}

}  // namespace

std::optional<std::string> readNpyMatrix(std::span<const uint8_t> bytes, NpyMatrix* out) {
  if (bytes.size() < 10 || std::memcmp(bytes.data(), kNpyMagic, 6) != 0) return "not a .npy file (no \\x93NUMPY magic)";
  const uint8_t major = bytes[6];
  size_t headerLen = 0, start = 0;
  if (major == 1) {
    headerLen = size_t(bytes[8]) | size_t(bytes[9]) << 8;
    start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) return "the .npy header is truncated";
    headerLen = size_t(bytes[8]) | size_t(bytes[9]) << 8 | size_t(bytes[10]) << 16 | size_t(bytes[11]) << 24;
    start = 12;
  } else {
    return "unsupported .npy format version " + std::to_string(major);
  }
  if (headerLen > bytes.size() - start) return "the .npy header is truncated";
  const std::string_view header(reinterpret_cast<const char*>(bytes.data() + start), headerLen);
  if (auto bad = checkDict(header)) return "the .npy header " + *bad;
  const auto descr = dictValue(header, "'descr'");
  const auto order = dictValue(header, "'fortran_order'");
  const auto shapeText = dictValue(header, "'shape'");
  if (!descr || !order || !shapeText) return "the .npy header lacks descr, fortran_order or shape";
  if (*descr != "'<f4'") return "expected dtype float32 ('<f4'), found " + shown(*descr);
  if (*order != "False") return "expected a C-order array, found fortran_order " + shown(*order);
  const auto shape = parseShape(*shapeText);
  if (!shape) return "expected a 2-D array of shape (N, 6) or (N, 8), found shape " + shown(*shapeText);
  const uint64_t dataBytes = shape->first * shape->second * 4;
  const size_t dataStart = start + headerLen;
  if (dataBytes != bytes.size() - dataStart)
    return "the data holds " + std::to_string(bytes.size() - dataStart) + " bytes, the shape " +
           shown(*shapeText) + " needs " + std::to_string(dataBytes);
  out->rows = shape->first;
  out->cols = shape->second;
  out->data = bytes.subspan(dataStart);
  return std::nullopt;
}

std::vector<uint8_t> npyMatrixHeader(uint64_t rows, uint64_t cols) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
                       std::to_string(cols) + "), }";
  // The data starts on a 64-byte boundary; the header ends with '\n'.
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  std::vector<uint8_t> out(10 + header.size());
  std::memcpy(out.data(), kNpyMagic, 6);
  out[6] = 1;
  out[7] = 0;
  out[8] = uint8_t(header.size() & 0xff);
  out[9] = uint8_t(header.size() >> 8);
  std::memcpy(out.data() + 10, header.data(), header.size());
  return out;
}

std::vector<uint8_t> npyMatrixBytes(std::span<const float> values, uint64_t rows, uint64_t cols) {
  std::vector<uint8_t> out = npyMatrixHeader(rows, cols);
  const size_t head = out.size();
  out.resize(head + values.size_bytes());
  if (!values.empty()) std::memcpy(out.data() + head, values.data(), values.size_bytes());
  return out;
}

}  // namespace vff::query_tool
