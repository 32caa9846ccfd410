// strict_json.cpp - the JSON text rules of vff's JSON documents (vff/strict_json.h), on
// nlohmann-json's SAX parser: the parser checks the syntax, UTF-8, surrogates and the binary64 range
// of numbers; the handler below adds the depth limit and repeated names and builds the value.
#include <algorithm>
#include <cstddef>
#include <iterator>
#include <string>
#include <vector>

#include "scene/strict_json_dom.h"

namespace vff {
namespace {

using nlohmann::json;

// A pointer into the text that records how far the parser has read, so that a problem the handler
// finds (it gets no position) can still be placed.
class CountingIterator {
 public:
  using iterator_category = std::input_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  CountingIterator(const char* p, const char** high) : p_(p), high_(high) {}
  reference operator*() const { return *p_; }
  CountingIterator& operator++() {
    ++p_;
    if (high_ && p_ > *high_) *high_ = p_;
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator old = *this;
    ++*this;
    return old;
  }
  bool operator==(const CountingIterator& o) const { return p_ == o.p_; }
  bool operator!=(const CountingIterator& o) const { return p_ != o.p_; }

 private:
  const char* p_;
  const char** high_;
};

bool isPlainKey(std::string_view key) {
  if (key.empty() || (key[0] >= '0' && key[0] <= '9')) return false;
  for (char c : key)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

JsonTextProblem placed(std::string_view text, std::size_t at, std::string path, std::string what) {
  JsonTextProblem p;
  p.byte = at;
  for (std::size_t i = 0; i < at && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++p.line;
      p.column = 1;
    } else {
      ++p.column;
    }
  }
  p.path = std::move(path);
  p.message = std::move(what);
  return p;
}

// nlohmann's message without its "[json.exception...] " tag and its own place (ours replaces it).
std::string parserMessage(const nlohmann::detail::exception& ex) {
  std::string m = ex.what();
  if (const size_t tag = m.find("] "); tag != std::string::npos) m.erase(0, tag + 2);
  if (m.rfind("parse error", 0) == 0) {
    if (const size_t colon = m.find(": "); colon != std::string::npos) m.erase(0, colon + 2);
  }
  // The bytes it quotes ("; last read: '...'") may be the very ones that are not UTF-8: the place
  // stands for them.
  if (const size_t read = m.find("; last read: "); read != std::string::npos) {
    const size_t expected = m.find("; expected", read);
    m.erase(read, expected == std::string::npos ? std::string::npos : expected - read);
  }
  return m;
}

// Builds the value as nlohmann's DOM parser does (iteratively: a hostile depth cannot reach the
// stack), refusing what the parser lets through.
class Handler {
 public:
  Handler(std::string_view text, const char** high, json& root) : text_(text), high_(high), root_(root) {}

  bool null() { return value(json(nullptr)); }
  bool boolean(bool v) { return value(json(v)); }
  bool number_integer(json::number_integer_t v) { return value(json(v)); }
  bool number_unsigned(json::number_unsigned_t v) { return value(json(v)); }
  bool number_float(json::number_float_t v, const std::string&) { return value(json(v)); }
  bool string(std::string& v) { return value(json(std::move(v))); }
  bool binary(json::binary_t&) { return fail(consumed(), "binary values are not JSON"); }

  bool start_object(std::size_t) { return open(json::object()); }
  bool start_array(std::size_t) { return open(json::array()); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(std::string& k) {
    json& obj = *stack_.back();
    keys_.back() = k;
    if (obj.contains(k)) {
      std::string what = "the member name ";
      what += json(k).dump();
      what += " is repeated in one object";
      return fail(keyStart(), what);
    }
    return true;
  }

  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& ex) {
    // `position` counts the bytes read, the one in error included (and the end of the text).
    std::size_t at = position > 0 ? position - 1 : 0;
    if (at > text_.size()) at = text_.size();
    std::string what;
    if (at < text_.size() && text_[at] == '\0')
      what = "a NUL byte (JSON allows none outside strings, and in a string only as \\u0000)";
    else if (ex.id == 406) {
      at = numberStart(at);
      what = "the number " + numberText(at) + " is not representable as a finite binary64";
    }
    else if (std::string_view(ex.what()).find("expected end of input") != std::string_view::npos)
      what = "a byte after the JSON value (only whitespace may follow it)";
    else
      what = parserMessage(ex);
    return fail(at, what);
  }

  std::optional<JsonTextProblem> problem;

