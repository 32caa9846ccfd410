// Fuzz target: the merge of partial results (vff-bake --merge; mergeParts in tools/bake-job,
// spec/partial.md). The input is up to four parts: a byte whose value mod 4 is the part count less
// one, the length of every part but the last as 4 bytes little-endian (cut to what is left), then
// the parts (seeds: make_merge_seeds.sh). They are written to a private temporary folder and merged
// into an output there. Whatever the parts:
//   * mergeParts returns (no exception: vff-bake would report it as an internal error);
//   * it returns 0, the output exists, the validator finds no error in it, it opens, and each of
//     its maps is, in both planes, the map of the one part whose range holds it; or it
//     returns a documented exit code (1..5), printed a message "vff-bake: error: ..." (never an
//     internal error), and left no file behind: no output, no temporary.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "bake_job.h"
#include "vff/vff.h"

namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "merge: %s\n%s\n", what, detail.c_str());
  std::abort();
}

// The private folder of this process, made once (removed when the process ends normally).
const fs::path& folder() {
  static const fs::path dir = [] {
    std::string t = (fs::temp_directory_path() / "vff-fuzz-merge-XXXXXX").string();
    if (!mkdtemp(t.data())) fail("cannot make a temporary folder", t);
    return fs::path(t);
  }();
  static const struct Cleanup {
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup;
  return dir;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs the merge with its messages (stderr) going to `log`; returns its exit code.
int mergeLogged(const vff::bake_tool::Options& o, const fs::path& log) {
  std::fflush(stderr);
  const int saved = dup(2);
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (saved < 0 || fd < 0) fail("cannot redirect stderr", log.string());
  dup2(fd, 2);
  close(fd);
  int rc = -1;
  std::string thrown;
  try {
    rc = vff::bake_tool::mergeParts(o);
  } catch (const std::exception& e) {
    thrown = e.what();
  } catch (...) {
    thrown = "(not a std::exception)";
  }
  std::fflush(stderr);
  dup2(saved, 2);
  close(saved);
  if (rc == -1) fail("mergeParts threw", thrown);
  return rc;
}

std::vector<uint8_t> readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool sameMap(const vff::File& a, const vff::File& b, vff::Plane p, uint32_t k) {
  auto x = a.mapData(p, k), y = b.mapData(p, k);
  return x && y && x->size() == y->size() && std::equal(x->begin(), x->end(), y->begin());
}

// Each map of the merged file is its part's map; every map lies in exactly one part's range.
void checkMaps(const std::vector<uint8_t>& merged, const std::vector<std::string>& parts, const std::string& messages) {
  vff::Result<vff::File> whole = vff::File::openMemory(merged);
  if (!whole) fail("the merged file does not open", whole.error().toString() + "\n" + messages);
  std::vector<uint32_t> cover(whole->field().mapCount, 0);
  for (const std::string& path : parts) {
    const std::vector<uint8_t> bytes = readBytes(path);
    vff::Result<vff::File> part = vff::File::openMemory(bytes);
    if (!part) fail("a part of a merge that succeeded does not open", part.error().toString());
    const nlohmann::json meta = nlohmann::json::parse(part->metadata(), nullptr, false);
    if (!meta.is_object() || !meta.contains("vff.partial")) fail("a part of a merge that succeeded is not partial", path);
    const uint64_t begin = meta["vff.partial"].value("mapBegin", uint64_t{0});
    const uint64_t end = meta["vff.partial"].value("mapEnd", uint64_t{0});
    if (part->field().mapCount != cover.size() || end > cover.size() || begin >= end)
      fail("a part's range does not fit the merged field", path);
    for (auto k = uint32_t(begin); k < end; ++k) {
      ++cover[k];
      for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal})
        if (whole->plane(p).present && !sameMap(*whole, *part, p, k))
          fail("a merged map differs from its part's", path + " map " + std::to_string(k));
    }
  }
  for (uint32_t c : cover)
    if (c != 1) fail("the parts' ranges do not cover the field once", messages);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const size_t n = 1 + data[0] % 4;
  if (size < 1 + 4 * (n - 1)) return 0;
  const fs::path& dir = folder();
  size_t pos = 1 + 4 * (n - 1);
  vff::bake_tool::Options o;
  std::set<fs::path> mine;
  for (size_t i = 0; i < n; ++i) {
    size_t len = size - pos;
    if (i + 1 < n) {
      const uint8_t* l = data + 1 + 4 * i;
      len = std::min<size_t>(len, size_t(l[0]) | size_t(l[1]) << 8 | size_t(l[2]) << 16 | size_t(l[3]) << 24);
    }
    const fs::path p = dir / ("part" + std::to_string(i) + ".vff");
    std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data + pos), std::streamsize(len));
    pos += len;
    o.merge.push_back(p.string());
    mine.insert(p);
  }
  const fs::path out = dir / "whole.vff", log = dir / "messages.txt";
  mine.insert(log);
  o.output = out.string();
  o.threads = 1;
  o.quiet = true;
  const int rc = mergeLogged(o, log);
  const std::string messages = readText(log);
  // (A message may quote a part, which may hold those words itself.)
  if (messages.find("internal error") != std::string::npos &&
      std::string_view(reinterpret_cast<const char*>(data), size).find("internal error") == std::string_view::npos)
    fail("an internal error", messages);
  if (rc == 0) {
    const std::vector<uint8_t> bytes = readBytes(out);
    if (bytes.empty()) fail("the merge succeeded without an output", messages);
    const vff::Report report = vff::validate(bytes);
    if (!report.valid()) fail("the merged file does not validate", messages);
    checkMaps(bytes, o.merge, messages);
    mine.insert(out);
  } else {
    if (rc < 1 || rc > 5) fail("an exit code that is not documented", std::to_string(rc) + "\n" + messages);
    if (messages.rfind("vff-bake: error: ", 0) != 0) fail("a refusal without its message", messages);
  }
  for (const auto& e : fs::directory_iterator(dir))
    if (!mine.count(e.path())) fail("a file left behind", e.path().string() + "\n" + messages);
  for (const fs::path& p : mine) std::remove(p.c_str());
  return 0;
}
