// The partial-result vectors (spec/conformance/partial/, spec/partial.md section 4): every merge
// set under merge/ is its own test case, found by listing the folders when the test program starts,
// so a set added without rebuilding still runs. vff-bake --merge of a valid set writes the bytes of
// its expected.vff (XXH3-64 and size as manifest.json records them); of an invalid set, it exits
// with the rule's code, prints "PART: NAME (ID)" of the one rule the folder's name starts with, and
// writes nothing. vff-inspect reports every valid partial with its range (schema-checked).
#include <gtest/gtest.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const fs::path kDir = fs::path(VFF_CONFORMANCE_DIR) / "partial";

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

json manifest() {
  return json::parse(readText(kDir / "manifest.json"), nullptr, false);
}

std::string hex64(const std::string& b) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(XXH3_64bits(b.data(), b.size())));
  return s;
}

// The folders under merge/, sorted.
std::vector<std::string> listSets() {
  std::vector<std::string> out;
  std::error_code ec;
  for (fs::directory_iterator it(kDir / "merge", ec), end; !ec && it != end; it.increment(ec))
    if (it->is_directory()) out.push_back(it->path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// A scratch folder of this process, removed with it.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("vff-partial-vectors-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(dir); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

// Runs `command` with stdout and stderr to `log`; returns its exit status.
int run(const std::string& command, const fs::path& log) {
  const int st = std::system((command + " >\"" + log.string() + "\" 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

class MergeSet : public ::testing::TestWithParam<std::string> {};

TEST_P(MergeSet, MergesOrRefusesWithItsId) {
  const std::string name = GetParam();
  const json m = manifest();
  ASSERT_TRUE(m.is_object()) << "manifest.json does not parse";
  ASSERT_TRUE(m["sets"].contains(name)) << name << " is not in manifest.json: regenerate the vectors";
  const json& set = m["sets"][name];
  const fs::path dir = kDir / "merge" / name;
  // Every file of the folder is a part or the expected output: none goes unused.
  std::set<std::string> listed;
  for (const auto& p : set["parts"]) listed.insert(p.get<std::string>());
  if (set.contains("expected")) listed.insert(set["expected"].get<std::string>());
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_TRUE(listed.count(e.path().filename().string())) << e.path() << " is no part of the set";

  Scratch scratch;
  const fs::path out = scratch.dir / "merged.vff", log = scratch.dir / "log";
  std::string cmd = std::string("\"") + VFF_BAKE + "\" --merge";
  for (const auto& p : set["parts"]) cmd += " \"" + (dir / p.get<std::string>()).string() + "\"";
  cmd += " -o \"" + out.string() + "\" -q";
  const int rc = run(cmd, log);
  const std::string err = readText(log);
  ASSERT_EQ(rc, set["exit"].get<int>()) << cmd << "\n" << err;
  if (rc == 0) {
    const json& expected = m["files"]["merge/" + name + "/" + set["expected"].get<std::string>()];
    const std::string bytes = readText(out);
    EXPECT_EQ(bytes.size(), expected["bytes"].get<size_t>());
    EXPECT_EQ(hex64(bytes), expected["xxh3"].get<std::string>());
    EXPECT_TRUE(bytes == readText(dir / set["expected"].get<std::string>())) << "merged bytes differ from expected.vff";
    return;
  }
  // The folder's name starts with the ID the manifest gives, and the tool names exactly that rule.
  const std::string id = std::to_string(set["id"].get<int>());
  EXPECT_EQ(name.substr(0, id.size() + 1), id + "-");
  const std::string tag =
      (dir / set["refused"].get<std::string>()).string() + ": " + set["name"].get<std::string>() + " (" + id + "): ";
  EXPECT_NE(err.find(tag), std::string::npos) << "expected \"" << tag << "\" in:\n" << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one refusal, one line:\n" << err;
  EXPECT_FALSE(fs::exists(out)) << "a refused merge wrote its output";
}

INSTANTIATE_TEST_SUITE_P(PartialVectors, MergeSet, ::testing::ValuesIn(listSets()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string n = i.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

// Every set of the manifest has its folder, and the sets cover every rule a file can break.
TEST(PartialVectors, ManifestMatchesFoldersAndCoversEveryFileRule) {
  const json m = manifest();
  ASSERT_TRUE(m.is_object());
  const std::vector<std::string> folders = listSets();
  std::set<int> ids;
  int valid = 0;
  for (const auto& [name, set] : m["sets"].items()) {
    EXPECT_TRUE(std::count(folders.begin(), folders.end(), name)) << name << " has no folder";
    if (set["exit"] == 0)
      ++valid;
    else
      ids.insert(set["id"].get<int>());
  }
  EXPECT_EQ(folders.size(), m["sets"].size());
  EXPECT_GE(valid, 3);
  for (int id = 12002; id <= 12019; ++id) EXPECT_TRUE(ids.count(id)) << "no invalid set raises " << id;
}

// vff-inspect's JSON report of every valid partial gives its range, counts only the range's maps and
// conforms to spec/inspect-schema.json; the merged whole fields report "partial": null.
TEST(PartialVectors, InspectReportsEveryValidPartial) {
  const json m = manifest();
  ASSERT_TRUE(m.is_object());
  Scratch scratch;
  const fs::path report = scratch.dir / "report.json", log = scratch.dir / "log";
  auto inspect = [&](const fs::path& file) {
    const int rc = run(std::string("\"") + VFF_INSPECT + "\" --format json \"" + file.string() + "\" >\"" +
                           report.string() + "\" 2>\"" + log.string() + "\" && \"" + VFF_SCHEMA_CHECK + "\" \"" +
                           VFF_INSPECT_SCHEMA + "\" \"" + report.string() + "\"",
                       scratch.dir / "schema-log");
    EXPECT_EQ(rc, 0) << file << ": " << readText(log) << readText(scratch.dir / "schema-log");
    return json::parse(readText(report), nullptr, false);
  };
  ASSERT_GE(m["partials"].size(), 6u);
  for (const auto& [name, r] : m["partials"].items()) {
    const json doc = inspect(kDir / name);
    ASSERT_TRUE(doc.is_object()) << name;
    const uint64_t maps = r["mapEnd"].get<uint64_t>() - r["mapBegin"].get<uint64_t>();
    EXPECT_EQ(doc["partial"],
              (json{{"mapBegin", r["mapBegin"]}, {"mapEnd", r["mapEnd"]}, {"mapCount", r["mapCount"]}, {"maps", maps}}))
        << name;
    const uint64_t m2 = doc["field"]["mapResolution"].get<uint64_t>() * doc["field"]["mapResolution"].get<uint64_t>();
    EXPECT_EQ(doc["statistics"]["texels"].get<uint64_t>(), maps * m2) << name;
  }
  for (const auto& [name, set] : m["sets"].items()) {
    if (set["exit"] != 0) continue;
    EXPECT_TRUE(inspect(kDir / "merge" / name / "expected.vff")["partial"].is_null()) << name;
  }
}

// The committed vectors are what the generator makes now. A different libzstd may compress
// differently: then the files with zstd blocks are not compared (a note says so).
TEST(PartialVectors, RegeneratedBytesMatch) {
  Scratch scratch;
  ASSERT_EQ(run(std::string("\"") + VFF_PARTIAL_GEN + "\" \"" + scratch.dir.string() + "\"", scratch.dir / "log"), 0)
      << readText(scratch.dir / "log");
  const json committed = manifest(), fresh = json::parse(readText(scratch.dir / "manifest.json"), nullptr, false);
  ASSERT_TRUE(committed.is_object() && fresh.is_object());
  const bool sameZstd = committed["zstdVersion"] == fresh["zstdVersion"];
  if (!sameZstd) std::printf("note: the vectors were made with another zstd: zstd files are not compared\n");
  EXPECT_EQ(committed["sets"], fresh["sets"]);
  EXPECT_EQ(committed["partials"], fresh["partials"]);
  int compared = 0;
  for (const auto& [name, entry] : fresh["files"].items()) {
    ASSERT_TRUE(committed["files"].contains(name)) << name << " is new: regenerate the vectors";
    if (!sameZstd && entry["zstd"].get<bool>()) continue;
    ++compared;
    EXPECT_EQ(committed["files"][name], entry) << name;
    EXPECT_TRUE(readText(kDir / name) == readText(scratch.dir / name)) << name << " differs from the generator's";
  }
  EXPECT_EQ(committed["files"].size(), fresh["files"].size());
  EXPECT_GT(compared, 0);
}

}  // namespace
