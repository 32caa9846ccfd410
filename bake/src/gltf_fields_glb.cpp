// gltf_fields_glb.cpp - the GLB container, uris and buffer bytes for the VFF_visibility_field reader
// and writer (gltf_fields_glb.h).
#include "gltf_fields_glb.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace vff::bake::detail {
namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }
void put32(std::vector<uint8_t>* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(uint8_t(v >> (8 * i)));
}

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

int base64Value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+' || c == '-') return 62;
  if (c == '/' || c == '_') return 63;
  return -1;
}

}  // namespace

bool hasGlbMagic(std::span<const uint8_t> bytes) { return bytes.size() >= 4 && le32(bytes.data()) == kGlbMagic; }

std::string splitGlb(std::span<const uint8_t> bytes, GlbChunks* out) {
  if (bytes.size() < 12 || le32(bytes.data()) != kGlbMagic) return "not a GLB: no 12-byte header with the magic 'glTF'";
  if (le32(bytes.data() + 4) != 2) return "GLB version " + std::to_string(le32(bytes.data() + 4)) + ", not 2";
  const uint64_t length = le32(bytes.data() + 8);
  if (length != bytes.size())
    return "the GLB header's length " + std::to_string(length) + " is not the file's " + std::to_string(bytes.size()) +
           " bytes";
  size_t at = 12;
  int chunk = 0;
  while (at < bytes.size()) {
    if (bytes.size() - at < 8) return "chunk " + std::to_string(chunk) + " at byte " + std::to_string(at) + " has no 8-byte header";
    const uint64_t n = le32(bytes.data() + at), type = le32(bytes.data() + at + 4);
    if (n > bytes.size() - at - 8)
      return "chunk " + std::to_string(chunk) + " at byte " + std::to_string(at) + " of " + std::to_string(n) +
             " bytes runs past the end of the file";
    const uint8_t* data = bytes.data() + at + 8;
    if (chunk == 0) {
      if (type != kChunkJson) return "the first chunk is not JSON";
      out->json.assign(reinterpret_cast<const char*>(data), size_t(n));
    } else if (chunk == 1 && type == kChunkBin) {
      out->bin.assign(data, data + n);
      out->hasBin = true;
    } else if (type == kChunkJson || type == kChunkBin) {
      return "chunk " + std::to_string(chunk) + " is a second " + (type == kChunkJson ? "JSON" : "BIN") + " chunk";
    }
    at += 8 + size_t(n);
    ++chunk;
  }
  if (chunk == 0) return "the GLB has no JSON chunk";
  return "";
}

std::vector<uint8_t> joinGlb(const std::string& json, const std::vector<uint8_t>& bin) {
  // 12 (header) + 8 (JSON chunk header) + JSON + 8 (BIN chunk header) a multiple of 64.
  std::string text = json;
  while ((28 + text.size()) % 64 != 0) text.push_back(' ');
  std::vector<uint8_t> padded = bin;
  while (padded.size() % 4 != 0) padded.push_back(0);
  std::vector<uint8_t> out;
  const uint64_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + padded.size());
  out.reserve(size_t(total));
  put32(&out, kGlbMagic);
  put32(&out, 2);
  put32(&out, uint32_t(total));
  put32(&out, uint32_t(text.size()));
  put32(&out, kChunkJson);
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    put32(&out, uint32_t(padded.size()));
    put32(&out, kChunkBin);
    out.insert(out.end(), padded.begin(), padded.end());
  }
  return out;
}

std::string readRegularFile(const std::string& path, std::vector<uint8_t>* out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return std::string("cannot be opened: ") + std::strerror(errno);
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return "not a regular file";
  }
  out->resize(size_t(st.st_size));
  for (size_t done = 0; done < out->size();) {
    const ssize_t n = ::read(fd, out->data() + done, out->size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string e = n < 0 ? std::strerror(errno) : "the file shrank";
      ::close(fd);
      return "cannot be read: " + e;
    }
    done += size_t(n);
  }
  ::close(fd);
  return "";
}

bool isDataUri(const std::string& uri) { return uri.size() >= 5 && uri.compare(0, 5, "data:") == 0; }

