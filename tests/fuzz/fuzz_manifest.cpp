// Fuzz target: vff-library's manifest reader (spec/library.md; parseManifest in tools/vff-library,
// library vff_library_manifest) on arbitrary text. Whatever the text:
//   * parseManifest returns (it promises never to throw);
//   * *rc is 0 exactly when there is no message, and then a documented exit code (1..5);
//   * a message is never an internal error;
//   * the entries of a manifest it accepts each have an absolute mesh path, an output under the
//     output folder (no ".." there), a split of "", "mesh" or "node", and no two the same output.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "library.h"

namespace {

// Names only: parseManifest reads no file (the manifest is given as text, meshes are not opened).
constexpr const char* kPath = "/vff-fuzz/library/manifest.json";
constexpr const char* kOut = "/vff-fuzz/out";

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "manifest: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void checkEntries(const std::vector<vff::library::Entry>& entries) {
  std::set<std::string> outputs;
  const std::string under = std::string(kOut) + "/";
  for (const vff::library::Entry& e : entries) {
    if (e.mesh.empty() || e.mesh[0] != '/') fail("a mesh path that is not absolute", e.mesh);
    if (e.output.rfind(under, 0) != 0) fail("an output outside the output folder", e.output);
    for (const auto& part : std::filesystem::path(e.output.substr(under.size())))
      if (part == "..") fail("an output with a '..' component", e.output);
    if (!e.split.empty() && e.split != "mesh" && e.split != "node") fail("an unknown split", e.split);
    if (!outputs.insert(e.output).second) fail("two entries with one output", e.output);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<vff::library::Entry> entries;
  int rc = -1;
  std::optional<std::string> message;
  try {
    message = vff::library::parseManifest(text, kPath, kOut, &entries, &rc);
  } catch (const std::exception& e) {
    fail("parseManifest threw", e.what());
  } catch (...) {
    fail("parseManifest threw", "(not a std::exception)");
  }
  if (message) {
    if (rc < 1 || rc > 5) fail("a refusal with an exit code that is not documented", std::to_string(rc) + ": " + *message);
    if (message->empty()) fail("an empty message", "");
    // (A message may quote the input, which may hold those words itself.)
    if (message->find("internal error") != std::string::npos && text.find("internal error") == std::string_view::npos)
      fail("an internal error", *message);
    return 0;
  }
  if (rc != 0) fail("no message but a non-zero exit code", std::to_string(rc));
  checkEntries(entries);
  return 0;
}
