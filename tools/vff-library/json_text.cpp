// json_text.cpp - a strict scan of a JSON text (json_text.h): RFC 8259's grammar, with the places of
// problems, before nlohmann::json reads the values.
#include "json_text.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <set>

#include <nlohmann/json.hpp>

namespace vff::library {

void appendPathKey(std::string& path, std::string_view key) {
  const bool plain = !key.empty() && !(key[0] >= '0' && key[0] <= '9') &&
                     key.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") ==
                         std::string_view::npos;
  if (plain) {
    if (!path.empty()) path += '.';
    path += key;
  } else {
    path += '[';
    path += nlohmann::json(std::string(key)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    path += ']';
  }
}

namespace {

class Scanner {
 public:
  explicit Scanner(std::string_view t) : t_(t) {}

  std::optional<JsonTextProblem> run() {
    if (t_.substr(0, 3) == "\xEF\xBB\xBF") i_ = 3;  // RFC 8259 section 8.1: a parser may ignore it
    if (value(0)) {
      space();
      if (i_ < t_.size()) fail(i_, t_[i_] == '\0' ? "a NUL byte after the value" : "more text after the value");
    }
    return problem_;
  }

 private:
  bool fail(size_t at, const std::string& message) {
    if (problem_) return false;
    JsonTextProblem p;
    p.byte = at;
    for (size_t k = 0; k < at && k < t_.size(); ++k) {
      if (t_[k] == '\n') ++p.line, p.column = 1;
      else ++p.column;
    }
    // A deep path keeps its end, where the problem is.
    p.path = path_.size() > 80 ? "..." + path_.substr(path_.size() - 77) : path_;
    p.message = message;
    problem_ = p;
    return false;
  }
  bool end() const { return i_ >= t_.size(); }
  unsigned char at() const { return static_cast<unsigned char>(t_[i_]); }
  void space() {
    while (!end() && (t_[i_] == ' ' || t_[i_] == '\t' || t_[i_] == '\n' || t_[i_] == '\r')) ++i_;
  }
  std::string unexpected() const {
    if (end()) return "the text ends";
    const unsigned char c = at();
    if (c == 0) return "a NUL byte";
    char s[32];
    if (c < 0x20 || c >= 0x7F) std::snprintf(s, sizeof s, "byte 0x%02X", c);
    else std::snprintf(s, sizeof s, "'%c'", c);
    return s;
  }

  // A value whose containers are `depth` deep.
  bool value(int depth) {
    space();
    if (end()) return fail(i_, "a value expected; the text ends");
    const char c = t_[i_];
    if (c == '{' || c == '[') {
      if (depth + 1 > kJsonMaxDepth)
        return fail(i_, "objects and arrays nested deeper than " + std::to_string(kJsonMaxDepth));
      return c == '{' ? object(depth + 1) : array(depth + 1);
    }
    if (c == '"') {
      std::string s;
      return string(&s);
    }
    if (c == '-' || (c >= '0' && c <= '9')) return number();
    for (const char* word : {"true", "false", "null"})
      if (t_.substr(i_, std::strlen(word)) == word) return i_ += std::strlen(word), true;
    return fail(i_, "a value expected, not " + unexpected());
  }

  bool object(int depth) {
    ++i_;
    space();
    if (!end() && t_[i_] == '}') return ++i_, true;
    std::set<std::string> names;
    const size_t pathSize = path_.size();
    for (;;) {
      space();
      if (end() || t_[i_] != '"') return fail(i_, "a member name (a string) expected, not " + unexpected());
      const size_t nameAt = i_;
      std::string name;
      if (!string(&name)) return false;
      if (!names.insert(name).second) {
        return fail(nameAt, "the member name " + nlohmann::json(name).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
                                " appears twice in this object");
      }
      appendPathKey(path_, name);
      space();
      if (end() || t_[i_] != ':') return fail(i_, "':' expected after a member name, not " + unexpected());
      ++i_;
      if (!value(depth)) return false;
      path_.resize(pathSize);
      space();
      if (!end() && t_[i_] == ',') {
        ++i_;
        continue;
      }
      if (!end() && t_[i_] == '}') return ++i_, true;
      return fail(i_, "',' or '}' expected, not " + unexpected());
    }
  }

  bool array(int depth) {
    ++i_;
    space();
    if (!end() && t_[i_] == ']') return ++i_, true;
    const size_t pathSize = path_.size();
    for (size_t n = 0;; ++n) {
      path_ += '[';
      path_ += std::to_string(n);
      path_ += ']';
      if (!value(depth)) return false;
      path_.resize(pathSize);
      space();
      if (!end() && t_[i_] == ',') {
        ++i_;
        continue;
      }
      if (!end() && t_[i_] == ']') return ++i_, true;
      return fail(i_, "',' or ']' expected, not " + unexpected());
    }
  }

  // Four hex digits at i_, as a number (or -1).
  long hex4() const {
    if (i_ + 4 > t_.size()) return -1;
    long v = 0;
    for (size_t k = i_; k < i_ + 4; ++k) {
      const char c = t_[k];
      const int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (d < 0) return -1;
      v = v * 16 + d;
    }
    return v;
  }

  static void putUtf8(std::string* out, long cp) {
    if (cp < 0x80) {
      *out += char(cp);
    } else if (cp < 0x800) {
      *out += char(0xC0 | (cp >> 6)), *out += char(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      *out += char(0xE0 | (cp >> 12)), *out += char(0x80 | ((cp >> 6) & 0x3F)), *out += char(0x80 | (cp & 0x3F));
    } else {
      *out += char(0xF0 | (cp >> 18)), *out += char(0x80 | ((cp >> 12) & 0x3F));
      *out += char(0x80 | ((cp >> 6) & 0x3F)), *out += char(0x80 | (cp & 0x3F));
    }
  }

  // One UTF-8 sequence at i_ (RFC 3629: no overlong forms, no surrogates, at most U+10FFFF).
  bool utf8(std::string* out) {
    const unsigned char c = at();
    int n = 0;
    long cp = 0, min = 0;
    if (c >= 0xC2 && c <= 0xDF) n = 1, cp = c & 0x1F, min = 0x80;
    else if (c >= 0xE0 && c <= 0xEF) n = 2, cp = c & 0x0F, min = 0x800;
    else if (c >= 0xF0 && c <= 0xF4) n = 3, cp = c & 0x07, min = 0x10000;
    else return fail(i_, "invalid UTF-8 (byte 0x" + hexByte(c) + ")");
    for (int k = 1; k <= n; ++k) {
      if (i_ + size_t(k) >= t_.size() || (static_cast<unsigned char>(t_[i_ + k]) & 0xC0) != 0x80)
        return fail(i_, "invalid UTF-8 (a sequence cut short)");
      cp = (cp << 6) | (static_cast<unsigned char>(t_[i_ + k]) & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return fail(i_, "invalid UTF-8 (an overlong form, a surrogate or beyond U+10FFFF)");
    out->append(t_.substr(i_, size_t(n) + 1));
    i_ += size_t(n) + 1;
    return true;
  }
  static std::string hexByte(unsigned char c) {
    char s[4];
    std::snprintf(s, sizeof s, "%02X", c);
    return s;
  }

  bool string(std::string* out) {
    ++i_;
    for (;;) {
      if (end()) return fail(i_, "the text ends inside a string");
      const unsigned char c = at();
      if (c == '"') return ++i_, true;
      if (c < 0x20) return fail(i_, "a control character (byte 0x" + hexByte(c) + ") in a string must be escaped");
      if (c >= 0x80) {
        if (!utf8(out)) return false;
        continue;
      }
      if (c != '\\') {
        *out += char(c);
        ++i_;
        continue;
      }
      const size_t escape = i_++;
      if (end()) return fail(i_, "the text ends inside a string");
      const char e = t_[i_++];
      static const std::string_view simple = "\"\\/bfnrt", meaning = "\"\\/\b\f\n\r\t";
      if (const size_t k = simple.find(e); k != std::string_view::npos) {
        *out += meaning[k];
        continue;
      }
      if (e != 'u') return fail(escape, "an unknown escape \\" + std::string(1, e));
      long cp = hex4();
      if (cp < 0) return fail(escape, "\\u needs four hex digits");
      i_ += 4;
      if (cp >= 0xDC00 && cp <= 0xDFFF) return fail(escape, "a \\u escape of a low surrogate without its high one");
      if (cp >= 0xD800 && cp <= 0xDBFF) {
        const long low = t_.substr(i_, 2) == "\\u" ? (i_ += 2, hex4()) : -1;
        if (low < 0xDC00 || low > 0xDFFF) return fail(escape, "a \\u escape of a high surrogate without its low one");
        i_ += 4;
        cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
      }
      putUtf8(out, cp);
    }
  }

  bool digits() {
    const size_t from = i_;
    while (!end() && t_[i_] >= '0' && t_[i_] <= '9') ++i_;
    return i_ > from;
  }

  bool number() {
    const size_t from = i_;
    if (t_[i_] == '-') ++i_;
    if (!end() && t_[i_] == '0') ++i_;
    else if (!digits()) return fail(from, "a malformed number");
    if (!end() && t_[i_] == '.' && (++i_, !digits())) return fail(from, "a malformed number (digits expected after '.')");
    if (!end() && (t_[i_] == 'e' || t_[i_] == 'E')) {
      ++i_;
      if (!end() && (t_[i_] == '+' || t_[i_] == '-')) ++i_;
      if (!digits()) return fail(from, "a malformed number (digits expected in the exponent)");
    }
    const std::string text(t_.substr(from, i_ - from));
    if (!std::isfinite(std::strtod(text.c_str(), nullptr)))
      return fail(from, "the number " + text + " is beyond binary64's range (at most about 1.8e308)");
    return true;
  }

  std::string_view t_;
  size_t i_ = 0;
  std::string path_;
  std::optional<JsonTextProblem> problem_;
};

}  // namespace

std::optional<JsonTextProblem> checkJsonText(std::string_view text) { return Scanner(text).run(); }

}  // namespace vff::library
