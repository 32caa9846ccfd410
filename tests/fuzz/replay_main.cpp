// Runs a fuzz target's entry point over files and folders given on the command line (the seeds
// and the regression inputs): what the ctest cases do in every build, fuzzer or not.
#include <cstdint>
#include <cstdio>
#include <vector>

#include "input_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  const auto files = vff::fuzz::inputFiles(argc, argv);
  for (const auto& p : files) {
    const std::vector<uint8_t> bytes = vff::fuzz::fileBytes(p);
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  }
  std::printf("replayed %zu inputs\n", files.size());
  return files.empty() ? 1 : 0;
}
