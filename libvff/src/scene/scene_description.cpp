// scene_description.cpp - reading and writing scene descriptions (spec/scene.md).
#include "vff/scene_description.h"

#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scene/strict_json_dom.h"

namespace vff {
namespace {

using nlohmann::json;

Error valueError(const std::string& name, const std::string& where, const std::string& what) {
  return makeError(Code::kSceneValue, name + ": " + where + ": " + what);
}

// A finite number that fits a float.
Result<float> number(const json& v, const std::string& name, const std::string& where) {
  if (!v.is_number()) return valueError(name, where, "expected a number, got " + v.dump());
  const double d = v.get<double>();
  const auto f = float(d);
  if (!std::isfinite(d) || !std::isfinite(f)) return valueError(name, where, "the number is not finite as a float");
  return f;
}

Status numbers(const json& obj, const char* key, size_t n, float* out, const std::string& name,
               const std::string& where) {
  if (!obj.contains(key)) return {};
  const json& a = obj[key];
  const std::string w = where + "." + key;
  if (!a.is_array() || a.size() != n)
    return valueError(name, w, "expected an array of " + std::to_string(n) + " numbers, got " + a.dump());
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
  if (!obj[key].is_string()) return valueError(name, where + "." + key, "expected a string, got " + obj[key].dump());
  return obj[key].get<std::string>();
}

bool hasScheme(const std::string& uri) {
  // RFC 3986 scheme: a letter, then letters, digits, '+', '-', '.', then ':'.
  if (uri.empty() || !std::isalpha(static_cast<unsigned char>(uri[0]))) return false;
  for (char c : uri) {
    if (c == ':') return true;
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '-' && c != '.') return false;
  }
  return false;
}

Result<SceneField> parseField(const json& f, const std::string& name, const std::string& where) {
  if (!f.is_object()) return valueError(name, where, "expected an object");
  SceneField out;
  if (!f.contains("uri") || !f["uri"].is_string()) return valueError(name, where + ".uri", "a string is required");
  out.uri = f["uri"].get<std::string>();
  if (out.uri.empty()) return valueError(name, where + ".uri", "is empty");
  if (hasScheme(out.uri)) return valueError(name, where + ".uri", "'" + out.uri + "' has a URI scheme; a file path is required");
  auto n = optionalString(f, "name", name, where);
  if (!n) return std::move(n).error();
  out.name = std::move(*n);
  if (f.contains("source")) {
    if (!f["source"].is_object()) return valueError(name, where + ".source", "expected an object");
    out.sourceJson = f["source"].dump();
  }
  return out;
}

Result<SceneInstance> parseInstance(const json& i, size_t fieldCount, const std::string& name, const std::string& where) {
  if (!i.is_object()) return valueError(name, where, "expected an object");
  SceneInstance out;
  if (!i.contains("field") || !i["field"].is_number_integer())
    return valueError(name, where + ".field", "an integer field index is required");
  const auto field = i["field"].get<int64_t>();
  if (field < 0 || uint64_t(field) >= fieldCount)
    return valueError(name, where + ".field", "index " + std::to_string(field) + " is not one of the " +
                                                  std::to_string(fieldCount) + " fields");
  out.field = uint32_t(field);
  auto n = optionalString(i, "name", name, where);
  if (!n) return std::move(n).error();
  out.name = std::move(*n);
  float t[3] = {0, 0, 0};
  if (Status s = numbers(i, "translation", 3, t, name, where); !s) return std::move(s).error();
  out.translation = {t[0], t[1], t[2]};
  if (Status s = numbers(i, "rotation", 4, out.rotation.data(), name, where); !s) return std::move(s).error();
  const auto& q = out.rotation;
  const double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
  if (!(std::fabs(norm - 1.0) <= 1e-3)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "the quaternion's norm is %.9g, not within 1e-3 of 1", norm);
    return valueError(name, where + ".rotation", buf);
  }
  for (float& c : out.rotation) c = float(c / norm);
  if (i.contains("scale")) {
    auto s = number(i["scale"], name, where + ".scale");
    if (!s) return std::move(s).error();
    if (!(*s > 0)) return valueError(name, where + ".scale", "must be positive, got " + i["scale"].dump());
    out.scale = *s;
  }
  if (i.contains("extras")) out.extrasJson = i["extras"].dump();
  return out;
}

// The shortest text that reads back as the same float.
std::string floatText(float v) {
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
  if (!doc.contains("asset") || !doc["asset"].is_object())
    return makeError(Code::kSceneVersion, name + ": asset: an object with format \"vff-scene\" is required");
  const json& asset = doc["asset"];
  if (!asset.contains("format") || asset["format"] != "vff-scene")
    return makeError(Code::kSceneVersion, name + ": asset.format is " +
                                              (asset.contains("format") ? asset["format"].dump() : "missing") +
                                              ", not \"vff-scene\"");
  if (!asset.contains("version") || !asset["version"].is_number_integer() ||
      asset["version"].get<int64_t>() != kSceneDescriptionVersion)
    return makeError(Code::kSceneVersion, name + ": asset.version is " +
                                              (asset.contains("version") ? asset["version"].dump() : "missing") +
                                              "; this reader implements version 1");
  SceneDescription out;
  auto gen = optionalString(asset, "generator", name, "asset");
  if (!gen) return std::move(gen).error();
  out.generator = std::move(*gen);
  for (const char* key : {"fields", "instances"})
    if (!doc.contains(key) || !doc[key].is_array()) return valueError(name, key, "an array is required");
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
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot be opened");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return makeError(Code::kIoRead, path + ": cannot be read");
  return parseSceneDescription(ss.str(), path);
}

Result<std::string> formatSceneDescription(const SceneDescription& scene) {
  // Checked by the reader's own rules on the text produced, so the writer cannot write what the
  // reader refuses.
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
  if (!uri.empty() && uri[0] == '/') return uri;
  const size_t slash = descriptionPath.find_last_of('/');
  return slash == std::string::npos ? uri : descriptionPath.substr(0, slash + 1) + uri;
}

}  // namespace vff
