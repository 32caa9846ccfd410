// gen_invalid.h - the invalid conformance vectors: mutations of the valid ones, each with one fault
// that raises its validation ID (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "gen_bytes.h"
#include "gen_valid.h"

namespace vff::gen {

struct InvalidCase {
  uint32_t id = 0;
  std::string name;
  std::string base;
  std::string mutation;
  Bytes bytes;
  bool zstd = false;
};

// Every invalid vector, made from the valid vectors `valid` (by name), in the order they are written.
std::vector<InvalidCase> invalidCases(const std::map<std::string, BuiltValid>& valid);

}  // namespace vff::gen
