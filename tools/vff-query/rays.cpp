// rays.cpp - parsing the text lines of rays and formatting the answers (rays.h).
#include "rays.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "npy.h"

namespace vff::query_tool {

std::string shown(std::string_view bytes, size_t limit) {
  std::string out;
  for (size_t k = 0; k < bytes.size() && k < limit; ++k) {
    const unsigned char c = static_cast<unsigned char>(bytes[k]);
    if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
      out.push_back(char(c));
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", unsigned(c));
      out += buf;
    }
  }
  if (bytes.size() > limit) out += "...";
  return out;
}

namespace {

bool isBlank(char c) { return c == ' ' || c == '\t'; }

// The 6 or 8 numbers of a ray into `ray`.
void assign(Ray* ray, const float* v, size_t n) {
  ray->origin = {v[0], v[1], v[2]};
  ray->direction = {v[3], v[4], v[5]};
  if (n == 8) {
    ray->tmin = v[6];
    ray->tmax = v[7];
  }
}

// A CSV line. columns[i]: the 1-based column where number i starts.
std::optional<LineError> parseCsv(std::string_view line, Ray* ray) {
  float v[8];
  uint64_t columns[9] = {};
  size_t n = 0, i = 0;
  while (true) {
    while (i < line.size() && isBlank(line[i])) ++i;
    if (i == line.size()) break;
    if (n == 8) return LineError{0, i + 1, "too many numbers: a ray has 6 (ox,oy,oz,dx,dy,dz) or 8 (and tmin,tmax)"};
    const char* first = line.data() + i;
    const char* last = line.data() + line.size();
    if (*first == '+') ++first;  // from_chars takes no '+'
    auto [ptr, ec] = std::from_chars(first, last, v[n]);
    size_t end = size_t(ptr - line.data());
    if (ec == std::errc::result_out_of_range) return LineError{0, i + 1, "number out of float range"};
    if (ec != std::errc() || (end < line.size() && !isBlank(line[end]) && line[end] != ',')) {
      size_t e = i;
      while (e < line.size() && !isBlank(line[e]) && line[e] != ',') ++e;
      return LineError{0, i + 1, "expected a number, found \"" + shown(line.substr(i, e - i)) + "\""};
    }
    columns[n++] = i + 1;
    i = end;
    while (i < line.size() && isBlank(line[i])) ++i;
    if (i < line.size() && line[i] == ',') {
      ++i;
      while (i < line.size() && isBlank(line[i])) ++i;
      if (i == line.size()) return LineError{0, i + 1, "expected a number after ','"};
    }
  }
  if (n != 6 && n != 8)
    return LineError{0, line.size() + 1,
                     "found " + std::to_string(n) + " numbers: a ray has 6 (ox,oy,oz,dx,dy,dz) or 8 (and tmin,tmax)"};
  assign(ray, v, n);
  if (auto bad = checkRay(*ray)) return LineError{0, columns[bad->second], bad->first};
  return std::nullopt;
}

// A JSON line: an object with origin/direction (and tmin/tmax), or an array of 6 or 8 numbers.
std::optional<LineError> parseJson(std::string_view line, Ray* ray) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(line);
  } catch (const nlohmann::json::parse_error& e) {
    std::string what = e.what();
    const size_t colon = what.find("syntax error");
    return LineError{0, e.byte ? e.byte : 1,
                     "invalid JSON: " + shown(colon == std::string::npos ? what : what.substr(colon), 200)};
  } catch (const nlohmann::json::out_of_range&) {
    // nlohmann refuses a number beyond binary64 (1e400) after the parse, with no place.
    return LineError{0, 1, "invalid JSON: a number is beyond the binary64 range"};
  }
  auto numbers = [](const nlohmann::json& a, size_t count, const char* name, float* v) -> std::optional<std::string> {
    if (!a.is_array() || a.size() != count) return std::string(name) + " must be an array of " + std::to_string(count) + " numbers";
    for (size_t k = 0; k < count; ++k) {
      if (!a[k].is_number()) return std::string(name) + "[" + std::to_string(k) + "] is not a number";
      v[k] = a[k].get<float>();
    }
    return std::nullopt;
  };
  float v[8];
  if (j.is_array()) {
    const size_t n = j.size();
    if (n != 6 && n != 8) return LineError{0, 1, "a ray array holds 6 or 8 numbers, found " + std::to_string(n)};
    if (auto e = numbers(j, n, "the ray", v)) return LineError{0, 1, *e};
    assign(ray, v, n);
  } else if (j.is_object()) {
    if (!j.contains("origin") || !j.contains("direction"))
      return LineError{0, 1, "a ray object needs \"origin\" and \"direction\""};
    for (const auto& item : j.items())
      if (item.key() != "origin" && item.key() != "direction" && item.key() != "tmin" && item.key() != "tmax")
        return LineError{0, 1, "unknown key \"" + shown(item.key()) + "\" (a ray has origin, direction, tmin, tmax)"};
    if (auto e = numbers(j["origin"], 3, "origin", v)) return LineError{0, 1, *e};
    if (auto e = numbers(j["direction"], 3, "direction", v + 3)) return LineError{0, 1, *e};
    assign(ray, v, 6);
    for (const char* key : {"tmin", "tmax"}) {
      if (!j.contains(key)) continue;
      if (!j[key].is_number()) return LineError{0, 1, std::string(key) + " is not a number"};
      (key[1] == 'm' && key[2] == 'i' ? ray->tmin : ray->tmax) = j[key].get<float>();
    }
  } else {
    return LineError{0, 1, "expected a JSON object or array"};
  }
  if (auto bad = checkRay(*ray)) return LineError{0, 1, bad->first};
  return std::nullopt;
}

