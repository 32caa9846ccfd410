// json_text.h - the META text check (spec/format.md section 9, rule 8001): one JSON text as
// RFC 8259 defines it, checked byte by byte without building a value.
#pragma once

#include <string>
#include <string_view>

namespace vff::detail {

// How deep META's arrays and objects may nest (spec/format.md section 9).
inline constexpr int kMaxJsonDepth = 64;

struct JsonTextCheck {
  std::string problem;    // empty when the text is valid; else what is wrong, with its byte offset
  bool isObject = false;  // the top-level value is an object (meaningful when problem is empty)
};

// Checks that `text` is exactly one JSON value with optional whitespace around it: UTF-8 without a
// byte-order mark, no bytes after the value, arrays/objects nested at most `maxDepth` deep, and every
// \u escape of a surrogate part of a high-low pair. Numbers are checked as text only, so any
// magnitude is accepted. Iterative, so hostile nesting cannot exhaust the stack.
JsonTextCheck checkJsonText(std::string_view text, int maxDepth);

}  // namespace vff::detail
