// param_name.h - a gtest case name from a string parameter (a file's path): every character that
// gtest does not allow in a name becomes '_'.
#pragma once

#include <gtest/gtest.h>

#include <cctype>
#include <string>

namespace vff::test {

inline std::string paramCaseName(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

}  // namespace vff::test
