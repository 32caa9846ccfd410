// json_text.h - the JSON text rules of a library manifest (spec/library.md section 1), which scene
// descriptions share: one JSON text in UTF-8, a leading byte-order mark ignored, nothing but JSON
// whitespace after the value, objects and arrays nested at most kJsonMaxDepth deep, every number a
// finite binary64, no member name twice in one object, strings valid UTF-8 with paired surrogates.
// Checked before the document's own values, so that nlohmann::json then parses the text without a
// choice of its own (it ends a text at a NUL byte, keeps the last of two equal names).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vff::library {

// How deep objects and arrays may nest: the top-level value is depth 1.
inline constexpr int kJsonMaxDepth = 64;

struct JsonTextProblem {
  uint64_t byte = 0;    // 0-based offset of the byte where the problem was found
  uint32_t line = 1;    // 1-based; lines end at LF
  uint32_t column = 1;  // 1-based, counted in bytes
  std::string path;     // JSON path of the value being read ("entries[2].options"), "" at the top
  std::string message;  // what is wrong
};

// The first problem of `text` in text order; nothing when it follows the rules.
std::optional<JsonTextProblem> checkJsonText(std::string_view text);

// Appends a member name to a JSON path: ".name" for ASCII letters, digits, '_' and '-' not starting
// with a digit, else ["..."] (the name as a JSON string).
void appendPathKey(std::string& path, std::string_view key);

}  // namespace vff::library