bool isColumnNames(std::string_view line) {
  std::string compact;
  for (char c : line)
    if (!isBlank(c)) compact.push_back(c);
  return compact == "ox,oy,oz,dx,dy,dz" || compact == "ox,oy,oz,dx,dy,dz,tmin,tmax";
}

void appendNumber(std::string& out, float v) {
  char buf[32];
  const int n = std::snprintf(buf, sizeof buf, "%.9g", double(v));
  out.append(buf, size_t(n));
}

}  // namespace

std::optional<std::pair<std::string, int>> checkRay(const Ray& ray) {
  if (rayIsGood(ray)) return std::nullopt;
  const float v[6] = {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z};
  for (int k = 0; k < 6; ++k)
    if (!std::isfinite(v[k])) return std::pair{std::string(k < 3 ? "the origin" : "the direction") + " is not finite", k};
  if (v[3] == 0 && v[4] == 0 && v[5] == 0) return std::pair{std::string("the direction is zero"), 3};
  if (std::isnan(ray.tmin) || std::isnan(ray.tmax)) return std::pair{std::string("tmin or tmax is NaN"), 6};
  if (ray.tmin > ray.tmax) return std::pair{std::string("tmin is greater than tmax"), 6};
  return std::nullopt;
}

ParsedRays parseRayLines(std::string_view text, float tmin, float tmax) {
  ParsedRays out;
  uint64_t lineNo = 0;
  bool firstContent = true;
  size_t pos = 0;
  // A UTF-8 byte order mark (what some editors write first) is not part of the first line.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") pos = 3;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (const size_t nul = line.find('\0'); nul != std::string_view::npos) {
      out.error = LineError{lineNo, nul + 1, "a NUL byte: the input is not text (a .npy file must be named *.npy)"};
      return out;
    }
    size_t s = 0;
    while (s < line.size() && isBlank(line[s])) ++s;
    if (s == line.size() || line[s] == '#') continue;
    if (firstContent && isColumnNames(line)) {
      firstContent = false;
      continue;
    }
    firstContent = false;
    Ray ray{{}, {}, tmin, tmax};
    std::optional<LineError> e = (line[s] == '{' || line[s] == '[') ? parseJson(line, &ray) : parseCsv(line, &ray);
    if (e) {
      e->line = lineNo;
      out.error = std::move(e);
      return out;
    }
    out.rays.push_back(ray);
  }
  return out;
}

std::vector<Column> defaultColumns(bool sites, bool visibility) {
  std::vector<Column> out;
  for (int c = 0; c <= int(Column::kInside); ++c) out.push_back(Column(c));
  if (sites) out.insert(out.end(), {Column::kSample, Column::kI, Column::kJ});
  if (visibility) out.push_back(Column::kVisibility);
  return out;
}

std::optional<std::string> parseColumns(std::string_view list, std::vector<Column>* out) {
  out->clear();
  size_t pos = 0;
  while (true) {
    const size_t comma = std::min(list.find(',', pos), list.size());
    const std::string_view name = list.substr(pos, comma - pos);
    int found = -1;
    for (int c = 0; c < kAllColumns; ++c)
      if (name == kColumns[c]) found = c;
    if (found < 0) {
      std::string known;
      for (int c = 0; c < kAllColumns; ++c) known.append(c ? "," : "").append(kColumns[c]);
      return "unknown column \"" + std::string(name) + "\" (the columns: " + known + ")";
    }
    if (hasColumn(*out, Column(found))) return "column \"" + std::string(name) + "\" named twice";
    out->push_back(Column(found));
    if (comma == list.size()) return std::nullopt;
    pos = comma + 1;
  }
}

namespace {

// One CSV field of answer i.
void appendCsv(std::string& out, const Answers& a, size_t i, Column c) {
  const QueryHit& h = a.hits[i];
  const LookupSite s = a.sites.empty() ? LookupSite{} : a.sites[i];
  switch (c) {
    case Column::kHit: out += h.hit ? '1' : '0'; return;
    case Column::kT: h.hit ? appendNumber(out, h.t) : void(out += "inf"); return;
    case Column::kX: h.hit ? appendNumber(out, h.point.x) : void(out += "nan"); return;
    case Column::kY: h.hit ? appendNumber(out, h.point.y) : void(out += "nan"); return;
    case Column::kZ: h.hit ? appendNumber(out, h.point.z) : void(out += "nan"); return;
    case Column::kNx: h.hasNormal ? appendNumber(out, h.normal.x) : void(out += "nan"); return;
    case Column::kNy: h.hasNormal ? appendNumber(out, h.normal.y) : void(out += "nan"); return;
    case Column::kNz: h.hasNormal ? appendNumber(out, h.normal.z) : void(out += "nan"); return;
    case Column::kInside: out += h.inside ? '1' : '0'; return;
    case Column::kSample: out += s.valid ? std::to_string(s.sample) : "-1"; return;
    case Column::kI: out += s.valid ? std::to_string(s.i) : "-1"; return;
    case Column::kJ: out += s.valid ? std::to_string(s.j) : "-1"; return;
    case Column::kVisibility: appendNumber(out, a.visibility.empty() ? 1.0f : a.visibility[i]); return;
  }
}

}  // namespace

