// json_text.cpp - the META text check (json_text.h).
#include "container/json_text.h"

#include <cstdint>
#include <cstdio>
#include <vector>

namespace vff::detail {

namespace {

bool isWs(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }
int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

class Checker {
 public:
  Checker(std::string_view t, int maxDepth) : t_(t), maxDepth_(maxDepth) {}

  JsonTextCheck run() {
    JsonTextCheck r;
    if (t_.substr(0, 3) == "\xEF\xBB\xBF") {
      r.problem = "begins with a UTF-8 byte-order mark (RFC 8259 section 8.1 forbids it)";
      return r;
    }
    skipWs();
    r.isObject = pos_ < t_.size() && t_[pos_] == '{';
    if (value()) {
      skipWs();
      if (pos_ != t_.size()) fail(std::to_string(t_.size() - pos_) + " bytes follow the JSON value");
    }
    r.problem = problem_;
    return r;
  }

 private:
  bool fail(const std::string& what) {
    problem_ = what + " at byte " + std::to_string(pos_);
    return false;
  }
  bool failByte(const char* what) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", unsigned(uint8_t(t_[pos_])));
    return fail(std::string(what) + " " + hex);
  }
  void skipWs() {
    while (pos_ < t_.size() && isWs(t_[pos_])) ++pos_;
  }
  char closer() const { return stack_.back() == '{' ? '}' : ']'; }

  // One value, containers included; on return pos_ is just after it.
  bool value() {
    for (;;) {
      skipWs();
      if (pos_ >= t_.size()) return fail("the text ends where a value is expected");
      const char c = t_[pos_];
      bool closed = false;
      if (c == '{' || c == '[') {
        if (int(stack_.size()) >= maxDepth_)
          return fail("arrays/objects nest deeper than " + std::to_string(maxDepth_) + " levels");
        stack_.push_back(c);
        ++pos_;
        skipWs();
        if (pos_ < t_.size() && t_[pos_] == closer()) {
          ++pos_;
          stack_.pop_back();
          closed = true;
        } else if (c == '[') {
          continue;
        } else if (!memberKey()) {
          return false;
        } else {
          continue;
        }
      }
      if (!closed && !scalar(c)) return false;
      // After a value: close containers until a ',' asks for the next value.
      for (;;) {
        if (stack_.empty()) return true;
        skipWs();
        if (pos_ >= t_.size()) return fail("the text ends inside an array or object");
        if (t_[pos_] == closer()) {
          ++pos_;
          stack_.pop_back();
          continue;
        }
        if (t_[pos_] != ',') return failByte(stack_.back() == '{' ? "expected ',' or '}', found" : "expected ',' or ']', found");
        ++pos_;
        if (stack_.back() == '{' && !memberKey()) return false;
        break;
      }
    }
  }

  bool memberKey() {
    skipWs();
    if (pos_ >= t_.size()) return fail("the text ends where an object key is expected");
    if (t_[pos_] != '"') return failByte("expected a string key, found");
    if (!string()) return false;
    skipWs();
    if (pos_ >= t_.size()) return fail("the text ends where ':' is expected");
    if (t_[pos_] != ':') return failByte("expected ':', found");
    ++pos_;
    return true;
  }

  bool scalar(char c) {
    if (c == '"') return string();
    if (c == '-' || isDigit(c)) return number();
    for (std::string_view lit : {"true", "false", "null"}) {
      if (t_.substr(pos_, lit.size()) == lit) {
        pos_ += lit.size();
        return true;
      }
    }
    return failByte("unexpected byte");
  }

  bool digits() {
    if (pos_ >= t_.size() || !isDigit(t_[pos_])) return fail("a number lacks a digit");
    while (pos_ < t_.size() && isDigit(t_[pos_])) ++pos_;
    return true;
  }

