// gen_gltf_write.cpp - the bytes vff-gltf-gen writes: the GLB framing and the .gltf text of an
// asset (not through the library's writer, which the assets test), the manifest, the files.
#include <xxhash.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "gen_gltf.h"

namespace vff::gltf_gen {
namespace {

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

}  // namespace

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vff-gltf-gen: %s\n", what.c_str());
  std::exit(1);
}

std::string hex64(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

std::string xxh3(const std::vector<uint8_t>& b) {
  return hex64(XXH3_64bits(b.data(), b.size()));
}

// The GLB container (glTF 2.0 section 4.4): header, JSON chunk padded with spaces so that the
// binary chunk's data starts at a multiple of 64 in the file, binary chunk padded with zeros.
std::vector<uint8_t> glbBytes(const std::string& jsonText, const std::vector<uint8_t>* bin) {
  std::string text = jsonText;
  if (bin)
    while ((12 + 8 + text.size() + 8) % 64) text += ' ';
  else
    while (text.size() % 4) text += ' ';
  std::vector<uint8_t> out;
  const size_t binLength = bin ? (bin->size() + 3) / 4 * 4 : 0;
  const size_t total = 12 + 8 + text.size() + (bin ? 8 + binLength : 0);
  put32(out, 0x46546C67);  // "glTF"
  put32(out, 2);
  put32(out, uint32_t(total));
  put32(out, uint32_t(text.size()));
  put32(out, 0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  if (bin) {
    put32(out, uint32_t(binLength));
    put32(out, 0x004E4942);  // "BIN\0"
    out.insert(out.end(), bin->begin(), bin->end());
    out.resize(total, 0);
  }
  return out;
}

std::vector<uint8_t> asGlb(Asset& a) {
  a.finishBuffer(true);
  return glbBytes(a.j.dump(), a.bin.empty() ? nullptr : &a.bin);
}

std::vector<uint8_t> asGltf(Asset& a) {
  a.finishBuffer(false);
  const std::string text = a.j.dump(1) + "\n";
  return {text.begin(), text.end()};
}

// The manifest with one line per asset and per file, so that a change shows as the lines it changes.
std::string manifestText(const json& m) {
  std::string s = "{\n";
  size_t i = 0;
  for (const auto& [key, value] : m.items()) {
    // Appended piece by piece: GCC 12 warns (-Wrestrict) wrongly on " " + std::string&&.
    s += ' ';
    s += json(key).dump() + ": ";
    if (value.is_object()) {
      s += "{\n";
      size_t k = 0;
      for (const auto& [name, entry] : value.items())
        s += "  " + json(name).dump() + ": " + entry.dump() + (++k < value.size() ? ",\n" : "\n");
      s += " }";
    } else {
      s += value.dump();
    }
    s += ++i < m.size() ? ",\n" : "\n";
  }
  return s + "}\n";
}

void writeFile(const std::filesystem::path& p, const std::vector<uint8_t>& bytes) {
  std::filesystem::create_directories(p.parent_path());
  std::ofstream o(p, std::ios::binary);
  o.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!o) die(p.string() + ": cannot write");
}

}  // namespace vff::gltf_gen