void answerRows(const Answers& a, float* rows) {
  // Row by row: every column's value of a ray computed with selects, not branches (whether a ray
  // hit is as good as random), then the asked-for ones copied out in the asked-for order.
  const size_t cols = a.columns.size(), n = a.hits.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  uint8_t pick[kAllColumns];
  constexpr size_t kDefaultColumns = size_t(Column::kVisibility);  // hit .. j
  bool leading = true;  // the columns are the first `cols` of the full row, in order
  for (size_t c = 0; c < cols; ++c) pick[c] = uint8_t(a.columns[c]), leading = leading && pick[c] == c;
  const bool sites = !a.sites.empty(), vis = !a.visibility.empty();
  for (size_t i = 0; i < n; ++i) {
    const QueryHit& h = a.hits[i];
    const LookupSite s = sites ? a.sites[i] : LookupSite{};
    // (sample indices stay below 2^24, so float32 holds them exactly)
    const float row[kAllColumns] = {h.hit ? 1.0f : 0.0f,
                                    h.t,
                                    h.hit ? h.point.x : nan,
                                    h.hit ? h.point.y : nan,
                                    h.hit ? h.point.z : nan,
                                    h.hasNormal ? h.normal.x : nan,
                                    h.hasNormal ? h.normal.y : nan,
                                    h.hasNormal ? h.normal.z : nan,
                                    h.inside ? 1.0f : 0.0f,
                                    s.valid ? float(s.sample) : -1.0f,
                                    s.valid ? float(s.i) : -1.0f,
                                    s.valid ? float(s.j) : -1.0f,
                                    vis ? a.visibility[i] : 1.0f};
    float* out = rows + i * cols;
    if (leading && cols == kDefaultColumns) {
      std::memcpy(out, row, kDefaultColumns * sizeof(float));  // (a constant size: plain stores)
    } else {
      for (size_t c = 0; c < cols; ++c) out[c] = row[pick[c]];
    }
  }
}

std::vector<uint8_t> formatAnswers(const Answers& a, OutputFormat format) {
  const size_t cols = a.columns.size();
  if (format == OutputFormat::kNpy) {
    std::vector<float> m(a.hits.size() * cols);
    answerRows(a, m.data());
    return npyMatrixBytes(m, a.hits.size(), cols);
  }
  std::string out;
  out.reserve(a.hits.size() * 80 + 80);
  if (format == OutputFormat::kCsv) {
    for (size_t c = 0; c < cols; ++c) out += c ? "," : "", out += kColumns[int(a.columns[c])];
    out += '\n';
    for (size_t i = 0; i < a.hits.size(); ++i) {
      for (size_t c = 0; c < cols; ++c) {
        if (c) out += ',';
        appendCsv(out, a, i, a.columns[c]);
      }
      out += '\n';
    }
    return {out.begin(), out.end()};
  }
  const bool sites = needsSites(a.columns), vis = hasColumn(a.columns, Column::kVisibility);
  for (size_t i = 0; i < a.hits.size(); ++i) {
    const QueryHit& h = a.hits[i];
    const LookupSite s = sites ? a.sites[i] : LookupSite{};
    out += h.hit ? "{\"hit\":true,\"t\":" : "{\"hit\":false,\"t\":null";
    if (h.hit) {
      appendNumber(out, h.t);
      out += ",\"point\":[";
      appendNumber(out, h.point.x), out += ',', appendNumber(out, h.point.y), out += ',', appendNumber(out, h.point.z);
      out += ']';
    } else {
      out += ",\"point\":null";
    }
    if (h.hasNormal) {
      out += ",\"normal\":[";
      appendNumber(out, h.normal.x), out += ',', appendNumber(out, h.normal.y), out += ',', appendNumber(out, h.normal.z);
      out += ']';
    } else {
      out += ",\"normal\":null";
    }
    out += h.inside ? ",\"inside\":true" : ",\"inside\":false";
    if (sites && s.valid)
      out += ",\"sample\":" + std::to_string(s.sample) + ",\"texel\":[" + std::to_string(s.i) + ',' +
             std::to_string(s.j) + ']';
    else if (sites)
      out += ",\"sample\":null,\"texel\":null";
    if (vis) {
      out += ",\"visibility\":";
      appendNumber(out, a.visibility[i]);
    }
    out += "}\n";
  }
  return {out.begin(), out.end()};
}

}  // namespace vff::query_tool
