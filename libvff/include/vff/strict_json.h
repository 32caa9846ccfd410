// vff/strict_json.h - the JSON text rules that vff's JSON documents share: scene descriptions
// (spec/scene.md section 1) and library manifests.
//
// Each of those documents is one JSON text (RFC 8259) in UTF-8, read by these rules:
//   1. A leading UTF-8 byte-order mark (EF BB BF) is ignored (RFC 8259 section 8.1 allows a parser
//      to); nothing else but JSON whitespace may stand before the value.
//   2. After the value only JSON whitespace (space, tab, LF, CR) may follow: a NUL byte or any other
//      byte there is an error.
//   3. Objects and arrays nest at most kStrictJsonMaxDepth deep (a reader limit).
//   4. Every number is representable as a finite IEEE binary64 (`1e400` is an error wherever it
//      stands, application data included). Unlike META (rule 8001, which checks numbers as text),
//      these documents are read as values, and a value out of binary64's range has none.
//   5. A member name appears at most once in an object (RFC 8259 leaves a repeated name's meaning
//      undefined, so readers would disagree).
//   6. Strings are valid UTF-8, and \u escapes pair their surrogates.
//   7. A problem is reported with its place: LINE:COLUMN (1-based; the column counts bytes) and the
//      JSON path of the value being read.
// A check of the document's values (a member's type, a range) is the document's own and comes after
// this one:
//
//   if (auto p = vff::checkStrictJson(text)) {
//     fprintf(stderr, "%s\n", vff::describeJsonProblem(*p, "library.json").c_str());
//     return 3;  // invalid input file
//   }
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "vff/export.h"

namespace vff {

// How deep objects and arrays may nest: the top-level value is depth 1.
inline constexpr int kStrictJsonMaxDepth = 64;

// Where and what: the first problem of a text, in text order.
struct JsonTextProblem {
  uint64_t byte = 0;    // 0-based offset of the byte where the problem was found
  uint32_t line = 1;    // 1-based line of that byte (lines end at LF)
  uint32_t column = 1;  // 1-based column of that byte, counted in bytes
  std::string path;     // JSON path of the value being read ("instances[3].rotation"), "" at the top
  std::string message;  // what is wrong, without the place ("a repeated member name \"uri\"")
};

// Checks `text` by the rules above; nothing when it follows them all.
VFF_API std::optional<JsonTextProblem> checkStrictJson(std::string_view text);

// "FILE:LINE:COLUMN: PATH: MESSAGE" (PATH and its colon left out at the top level).
VFF_API std::string describeJsonProblem(const JsonTextProblem& problem, const std::string& fileName);

// A member name as a JSON path names it: ".name" for a name of letters, digits and underscores that
// does not start with a digit, else ["..."] (the name as a JSON string). `path` is appended to.
VFF_API void appendJsonPathKey(std::string& path, std::string_view key);

}  // namespace vff