  // RFC 8259 section 6 grammar; the magnitude is not limited.
  bool number() {
    if (t_[pos_] == '-') ++pos_;
    if (pos_ < t_.size() && t_[pos_] == '0') {
      ++pos_;
      if (pos_ < t_.size() && isDigit(t_[pos_])) return fail("a number has a leading zero");
    } else if (!digits()) {
      return false;
    }
    if (pos_ < t_.size() && t_[pos_] == '.') {
      ++pos_;
      if (!digits()) return false;
    }
    if (pos_ < t_.size() && (t_[pos_] == 'e' || t_[pos_] == 'E')) {
      ++pos_;
      if (pos_ < t_.size() && (t_[pos_] == '+' || t_[pos_] == '-')) ++pos_;
      if (!digits()) return false;
    }
    return true;
  }

  // The code unit of the \uXXXX escape at pos_ (which is at the backslash), or -1.
  int escapeUnit(size_t at) const {
    if (at + 6 > t_.size() || t_[at] != '\\' || t_[at + 1] != 'u') return -1;
    int v = 0;
    for (size_t i = at + 2; i < at + 6; ++i) {
      const int h = hexValue(t_[i]);
      if (h < 0) return -1;
      v = v * 16 + h;
    }
    return v;
  }

  bool escape() {
    if (pos_ + 1 >= t_.size()) return fail("the text ends inside an escape");
    const char e = t_[pos_ + 1];
    if (e != 'u') {
      if (std::string_view("\"\\/bfnrt").find(e) == std::string_view::npos) return ++pos_, failByte("invalid escape");
      pos_ += 2;
      return true;
    }
    const int u = escapeUnit(pos_);
    if (u < 0) return fail("a \\u escape lacks four hex digits");
    if (u >= 0xDC00 && u <= 0xDFFF) return fail("a low surrogate escape without a high surrogate before it");
    if (u >= 0xD800 && u <= 0xDBFF) {
      const int low = escapeUnit(pos_ + 6);
      if (low < 0xDC00 || low > 0xDFFF) return fail("a high surrogate escape without a low surrogate after it");
      pos_ += 6;
    }
    pos_ += 6;
    return true;
  }

  // One UTF-8 encoded character of U+0080 or above (RFC 3629: shortest form, no surrogates).
  bool utf8() {
    const auto b = [&](size_t i) { return pos_ + i < t_.size() ? uint8_t(t_[pos_ + i]) : uint8_t(0); };
    const uint8_t lead = b(0);
    size_t more = 0;
    uint8_t lo = 0x80, hi = 0xBF;
    if (lead >= 0xC2 && lead <= 0xDF) more = 1;
    else if (lead >= 0xE0 && lead <= 0xEF) more = 2, lo = lead == 0xE0 ? 0xA0 : 0x80, hi = lead == 0xED ? 0x9F : 0xBF;
    else if (lead >= 0xF0 && lead <= 0xF4) more = 3, lo = lead == 0xF0 ? 0x90 : 0x80, hi = lead == 0xF4 ? 0x8F : 0xBF;
    else return failByte("invalid UTF-8 lead byte");
    for (size_t i = 1; i <= more; ++i) {
      const uint8_t c = b(i);
      if (c < (i == 1 ? lo : 0x80) || c > (i == 1 ? hi : 0xBF)) return fail("invalid UTF-8 sequence");
    }
    pos_ += more + 1;
    return true;
  }

  bool string() {
    ++pos_;  // the opening quote
    for (;;) {
      if (pos_ >= t_.size()) return fail("the text ends inside a string");
      const uint8_t c = uint8_t(t_[pos_]);
      if (c == '"') {
        ++pos_;
        return true;
      }
      if (c < 0x20) return failByte("unescaped control character");
      if (c == '\\') {
        if (!escape()) return false;
      } else if (c >= 0x80) {
        if (!utf8()) return false;
      } else {
        ++pos_;
      }
    }
  }

  std::string_view t_;
  int maxDepth_;
  size_t pos_ = 0;
  std::vector<char> stack_;
  std::string problem_;
};

}  // namespace

JsonTextCheck checkJsonText(std::string_view text, int maxDepth) { return Checker(text, maxDepth).run(); }

}  // namespace vff::detail
