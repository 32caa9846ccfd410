// The glTF extension's sample assets (spec/conformance/gltf/, spec/gltf/VFF_visibility_field):
// every .glb and .gltf under valid/ and invalid/ is its own test case, found by listing the folders
// when the test program starts, so an asset added without rebuilding still runs. readGltfFields
// must report each asset's problems as manifest.json lists them (rule, name, severity, JSON pointer,
// in that order, one formatted line each) and its fields (match, usability, hashes, the payload's
// size and XXH3-64, the nodes that can be answered). The generator's fresh output equals the
// committed bytes.
#include <gtest/gtest.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "common/param_name.h"
#include "vff/bake/gltf_fields.h"
#include "vff/reader.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff::bake {
namespace {

const fs::path kDir = fs::path(VFF_CONFORMANCE_DIR) / "gltf";

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

json manifest() {
  return json::parse(readText(kDir / "manifest.json"), nullptr, false);
}

std::string hex64(const void* data, size_t size) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(XXH3_64bits(data, size)));
  return s;
}

bool isAsset(const fs::path& p) {
  return p.extension() == ".glb" || p.extension() == ".gltf";
}

// "valid/NAME.glb", "invalid/ID-NAME.gltf", ... for each asset, sorted.
std::vector<std::string> listAssets() {
  std::vector<std::string> out;
  for (const char* kind : {"valid", "invalid"}) {
    std::error_code ec;
    for (fs::directory_iterator it(kDir / kind, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file() && isAsset(it->path())) out.push_back(std::string(kind) + "/" + it->path().filename().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A scratch folder of this process, removed with it.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("vff-gltf-vectors-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(dir); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

class GltfAsset : public ::testing::TestWithParam<std::string> {};

TEST_P(GltfAsset, ReadsAsTheManifestSays) {
  const std::string name = GetParam();
  const json m = manifest();
  ASSERT_TRUE(m.is_object()) << "manifest.json does not parse";
  ASSERT_TRUE(m["assets"].contains(name)) << name << " is not in manifest.json: regenerate the assets";
  const json& want = m["assets"][name];
  const std::string path = (kDir / name).string();

  auto r = readGltfFields(path);
  ASSERT_TRUE(r) << r.error().toString();

  // The problems, in check order, each with its rule, name, severity and place.
  const json& problems = want["problems"];
  std::string got;
  for (const GltfFieldProblem& p : r->problems) got += p.format(path) + "\n";
  ASSERT_EQ(r->problems.size(), problems.size()) << got;
  for (size_t i = 0; i < problems.size(); ++i) {
    const GltfFieldProblem& p = r->problems[i];
    const json& w = problems[i];
    const int id = w["rule"].get<int>();
    EXPECT_EQ(int(p.rule), id) << got;
    EXPECT_STREQ(gltfFieldRuleName(p.rule), w["name"].get<std::string>().c_str());
    EXPECT_STREQ(gltfSeverityName(p.severity), w["severity"].get<std::string>().c_str()) << got;
    EXPECT_EQ(p.path, w["path"].get<std::string>()) << got;
    EXPECT_EQ(p.ioError, w.value("ioError", false)) << got;
    EXPECT_FALSE(p.message.empty());
    // "FILE: PATH: NAME (ID): message", the path left out when empty.
    const std::string head = path + ": " + (p.path.empty() ? "" : p.path + ": ") + w["name"].get<std::string>() + " (" +
                             std::to_string(id) + "): ";
    EXPECT_EQ(p.format(path).rfind(head, 0), 0u) << p.format(path);
    // A payload libvff refuses: the message names one of the validator's codes, "NAME (CODE)".
    if (w.contains("vffCodes")) {
      bool named = false;
      for (const auto& c : w["vffCodes"])
        named = named || p.message.find(" (" + std::to_string(c.get<int>()) + ")") != std::string::npos;
      EXPECT_TRUE(named) << p.message << " names none of " << w["vffCodes"].dump();
    }
  }
  EXPECT_EQ(r->hasError(), want["hasError"].get<bool>());
  if (want.contains("meshes")) {
    EXPECT_EQ(r->meshCount, want["meshes"].get<int>());
  }

  // The fields, one per mesh carrying the extension.
  const json& fields = want["fields"];
  ASSERT_EQ(r->fields.size(), fields.size());
  for (size_t i = 0; i < fields.size(); ++i) {
    const GltfField& f = r->fields[i];
    const json& w = fields[i];
    SCOPED_TRACE("field of mesh " + std::to_string(f.mesh));
    EXPECT_EQ(f.mesh, w["mesh"].get<int>());
    EXPECT_EQ(f.path, "/meshes/" + std::to_string(f.mesh) + "/extensions/VFF_visibility_field");
    EXPECT_EQ(f.valid, w["valid"].get<bool>());
    EXPECT_EQ(f.usable(), w["usable"].get<bool>());
    EXPECT_STREQ(gltfFieldMatchName(f.match), w["match"].get<std::string>().c_str());
    if (!w["valid"].get<bool>()) {
      EXPECT_TRUE(f.bytes.empty()) << "a field with an error keeps no bytes";
      continue;
    }
    EXPECT_EQ(f.meshName, w["name"].get<std::string>());
    EXPECT_EQ(f.geometryHash, w["geometryHash"].get<std::string>());
    EXPECT_EQ(f.meshGeometryHash, w["meshGeometryHash"].get<std::string>());
    EXPECT_EQ(f.bytes.size(), w["bytes"].get<size_t>());
    EXPECT_EQ(hex64(f.bytes.data(), f.bytes.size()), w["xxh3"].get<std::string>());
    if (w["source"] == "bufferView") {
      EXPECT_GE(f.bufferView, 0);
      EXPECT_TRUE(f.uri.empty());
    } else {
      EXPECT_EQ(f.bufferView, -1);
      EXPECT_FALSE(f.uri.empty());
    }
    if (w.contains("tolerance")) {
      EXPECT_NEAR(f.tolerance, w["tolerance"].get<double>(), 1e-15);
      EXPECT_NEAR(f.boundsDifference, w["boundsDifference"].get<double>(), 1e-15);
    }
    ASSERT_EQ(f.nodes.size(), w["nodes"].size());
    for (size_t k = 0; k < f.nodes.size(); ++k) {
      EXPECT_EQ(f.nodes[k].node, w["nodes"][k]["node"].get<int>());
      EXPECT_EQ(f.nodes[k].answered, w["nodes"][k]["answered"].get<bool>());
      EXPECT_EQ(f.nodes[k].reason.empty(), f.nodes[k].answered) << "node " << f.nodes[k].node;
    }
    // A usable field's bytes are a .vff file libvff opens.
    if (f.usable()) {
      auto file = File::openMemory(f.bytes);
      EXPECT_TRUE(file) << file.error().toString();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(GltfVectors, GltfAsset, ::testing::ValuesIn(listAssets()), vff::test::paramCaseName);

// Every asset of the manifest is on disk and the other way round; the invalid assets cover every
// error rule, each named by the rule it raises first; the valid ones have no error and cover the
// notes and the warning.
TEST(GltfVectors, ManifestMatchesFilesAndCoversEveryRule) {
  const json m = manifest();
  ASSERT_TRUE(m.is_object());
  const std::vector<std::string> assets = listAssets();
  EXPECT_EQ(assets.size(), m["assets"].size());
  std::set<int> errors, others;
  int valid = 0;
  for (const auto& [name, a] : m["assets"].items()) {
    EXPECT_TRUE(std::count(assets.begin(), assets.end(), name)) << name << " is not on disk";
    EXPECT_TRUE(m["files"].contains(name)) << name;
    if (name.rfind("valid/", 0) == 0) {
      ++valid;
      EXPECT_FALSE(a["hasError"].get<bool>()) << name;
      for (const auto& p : a["problems"]) others.insert(p["rule"].get<int>());
      continue;
    }
    ASSERT_FALSE(a["problems"].empty()) << name;
    const int id = a["problems"][0]["rule"].get<int>();
    errors.insert(id);
    EXPECT_EQ(name.substr(0, 8 + 6), "invalid/" + std::to_string(id) + "-") << "named by its first rule";
  }
  EXPECT_GE(valid, 8);
  for (int id = 14001; id <= 14011; ++id) EXPECT_TRUE(errors.count(id)) << "no invalid asset raises " << id;
  for (int id : {14102, 14103, 14104}) EXPECT_TRUE(others.count(id)) << "no valid asset reports " << id;
  // Every file the manifest lists (assets and the .vff files beside them) is there, with its bytes.
  for (const auto& [name, entry] : m["files"].items()) {
    const std::string bytes = readText(kDir / name);
    EXPECT_EQ(bytes.size(), entry["bytes"].get<size_t>()) << name;
    EXPECT_EQ(hex64(bytes.data(), bytes.size()), entry["xxh3"].get<std::string>()) << name;
  }
}

// The committed assets are what the generator makes now. Its partial result has zstd blocks: with
// another libzstd, that asset is not compared (a note says so).
TEST(GltfVectors, RegeneratedBytesMatch) {
  Scratch scratch;
  const std::string cmd = std::string("\"") + VFF_GLTF_GEN + "\" \"" + scratch.dir.string() + "\" >\"" +
                          (scratch.dir / "log").string() + "\" 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << readText(scratch.dir / "log");
  const json committed = manifest(), fresh = json::parse(readText(scratch.dir / "manifest.json"), nullptr, false);
  ASSERT_TRUE(committed.is_object() && fresh.is_object());
  EXPECT_EQ(committed["assets"], fresh["assets"]);
  const bool sameZstd = committed["zstdVersion"] == fresh["zstdVersion"];
  if (!sameZstd) std::printf("note: the assets were made with another zstd: zstd files are not compared\n");
  int compared = 0;
  for (const auto& [name, entry] : fresh["files"].items()) {
    ASSERT_TRUE(committed["files"].contains(name)) << name << " is new: regenerate the assets";
    if (!sameZstd && entry["zstd"].get<bool>()) continue;
    ++compared;
    EXPECT_EQ(committed["files"][name], entry) << name;
    EXPECT_TRUE(readText(kDir / name) == readText(scratch.dir / name)) << name << " differs from the generator's";
  }
  EXPECT_EQ(committed["files"].size(), fresh["files"].size());
  EXPECT_GT(compared, 50);
}

}  // namespace
}  // namespace vff::bake