 private:
  // The number whose last byte (or the byte after it, which the parser reads) is at `at`.
  static bool inNumber(char c) { return std::string_view("0123456789+-.eE").find(c) != std::string_view::npos; }
  std::size_t numberStart(std::size_t at) const {
    std::size_t b = std::min(at + 1, text_.size());
    while (b > 0 && inNumber(text_[b - 1])) --b;
    return b;
  }
  std::string numberText(std::size_t start) const {
    std::size_t e = start;
    while (e < text_.size() && inNumber(text_[e])) ++e;
    return std::string(text_.substr(start, e - start));
  }

  std::size_t consumed() const { return std::size_t(*high_ - text_.data()); }

  // The opening quote of the key just read: the parser has read up to its closing quote.
  std::size_t keyStart() const {
    std::size_t close = consumed() - 1;
    for (std::size_t i = close; i-- > 0;) {
      if (text_[i] != '"') continue;
      std::size_t slashes = 0;
      while (i - slashes > 0 && text_[i - slashes - 1] == '\\') ++slashes;
      if (slashes % 2 == 0) return i;
    }
    return close;
  }

  std::string segment() const {
    if (stack_.empty()) return {};
    const json& top = *stack_.back();
    if (top.is_array()) return "[" + std::to_string(top.size()) + "]";
    std::string s;
    appendJsonPathKey(s, keys_.back());
    return s[0] == '[' ? s : "." + s;  // (path() drops a leading '.')
  }

  std::string path() const {
    std::string p;
    for (const std::string& s : segments_) p += s;
    p += segment();
    if (!p.empty() && p[0] == '.') p.erase(0, 1);
    return p;
  }

  json* add(json&& v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    json& top = *stack_.back();
    if (top.is_array()) {
      top.push_back(std::move(v));
      return &top.back();
    }
    json& slot = top[keys_.back()];
    slot = std::move(v);
    return &slot;
  }

  bool value(json&& v) {
    add(std::move(v));
    return true;
  }

  bool open(json&& container) {
    if (int(stack_.size()) + 1 > kStrictJsonMaxDepth) {
      return fail(consumed() - 1, "objects and arrays nest deeper than " + std::to_string(kStrictJsonMaxDepth) +
                                      " (a reader limit)");
    }
    std::string seg = segment();
    json* v = add(std::move(container));
    segments_.push_back(std::move(seg));
    stack_.push_back(v);
    keys_.emplace_back();
    return true;
  }

  bool close() {
    stack_.pop_back();
    segments_.pop_back();
    keys_.pop_back();
    return true;
  }

  bool fail(std::size_t at, const std::string& what) {
    problem = placed(text_, at, path(), what);
    return false;
  }

  std::string_view text_;
  const char** high_;
  json& root_;
  std::vector<json*> stack_;
  std::vector<std::string> segments_;  // where each open container stands in its parent
  std::vector<std::string> keys_;      // each open object's last member name
};

}  // namespace

void appendJsonPathKey(std::string& path, std::string_view key) {
  if (isPlainKey(key)) {
    if (!path.empty()) path += '.';
    path += key;
  } else {
    path += '[';
    path += json(std::string(key)).dump();
    path += ']';
  }
}

std::string describeJsonProblem(const JsonTextProblem& p, const std::string& fileName) {
  std::string s = fileName + ":" + std::to_string(p.line) + ":" + std::to_string(p.column) + ": ";
  if (!p.path.empty()) s += p.path + ": ";
  return s + p.message;
}

std::optional<JsonTextProblem> detail::parseStrictJson(std::string_view text, json& out) {
  const char* high = text.data();
  Handler h(text, &high, out);
  const CountingIterator first(text.data(), &high), last(text.data() + text.size(), nullptr);
  const bool ok = json::sax_parse(first, last, &h, json::input_format_t::json, true, false);
  if (h.problem) return h.problem;
  // The handler places every problem it stops on; this one stands for a parser that stopped without.
  if (!ok) return placed(text, std::size_t(high - text.data()), "", "the JSON parser stopped here");
  // The parser takes a NUL byte for the end of the text: only the first one can have ended a value
  // it accepted (one before it would have been an error).
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    return placed(text, nul, "", "a NUL byte after the JSON value (only whitespace may follow it)");
  return std::nullopt;
}

std::optional<JsonTextProblem> checkStrictJson(std::string_view text) {
  json value;
  return detail::parseStrictJson(text, value);
}

}  // namespace vff
