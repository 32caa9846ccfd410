// PLY files: checked before OpenMesh reads them, and read here when their faces are triangle strips
// (see mesh_importers.h).
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "mesh_importers.h"

namespace vff::bake::detail {
namespace {

struct PlyProperty {
  std::string name;
  bool list = false;
  int countSize = 0, itemSize = 0;  // bytes; countSize only for lists
  bool countSigned = false;
  bool itemSigned = false, itemFloat = false;
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  // A triangle-strip element: its list may be as long as the file holds (a scanner writes one
  // strip of every face, with -1 restarts).
  bool strips() const { return name == "tristrips"; }
};
struct PlyHeader {
  std::string format;  // "ascii", "binary_little_endian" or "binary_big_endian"
  std::vector<PlyElement> elements;
};

constexpr uint64_t kMaxPlyList = 65536;
constexpr uint64_t kMaxStripList = uint64_t{1} << 32;  // a 32-bit count can say no more

// Reads the header's lines from `in` (left at the body's first byte) into *header, checking its
// grammar within 64 KiB.
Status parsePlyHeader(std::istream& in, const std::string& path, PlyHeader* header) {
  static const std::map<std::string, std::pair<int, bool>> kTypes = {
      {"char", {1, true}},    {"uchar", {1, false}},  {"int8", {1, true}},    {"uint8", {1, false}},
      {"short", {2, true}},   {"ushort", {2, false}}, {"int16", {2, true}},   {"uint16", {2, false}},
      {"int", {4, true}},     {"uint", {4, false}},   {"int32", {4, true}},   {"uint32", {4, false}},
      {"float", {4, true}},   {"float32", {4, true}}, {"double", {8, true}},  {"float64", {8, true}}};
  std::vector<PlyElement>& elements = header->elements;
  std::string& format = header->format;
  std::string line;
  uint64_t read = 0;
  int64_t n = 0;
  auto bad = [&](const std::string& why) {
    return makeError(Code::kMeshParse, path + ": line " + std::to_string(n) + ": " + why);
  };
  bool ended = false;
  while (!ended && std::getline(in, line)) {
    ++n;
    read += line.size() + 1;
    if (read > 65536) return makeError(Code::kMeshParse, path + ": PLY header longer than 64 KiB");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (n == 1) {
      if (keyword != "ply") return makeError(Code::kMeshParse, path + ": line 1: not a PLY file (no 'ply' magic)");
      continue;
    }
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "comment" || keyword == "obj_info") continue;
    std::vector<std::string> rest;
    for (std::string w; words >> w;) rest.push_back(w);
    for (const std::string& w : rest)
      for (char ch : w)
        if (ch < 0x21 || ch > 0x7e) return bad("PLY header holds a byte that is not printable ASCII");
    if (keyword == "format") {
      if (rest.size() != 2 || (rest[0] != "ascii" && rest[0] != "binary_little_endian" && rest[0] != "binary_big_endian") ||
          rest[1] != "1.0")
        return bad("PLY format line is not 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      format = rest[0];
    } else if (keyword == "element") {
      if (rest.size() != 2 || rest[1].empty() || rest[1].size() > 10 ||
          rest[1].find_first_not_of("0123456789") != std::string::npos)
        return bad("PLY element line is not 'element NAME COUNT'");
      elements.push_back({rest[0], std::stoull(rest[1]), {}});
    } else if (keyword == "property") {
      if (elements.empty()) return bad("PLY property before any element");
      const bool list = !rest.empty() && rest[0] == "list";
      if (list ? (rest.size() != 4 || !kTypes.count(rest[1]) || !kTypes.count(rest[2]) || rest[1] == "float" ||
                  rest[1] == "float32" || rest[1] == "double" || rest[1] == "float64")
               : (rest.size() != 2 || !kTypes.count(rest[0])))
        return bad("PLY property line is not 'property TYPE NAME' or 'property list INTEGER-TYPE TYPE NAME'");
      PlyProperty pr;
      pr.name = rest.back();
      pr.list = list;
      const std::string& itemType = list ? rest[2] : rest[0];
      pr.itemSigned = kTypes.at(itemType).second;
      pr.itemFloat = itemType.rfind("float", 0) == 0 || itemType == "double";
      if (list) {
        pr.countSize = kTypes.at(rest[1]).first;
        pr.countSigned = kTypes.at(rest[1]).second;
        pr.itemSize = kTypes.at(rest[2]).first;
      } else {
        pr.itemSize = kTypes.at(rest[0]).first;
      }
      elements.back().properties.push_back(pr);
    } else {
      return bad("unknown PLY header keyword '" + keyword.substr(0, 32) + "'");
    }
  }
  if (!ended) return makeError(Code::kMeshParse, path + ": PLY header has no end_header line");
  if (format.empty()) return makeError(Code::kMeshParse, path + ": PLY header has no format line");
  return {};
}

// An ASCII body, row by row: every value a number, every list length an integer up to 65536.
Status checkPlyAsciiBody(std::istream& in, const std::string& path, const std::vector<PlyElement>& elements) {
  std::string word;
  auto number = [&](bool integer, uint64_t* value) {
    if (!(in >> word)) return false;
    std::istringstream ws(word);
    if (integer) {
      long long v = 0;
      if (!(ws >> v) || ws.peek() != EOF || v < 0) return false;
      *value = uint64_t(v);
      return true;
    }
    double d = 0;
    return bool(ws >> d) && ws.peek() == EOF;
  };
  for (size_t e = 0; e < elements.size(); ++e)
    for (uint64_t row = 0; row < elements[e].count && !elements[e].properties.empty(); ++row)
      for (const PlyProperty& pr : elements[e].properties) {
        uint64_t items = 1;
        if (pr.list && (!number(true, &items) || items > (elements[e].strips() ? kMaxStripList : kMaxPlyList)))
          return makeError(Code::kMeshParse, path + ": element " + std::to_string(e) + " row " + std::to_string(row) +
                                                 ": a list length is not an integer from 0 to " +
                                                 std::to_string(elements[e].strips() ? kMaxStripList : kMaxPlyList));
        for (uint64_t i = 0; i < items; ++i) {
          uint64_t ignored = 0;
          if (!number(false, &ignored))
            return makeError(Code::kMeshParse, path + ": element " + std::to_string(e) + " row " +
                                                   std::to_string(row) + ": missing or malformed value");
        }
      }
  return {};
}

// A binary body: walk the rows through the file, reading only the list lengths. Elements without
// lists have a fixed row size and are stepped over whole.
Status checkPlyBinaryBody(std::istream& in, const std::string& path, const PlyHeader& header) {
  const std::vector<PlyElement>& elements = header.elements;
  const bool little = header.format == "binary_little_endian";
  const uint64_t bodyStart = uint64_t(in.tellg());
  in.seekg(0, std::ios::end);
  const uint64_t size = uint64_t(in.tellg());
  uint64_t pos = bodyStart;
  auto ends = [&](size_t e, uint64_t row) {
    return makeError(Code::kMeshParse, path + ": element " + std::to_string(e) + " row " + std::to_string(row) +
                                           ": the file ends inside the body");
  };
  for (size_t e = 0; e < elements.size(); ++e) {
    const PlyElement& el = elements[e];
    bool hasList = false;
    uint64_t rowBytes = 0;
    for (const PlyProperty& pr : el.properties) {
      hasList = hasList || pr.list;
      rowBytes += uint64_t(pr.itemSize);
    }
    if (!hasList) {
      if (rowBytes != 0 && el.count > (size - pos) / rowBytes) return ends(e, (size - pos) / rowBytes);
      pos += el.count * rowBytes;
      continue;
    }
    for (uint64_t row = 0; row < el.count; ++row)
      for (const PlyProperty& pr : el.properties) {
        uint64_t items = 1;
        if (pr.list) {
          if (pos + uint64_t(pr.countSize) > size) return ends(e, row);
          unsigned char bytes[4] = {};
          in.seekg(std::streamoff(pos));
          in.read(reinterpret_cast<char*>(bytes), pr.countSize);
          uint64_t v = 0;
          for (int k = 0; k < pr.countSize; ++k) v |= uint64_t(bytes[little ? k : pr.countSize - 1 - k]) << (8 * k);
          const bool negative = pr.countSigned && (v >> (8 * pr.countSize - 1)) != 0;
          if (negative || v > (el.strips() ? kMaxStripList : kMaxPlyList))
            return makeError(Code::kMeshParse, path + ": element " + std::to_string(e) + " row " + std::to_string(row) +
                                                   ": a list length is not from 0 to " +
                                                   std::to_string(el.strips() ? kMaxStripList : kMaxPlyList));
          items = v;
          pos += uint64_t(pr.countSize);
        }
        pos += items * uint64_t(pr.itemSize);
        if (pos > size) return ends(e, row);
      }
  }
  return {};
}

// Reads the values of a checked body in order, whatever its format.
class PlyValues {
 public:
  PlyValues(std::istream& in, const std::string& format) : in_(in), ascii_(format == "ascii"),
      little_(format == "binary_little_endian") {}
  double next(int size, bool isSigned, bool isFloat) {
    if (ascii_) {
      std::string word;
      in_ >> word;
      return std::strtod(word.c_str(), nullptr);
    }
    unsigned char b[8] = {};
    in_.read(reinterpret_cast<char*>(b), size);
    uint64_t v = 0;
    for (int k = 0; k < size; ++k) v |= uint64_t(b[little_ ? k : size - 1 - k]) << (8 * k);
    if (isFloat) {
      if (size == 4) {
        float f = 0;
        const uint32_t u = uint32_t(v);
        std::memcpy(&f, &u, 4);
        return f;
      }
      double d = 0;
      std::memcpy(&d, &v, 8);
      return d;
    }
    if (isSigned && size < 8 && (v >> (8 * size - 1)) != 0) return double(int64_t(v) - (int64_t{1} << (8 * size)));
    return double(v);
  }

