// input_files.h - the inputs a replay-style driver is given: each file argument, and every file
// under each folder argument (recursively), in sorted order, so that every run reads the same
// inputs in the same order. Shared by replay_main.cpp and first_error.cpp.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace vff::fuzz {

// The files named by argv[1..argc), folders walked. A path that is neither is put in *missing
// (when given) and skipped.
inline std::vector<std::filesystem::path> inputFiles(int argc, char** argv, std::string* missing = nullptr) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (int a = 1; a < argc; ++a) {
    const fs::path p = argv[a];
    if (fs::is_directory(p)) {
      for (const auto& e : fs::recursive_directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (fs::is_regular_file(p)) {
      files.push_back(p);
    } else if (missing && missing->empty()) {
      *missing = p.string();
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

inline std::vector<uint8_t> fileBytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace vff::fuzz
