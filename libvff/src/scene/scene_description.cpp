// scene_description.cpp - reading and writing scene descriptions (spec/scene.md).
#include "vff/scene_description.h"

#include "platform/mapped_file.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scene/strict_json_dom.h"

namespace vff {
namespace {

using nlohmann::json;

// The message forms of spec/scene.md section 5: "FILE: PATH: what".
Error sceneError(Code code, const std::string& name, const std::string& where, const std::string& what) {
  return makeError(code, name + ": " + where + ": " + what);
}

Error valueError(const std::string& name, const std::string& where, const std::string& what) {
  return sceneError(Code::kSceneValue, name, where, what);
}

// A value as a message quotes it: its JSON text, cut short.
std::string shown(const json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

Error missing(const std::string& name, const std::string& where) {
  return valueError(name, where, "a required member is missing");
}

// An integer is a number written without a fraction or an exponent (spec/scene.md section 1, as
// library manifests count them): the parser keeps those as int64 or uint64 (-0 as the integer 0). An
// integer text beyond 64 bits reaches us as a float, refused like 1.0: out of every range an
// integer member has.
bool isInteger(const json& v) { return v.is_number_integer() || v.is_number_unsigned(); }

// An integer's value where it is non-negative; nothing for a negative integer.
std::optional<uint64_t> nonNegative(const json& v) {
  if (v.is_number_unsigned()) return v.get<uint64_t>();
  const int64_t i = v.get<int64_t>();
  if (i < 0) return std::nullopt;
  return uint64_t(i);
}

// A number's binary32 value (round to nearest), or nothing where it rounds to infinity: magnitudes
// from 2^128 - 2^103 (halfway between FLT_MAX and 2^128) up.
std::optional<float> binary32(double d) {
  if (!(std::fabs(d) < 0x1.ffffffp127)) return std::nullopt;
  return float(d);
}

Result<float> number(const json& v, const std::string& name, const std::string& where) {
  if (!v.is_number()) return valueError(name, where, "expected a number, got " + shown(v));
  const auto f = binary32(v.get<double>());
  if (!f) return valueError(name, where, "the number " + shown(v) + " is not finite in binary32");
  return *f;
}

Status numbers(const json& obj, const char* key, size_t n, float* out, const std::string& name,
               const std::string& where) {
  if (!obj.contains(key)) return {};
  const json& a = obj[key];
  const std::string w = where + "." + key;
  if (!a.is_array() || a.size() != n)
    return valueError(name, w, "expected an array of " + std::to_string(n) + " numbers, got " + shown(a));
  for (size_t i = 0; i < n; ++i) {
    auto f = number(a[i], name, w + "[" + std::to_string(i) + "]");
    if (!f) return std::move(f).error();
    out[i] = *f;
  }
  return {};
}

Result<std::string> optionalString(const json& obj, const char* key, const std::string& name,
                                   const std::string& where) {
  if (!obj.contains(key)) return std::string();
  if (!obj[key].is_string()) return valueError(name, where + "." + key, "expected a string, got " + shown(obj[key]));
  return obj[key].get<std::string>();
}

bool isAlpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool isDigit(char c) { return c >= '0' && c <= '9'; }
int hexValue(char c) {
  if (isDigit(c)) return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// The length of the RFC 3986 scheme that `uri` starts with (ALPHA *( ALPHA / DIGIT / "+" / "-" /
// "." ) ":"), without its colon; 0 where it has none.
size_t schemeLength(const std::string& uri) {
  if (uri.empty() || !isAlpha(uri[0])) return 0;
  for (size_t i = 1; i < uri.size(); ++i) {
    const char c = uri[i];
    if (c == ':') return i;
    if (!isAlpha(c) && !isDigit(c) && c != '+' && c != '-' && c != '.') return 0;
  }
  return 0;
}

bool validUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t n = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xE ? 2 : (c >> 3) == 0x1E ? 3 : 9;
    if (n == 9 || i + n >= s.size()) return false;
    uint32_t cp = n == 0 ? c : c & (0x3Fu >> n);
    for (size_t k = 1; k <= n; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3F);
    }
    static const uint32_t kMin[] = {0, 0x80, 0x800, 0x10000};
    if (cp < kMin[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += n + 1;
  }
  return true;
}

// `%XY` escapes decoded; a '%' without two hex digits after it is kept as it is (the reader refuses it).
std::string percentDecoded(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && hexValue(uri[i + 1]) >= 0 && hexValue(uri[i + 2]) >= 0) {
      out += char(hexValue(uri[i + 1]) * 16 + hexValue(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// Rule scene-uri (11004), its checks in the order of spec/scene.md section 5.
Status checkUri(const std::string& uri, const std::string& name, const std::string& where) {
  auto bad = [&](const std::string& what) { return sceneError(Code::kSceneUri, name, where, what); };
  if (uri.empty()) return bad("is empty");
  if (const size_t n = schemeLength(uri))
    return bad(n == 1 ? "'" + uri + "' starts with a Windows drive letter, which URI syntax reads as a scheme; "
                            "use a reference relative to the description"
                      : "'" + uri + "' has a URI scheme (" + uri.substr(0, n) + ":); a file reference is required");
  if (uri.find('\\') != std::string::npos) return bad("'" + uri + "' has a backslash; the separator is '/'");
  if (uri.rfind("//", 0) == 0) return bad("'" + uri + "' starts with '//', a network-path reference");
  if (uri.find_first_of("?#") != std::string::npos)
    return bad("'" + uri + "' has a query or fragment ('?' or '#'); write them as %3F and %23");
  for (size_t i = 0; i < uri.size(); ++i)
    if (uri[i] == '%' && (i + 2 >= uri.size() || hexValue(uri[i + 1]) < 0 || hexValue(uri[i + 2]) < 0))
      return bad("'" + uri + "' has a '%' at byte " + std::to_string(i) + " without two hex digits after it");
  const std::string path = percentDecoded(uri);
  if (path.find('\0') != std::string::npos) return bad("'" + uri + "' decodes to a NUL byte");
  if (!validUtf8(path)) return bad("'" + uri + "' decodes to bytes that are not UTF-8");
  return {};
}

Result<SceneField> parseField(const json& f, const std::string& name, const std::string& where) {
  if (!f.is_object()) return valueError(name, where, "expected an object, got " + shown(f));
  SceneField out;
  if (!f.contains("uri")) return missing(name, where + ".uri");
  if (!f["uri"].is_string()) return valueError(name, where + ".uri", "expected a string, got " + shown(f["uri"]));
  out.uri = f["uri"].get<std::string>();
  if (Status s = checkUri(out.uri, name, where + ".uri"); !s) return std::move(s).error();
  auto n = optionalString(f, "name", name, where);
  if (!n) return std::move(n).error();
  out.name = std::move(*n);
  if (f.contains("source")) {
    if (!f["source"].is_object()) return valueError(name, where + ".source", "expected an object, got " + shown(f["source"]));
    out.sourceJson = f["source"].dump();
  }
  return out;
}

Result<SceneInstance> parseInstance(const json& i, size_t fieldCount, const std::string& name, const std::string& where) {
  if (!i.is_object()) return valueError(name, where, "expected an object, got " + shown(i));
  SceneInstance out;
  if (!i.contains("field")) return missing(name, where + ".field");
  const json& fv = i["field"];
  if (!isInteger(fv)) return valueError(name, where + ".field", "expected an integer, got " + shown(fv));
  const std::optional<uint64_t> field = nonNegative(fv);
  if (!field || *field >= fieldCount)
    return sceneError(Code::kSceneFieldIndex, name, where + ".field",
                      "index " + shown(fv) + " is not one of the " + std::to_string(fieldCount) + " fields");
  out.field = uint32_t(*field);
  auto n = optionalString(i, "name", name, where);
  if (!n) return std::move(n).error();
  out.name = std::move(*n);
  float t[3] = {0, 0, 0};
  if (Status s = numbers(i, "translation", 3, t, name, where); !s) return std::move(s).error();
  out.translation = {t[0], t[1], t[2]};
  if (Status s = numbers(i, "rotation", 4, out.rotation.data(), name, where); !s) return std::move(s).error();
  // The norm in binary64 of the binary32 components, in this order (a reader elsewhere gets the same bits).
  const auto& q = out.rotation;
  const double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
  if (!(std::fabs(norm - 1.0) <= 1e-3)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "the quaternion's norm is %.9g, not within 1e-3 of 1", norm);
    return valueError(name, where + ".rotation", buf);
  }
  for (float& c : out.rotation) c = float(double(c) / norm);
  if (i.contains("scale")) {
    auto s = number(i["scale"], name, where + ".scale");
    if (!s) return std::move(s).error();
    if (!(*s > 0)) return valueError(name, where + ".scale", "must be positive in binary32, got " + shown(i["scale"]));
    out.scale = *s;
  }
  if (i.contains("extras")) out.extrasJson = i["extras"].dump();
  return out;
}

Result<std::string> parseAsset(const json& doc, const std::string& name) {
  if (!doc.contains("asset")) return missing(name, "asset");
  const json& asset = doc["asset"];
  if (!asset.is_object()) return valueError(name, "asset", "expected an object, got " + shown(asset));
  if (!asset.contains("format")) return missing(name, "asset.format");
  if (asset["format"] != "vff-scene")
    return sceneError(Code::kSceneVersion, name, "asset.format", "is " + shown(asset["format"]) + ", not \"vff-scene\"");
  if (!asset.contains("version")) return missing(name, "asset.version");
  const json& v = asset["version"];
  if (!isInteger(v) || nonNegative(v) != uint64_t(kSceneDescriptionVersion))
    return sceneError(Code::kSceneVersion, name, "asset.version", "is " + shown(v) + "; this reader implements version 1");
  if (asset.contains("minorVersion")) {
    const json& m = asset["minorVersion"];
    if (!isInteger(m) || !nonNegative(m))
      return valueError(name, "asset.minorVersion", "expected a non-negative integer, got " + shown(m));
  }
  return optionalString(asset, "generator", name, "asset");
}

// The shortest text that reads back as the same float. A negative zero keeps a fraction: "-0" is
// the integer 0 to a JSON reader, and would come back as +0.
std::string floatText(float v) {
  if (v == 0.0f && std::signbit(v)) return "-0.0";
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string floats(const float* v, size_t n) {
  std::string s = "[";
  for (size_t i = 0; i < n; ++i) s += (i ? ", " : "") + floatText(v[i]);
  return s + "]";
}

}  // namespace

RigidTransform SceneInstance::rigidTransform() const noexcept {
  RigidTransform t;
  const double x = rotation[0], y = rotation[1], z = rotation[2], w = rotation[3];
  const double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t.rotation[r][c] = float(m[r][c]);
  t.translation = translation;
  t.scale = scale;
  return t;
}

std::array<float, 4> quaternionFromRotation(const float r[3][3]) noexcept {
  // Shepperd's method: the largest of the four candidates keeps the division well conditioned.
  const double m00 = r[0][0], m11 = r[1][1], m22 = r[2][2], tr = m00 + m11 + m22;
  double x, y, z, w;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    w = 0.25 * s, x = (r[2][1] - r[1][2]) / s, y = (r[0][2] - r[2][0]) / s, z = (r[1][0] - r[0][1]) / s;
  } else if (m00 > m11 && m00 > m22) {
    const double s = std::sqrt(1.0 + m00 - m11 - m22) * 2;
    w = (r[2][1] - r[1][2]) / s, x = 0.25 * s, y = (r[0][1] + r[1][0]) / s, z = (r[0][2] + r[2][0]) / s;
  } else if (m11 > m22) {
    const double s = std::sqrt(1.0 + m11 - m00 - m22) * 2;
    w = (r[0][2] - r[2][0]) / s, x = (r[0][1] + r[1][0]) / s, y = 0.25 * s, z = (r[1][2] + r[2][1]) / s;
  } else {
    const double s = std::sqrt(1.0 + m22 - m00 - m11) * 2;
    w = (r[1][0] - r[0][1]) / s, x = (r[0][2] + r[2][0]) / s, y = (r[1][2] + r[2][1]) / s, z = 0.25 * s;
  }
  const double n = std::sqrt(x * x + y * y + z * z + w * w) * (w < 0 ? -1.0 : 1.0);
  return {float(x / n), float(y / n), float(z / n), float(w / n)};
}

Result<SceneDescription> parseSceneDescription(std::string_view text, const std::string& name) {
  json doc;
  if (auto problem = detail::parseStrictJson(text, doc))
    return makeError(Code::kSceneJson, describeJsonProblem(*problem, name));
  if (!doc.is_object()) return makeError(Code::kSceneJson, name + ": the JSON value is not an object");
  SceneDescription out;
  auto gen = parseAsset(doc, name);
  if (!gen) return std::move(gen).error();
  out.generator = std::move(*gen);
  for (const char* key : {"fields", "instances"}) {
    if (!doc.contains(key)) return missing(name, key);
    if (!doc[key].is_array()) return valueError(name, key, "expected an array, got " + shown(doc[key]));
  }
  for (size_t i = 0; i < doc["fields"].size(); ++i) {
    auto f = parseField(doc["fields"][i], name, "fields[" + std::to_string(i) + "]");
    if (!f) return std::move(f).error();
    out.fields.push_back(std::move(*f));
  }
  for (size_t i = 0; i < doc["instances"].size(); ++i) {
    auto inst = parseInstance(doc["instances"][i], out.fields.size(), name, "instances[" + std::to_string(i) + "]");
    if (!inst) return std::move(inst).error();
    out.instances.push_back(std::move(*inst));
  }
  if (doc.contains("extras")) out.extrasJson = doc["extras"].dump();
  return out;
}

Result<SceneDescription> readSceneDescription(const std::string& path) {
  // As File::open: a named pipe or a folder is refused (io-open) instead of waited on.
  detail::MappedFile file;
  if (Status st = file.open(path, false); !st) return st.error();
  const std::span<const uint8_t> b = file.bytes();
  return parseSceneDescription(std::string_view(reinterpret_cast<const char*>(b.data()), b.size()), path);
}

Result<std::string> formatSceneDescription(const SceneDescription& scene) {
  // Checked by the reader's own rules on the text produced, so the writer cannot write what the
  // reader refuses. Strings are checked first: JSON holds UTF-8 only.
  for (size_t i = 0; i < scene.fields.size(); ++i)
    for (const std::string* v : {&scene.fields[i].uri, &scene.fields[i].name})
      if (!validUtf8(*v)) return valueError("scene", "fields[" + std::to_string(i) + "]", "a string that is not UTF-8");
  for (size_t i = 0; i < scene.instances.size(); ++i)
    if (!validUtf8(scene.instances[i].name))
      return valueError("scene", "instances[" + std::to_string(i) + "].name", "a string that is not UTF-8");
  if (!validUtf8(scene.generator)) return valueError("scene", "asset.generator", "a string that is not UTF-8");
  std::string s = "{\n  \"asset\": {\"format\": \"vff-scene\", \"version\": 1";
  if (!scene.generator.empty()) s += ", \"generator\": " + json(scene.generator).dump();
  s += "},\n  \"fields\": [";
  for (size_t i = 0; i < scene.fields.size(); ++i) {
    const SceneField& f = scene.fields[i];
    s += (i ? ",\n" : "\n") + std::string("    {\"uri\": ") + json(f.uri).dump();
    if (!f.name.empty()) s += ", \"name\": " + json(f.name).dump();
    if (!f.sourceJson.empty()) {
      const json src = json::parse(f.sourceJson, nullptr, false);
      if (!src.is_object()) return valueError("scene", "fields[" + std::to_string(i) + "].source", "not a JSON object");
      s += ", \"source\": " + src.dump();
    }
    s += "}";
  }
  s += scene.fields.empty() ? "],\n" : "\n  ],\n";
  s += "  \"instances\": [";
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& in = scene.instances[i];
    const float t[3] = {in.translation.x, in.translation.y, in.translation.z};
    s += (i ? ",\n" : "\n") + std::string("    {\"field\": ") + std::to_string(in.field);
    if (!in.name.empty()) s += ", \"name\": " + json(in.name).dump();
    s += ", \"translation\": " + floats(t, 3) + ", \"rotation\": " + floats(in.rotation.data(), 4) +
         ", \"scale\": " + floatText(in.scale);
    if (!in.extrasJson.empty()) {
      const json e = json::parse(in.extrasJson, nullptr, false);
      if (e.is_discarded()) return valueError("scene", "instances[" + std::to_string(i) + "].extras", "not JSON");
      s += ", \"extras\": " + e.dump();
    }
    s += "}";
  }
  s += scene.instances.empty() ? "]" : "\n  ]";
  if (!scene.extrasJson.empty()) {
    const json e = json::parse(scene.extrasJson, nullptr, false);
    if (e.is_discarded()) return valueError("scene", "extras", "not JSON");
    s += ",\n  \"extras\": " + e.dump();
  }
  s += "\n}\n";
  auto check = parseSceneDescription(s, "scene");
  if (!check) return std::move(check).error();
  return s;
}

Status writeSceneDescription(const std::string& path, const SceneDescription& scene) {
  auto text = formatSceneDescription(scene);
  if (!text) return std::move(text).error();
  const std::string tmp = path + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return makeError(Code::kIoOpen, tmp + ": cannot be created");
    out << *text;
    out.flush();
    if (!out) {
      out.close();
      std::remove(tmp.c_str());
      return makeError(Code::kIoWrite, tmp + ": write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return makeError(Code::kIoWrite, path + ": cannot rename the temporary file over it");
  }
  return {};
}

std::string resolveSceneUri(const std::string& descriptionPath, const std::string& uri) {
  const std::string path = percentDecoded(uri);
  if (!path.empty() && path[0] == '/') return path;
  const size_t slash = descriptionPath.find_last_of('/');
  return slash == std::string::npos ? path : descriptionPath.substr(0, slash + 1) + path;
}

std::string encodeSceneUri(const std::string& path) {
  static const char kHex[] = "0123456789ABCDEF";
  const size_t scheme = schemeLength(path);  // the colon at this index would read as a scheme's
  std::string out;
  for (size_t i = 0; i < path.size(); ++i) {
    const auto c = static_cast<unsigned char>(path[i]);
    if (c == '%' || c == '?' || c == '#' || c == '\\' || c < 0x20 || c == 0x7F || (scheme && i == scheme)) {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += char(c);
    }
  }
  return out;
}

}  // namespace vff