 private:
  std::istream& in_;
  bool ascii_, little_;
};

// One strip's triangles with the alternating winding, skipping those that repeat a vertex.
void stripTriangles(const std::vector<int64_t>& strip, std::vector<uint32_t>* out) {
  for (size_t i = 0; i + 2 < strip.size(); ++i) {
    int64_t a = strip[i], b = strip[i + 1];
    const int64_t c = strip[i + 2];
    if (i % 2 == 1) std::swap(a, b);
    if (a == b || b == c || a == c) continue;
    out->insert(out->end(), {uint32_t(a), uint32_t(b), uint32_t(c)});
  }
}

// Reads the vertices (x, y, z, and nx, ny, nz when all three are there), the face lists (as
// fans) and the triangle strips of a checked body.
Status readPlyTriangles(std::istream& in, const std::string& path, const PlyHeader& header, PlyTriangles* out) {
  PlyValues values(in, header.format);
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& el = header.elements[e];
    const bool vertex = el.name == "vertex", face = el.name == "face" || el.strips();
    bool hasNormals = false;
    for (const PlyProperty& pr : el.properties) hasNormals = hasNormals || (vertex && pr.name == "nz");
    for (uint64_t row = 0; row < el.count; ++row) {
      float xyz[3] = {}, n[3] = {};
      for (const PlyProperty& pr : el.properties) {
        const uint64_t items = pr.list ? uint64_t(values.next(pr.countSize, pr.countSigned, false)) : 1;
        const bool indices = face && pr.list && (pr.name == "vertex_indices" || pr.name == "vertex_index");
        std::vector<int64_t> list;
        for (uint64_t i = 0; i < items; ++i) {
          const double v = values.next(pr.itemSize, pr.itemSigned, pr.itemFloat);
          if (indices) list.push_back(int64_t(v));
          static const char* const kNames[6] = {"x", "y", "z", "nx", "ny", "nz"};
          for (int k = 0; vertex && !pr.list && k < 6; ++k)
            if (pr.name == kNames[k]) (k < 3 ? xyz[k] : n[k - 3]) = float(v);
        }
        if (!indices) continue;
        const int64_t nv = int64_t(out->positions.size() / 3);
        for (int64_t i : list)
          if (i >= nv || (i < 0 && !(el.strips() && i == -1)))
            return makeError(Code::kMeshIndex, path + ": element " + std::to_string(e) + " row " + std::to_string(row) +
                                                   ": vertex index " + std::to_string(i) + " is not a vertex (0 to " +
                                                   std::to_string(nv - 1) + ")");
        if (!el.strips()) {
          for (size_t i = 1; i + 1 < list.size(); ++i)
            out->triangles.insert(out->triangles.end(), {uint32_t(list[0]), uint32_t(list[i]), uint32_t(list[i + 1])});
          continue;
        }
        std::vector<int64_t> strip;
        for (size_t i = 0; i <= list.size(); ++i) {
          if (i < list.size() && list[i] != -1) {
            strip.push_back(list[i]);
            continue;
          }
          stripTriangles(strip, &out->triangles);
          strip.clear();
        }
      }
      if (!vertex) continue;
      out->positions.insert(out->positions.end(), {xyz[0], xyz[1], xyz[2]});
      if (hasNormals) out->normals.insert(out->normals.end(), {n[0], n[1], n[2]});
    }
  }
  if (!in) return makeError(Code::kMeshParse, path + ": the body cannot be read");
  return {};
}

}  // namespace

// OpenMesh's PLY reader loops forever, or for as many steps as a garbled count says, on a header
// that never reaches `end_header`, holds an unknown or malformed line, or a body whose list counts
// or element counts do not match the file (found by tests/fuzz, fuzz_mesh). The file is checked
// first: the header's grammar (within 64 KiB), then the body against it, row by row for ASCII and
// byte by byte for binary, with list lengths of at most 65536 (a `tristrips` list: what the file
// holds). OpenMesh reads face lists only: a file with a `tristrips` element is read here.
Status checkPly(const std::string& path, std::optional<PlyTriangles>* strips) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot open");
  PlyHeader header;
  if (Status st = parsePlyHeader(in, path, &header); !st) return st;
  const std::streamoff body = in.tellg();
  Status st = header.format == "ascii" ? checkPlyAsciiBody(in, path, header.elements)
                                       : checkPlyBinaryBody(in, path, header);
  if (!st) return st;
  bool hasStrips = false;
  for (const PlyElement& el : header.elements) hasStrips = hasStrips || el.strips();
  if (!hasStrips) return {};
  in.clear();
  in.seekg(body);
  strips->emplace();
  return readPlyTriangles(in, path, header, &**strips);
}

}  // namespace vff::bake::detail
