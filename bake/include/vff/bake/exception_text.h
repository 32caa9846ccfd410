// vff/bake/exception_text.h - an exception's text, made fit for an error message. Header-only and
// free of dependencies: the baker's OpenVDB input (levelset.cpp) and vff-convert's OpenVDB export and
// import, which does not link the baker, both include it.
#pragma once

#include <exception>
#include <string>

namespace vff::bake {

// An OpenVDB exception's text for a message: on a damaged file it can hold bytes read from the
// file (an unterminated name, say), so keep printable ASCII, collapse blanks, and cut it short.
inline std::string exceptionText(const std::exception& e) {
  std::string out;
  for (const char* c = e.what(); *c && out.size() < 200; ++c) {
    const unsigned char u = static_cast<unsigned char>(*c);
    const char ch = u >= 0x20 && u < 0x7f ? *c : ' ';
    if (ch == ' ' && (out.empty() || out.back() == ' ')) continue;
    out += ch;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

}  // namespace vff::bake