std::string checkGltfUri(const std::string& uri) {
  if (uri.empty()) return "is empty";
  if (isDataUri(uri)) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos) return "is a data: URI without a ','";
    const std::string head = uri.substr(0, comma);
    if (head.size() < 7 || head.compare(head.size() - 7, 7, ";base64") != 0) return "is a data: URI that is not ;base64,";
    return "";
  }
  // A scheme: letters, digits, '+', '-', '.' after a first letter, then ':' before any '/'.
  const size_t colon = uri.find(':');
  if (colon != std::string::npos && colon > 0 && uri.find('/') > colon) {
    bool scheme = std::isalpha(static_cast<unsigned char>(uri[0])) != 0;
    for (size_t i = 1; i < colon && scheme; ++i)
      scheme = std::isalnum(static_cast<unsigned char>(uri[i])) || uri[i] == '+' || uri[i] == '-' || uri[i] == '.';
    if (scheme) return "has a URI scheme (" + uri.substr(0, colon) + ":); a relative reference or a data: URI is required";
  }
  if (uri.rfind("//", 0) == 0) return "starts with '//', a network-path reference";
  if (uri[0] == '/') return "is an absolute path; a relative reference is required";
  if (uri.find('\\') != std::string::npos) return "has a backslash; the separator is '/'";
  if (uri.find_first_of("?#") != std::string::npos) return "has a query or fragment ('?' or '#')";
  for (size_t i = 0; i < uri.size(); ++i)
    if (uri[i] == '%' && (i + 2 >= uri.size() || hexValue(uri[i + 1]) < 0 || hexValue(uri[i + 2]) < 0))
      return "has a '%' at byte " + std::to_string(i) + " without two hex digits after it";
  for (size_t i = 0; i + 2 < uri.size(); ++i)
    if (uri[i] == '%' && uri[i + 1] == '0' && uri[i + 2] == '0') return "decodes to a NUL byte";
  return "";
}

std::string decodeDataUri(const std::string& uri, std::vector<uint8_t>* out, std::string* mediaType) {
  if (std::string p = checkGltfUri(uri); !p.empty()) return p;
  const size_t comma = uri.find(',');
  if (mediaType) *mediaType = uri.substr(5, comma - 5 - 7);
  out->clear();
  uint32_t acc = 0;
  int bits = 0;
  size_t i = comma + 1;
  for (; i < uri.size() && uri[i] != '='; ++i) {
    const int v = base64Value(uri[i]);
    if (v < 0) return "has a byte that is not base64 at " + std::to_string(i);
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out->push_back(uint8_t(acc >> bits));
    }
  }
  for (; i < uri.size(); ++i)
    if (uri[i] != '=') return "has data after its base64 padding";
  return "";
}

std::string resolveGltfUri(const std::string& gltfPath, const std::string& uri) {
  std::string path;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && hexValue(uri[i + 1]) >= 0 && hexValue(uri[i + 2]) >= 0) {
      path += char(hexValue(uri[i + 1]) * 16 + hexValue(uri[i + 2]));
      i += 2;
    } else {
      path += uri[i];
    }
  }
  const size_t slash = gltfPath.find_last_of('/');
  return slash == std::string::npos ? path : gltfPath.substr(0, slash + 1) + path;
}

std::string readGltfUri(const std::string& gltfPath, const std::string& uri, std::vector<uint8_t>* out,
                        std::string* mediaType) {
  if (isDataUri(uri)) return decodeDataUri(uri, out, mediaType);
  if (std::string p = checkGltfUri(uri); !p.empty()) return p;
  const std::string path = resolveGltfUri(gltfPath, uri);
  if (std::string e = readRegularFile(path, out); !e.empty()) return path + ": " + e;
  return "";
}

std::string gltfBufferData(const nlohmann::json& doc, size_t index, const std::string& gltfPath, const GlbChunks* glb,
                           std::vector<uint8_t>* out) {
  const auto it = doc.find("buffers");
  if (it == doc.end() || !it->is_array() || index >= it->size()) return "there is no buffer " + std::to_string(index);
  const nlohmann::json& b = (*it)[index];
  if (!b.is_object()) return "buffer " + std::to_string(index) + " is not an object";
  if (b.contains("uri")) {
    if (!b["uri"].is_string()) return "buffer " + std::to_string(index) + "'s uri is not a string";
    if (std::string e = readGltfUri(gltfPath, b["uri"].get<std::string>(), out); !e.empty())
      return "buffer " + std::to_string(index) + "'s uri '" + b["uri"].get<std::string>() + "': " + e;
  } else if (index == 0 && glb && glb->hasBin) {
    *out = glb->bin;
  } else {
    return "buffer " + std::to_string(index) + " has no data (" +
           (index == 0 && glb ? "the GLB has no binary chunk" : "no uri") + ")";
  }
  // byteLength is what the buffer holds; the GLB chunk may be padded beyond it.
  if (b.contains("byteLength") && b["byteLength"].is_number_unsigned()) {
    const uint64_t n = b["byteLength"].get<uint64_t>();
    if (n > out->size())
      return "buffer " + std::to_string(index) + " declares " + std::to_string(n) + " bytes but has " +
             std::to_string(out->size());
    out->resize(size_t(n));
  }
  return "";
}

std::string hex16(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

}  // namespace vff::bake::detail
