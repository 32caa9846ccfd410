// The scene-description vectors (spec/conformance/scene/, spec/scene.md section 5): every vector is
// its own test case, found by listing the folders when the test program starts, so a vector added
// without rebuilding still runs. An invalid vector must raise the ID of its folder (the first error
// in the order of the rules table) with the file named in the message; a valid one must read as its
// expected.json says (binary32 values bit for bit, world spheres within binary32 rounding).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "common/param_name.h"
#include "vff/reader.h"
#include "vff/scene_description.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff {
namespace {

const fs::path kDir = fs::path(VFF_CONFORMANCE_DIR) / "scene";

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// "valid/NAME" or "invalid/ID/NAME" for each vector (without .json), sorted.
std::vector<std::string> listVectors(const std::string& kind) {
  std::vector<std::string> out;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(kDir / kind, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!it->is_regular_file() || it->path().extension() != ".json" || name.find(".expected.") != std::string::npos)
      continue;
    out.push_back(fs::relative(it->path(), kDir).replace_extension().generic_string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

class InvalidSceneVector : public ::testing::TestWithParam<std::string> {};

TEST_P(InvalidSceneVector, RaisesItsFoldersId) {
  const fs::path path = kDir / (GetParam() + ".json");
  const int id = std::stoi(path.parent_path().filename().string());
  auto s = readSceneDescription(path.string());
  ASSERT_FALSE(s) << path << " was accepted";
  EXPECT_EQ(int(s.error().code), id) << s.error().toString();
  EXPECT_EQ(s.error().message.rfind(path.string() + ":", 0), 0u) << "the message names the file first: " << s.error().message;
  if (id == int(Code::kSceneJson) && s.error().message.find("not an object") == std::string::npos) {
    // "FILE:LINE:COLUMN: ...": the place of a syntax error.
    const std::string rest = s.error().message.substr(path.string().size());
    int line = 0, column = 0;
    EXPECT_EQ(std::sscanf(rest.c_str(), ":%d:%d:", &line, &column), 2) << s.error().message;
    EXPECT_GE(line, 1);
    EXPECT_GE(column, 1);
  }
}

INSTANTIATE_TEST_SUITE_P(SceneVectors, InvalidSceneVector, ::testing::ValuesIn(listVectors("invalid")), vff::test::paramCaseName);

// A binary32 the reader produced equals the expected number (a binary32 written as a binary64).
void expectFloat(float got, const json& want, const std::string& where) {
  ASSERT_TRUE(want.is_number()) << where;
  const float w = float(want.get<double>());
  EXPECT_EQ(std::memcmp(&got, &w, sizeof got), 0) << where << ": got " << got << ", expected " << w;
}

void expectNear(double got, const json& want, const std::string& where) {
  const double w = want.get<double>();
  EXPECT_NEAR(got, w, 1e-5 * (1 + std::fabs(w))) << where;
}

class ValidSceneVector : public ::testing::TestWithParam<std::string> {};

TEST_P(ValidSceneVector, ReadsAsExpected) {
  const fs::path path = kDir / (GetParam() + ".json");
  const json want = json::parse(readText(kDir / (GetParam() + ".expected.json")), nullptr, false);
  ASSERT_TRUE(want.is_object());
  auto s = readSceneDescription(path.string());
  ASSERT_TRUE(s) << s.error().toString();
  EXPECT_EQ(s->generator, want["generator"].get<std::string>());
  ASSERT_EQ(s->fields.size(), want["fields"].size());
  bool allExist = true;
  std::vector<Sphere> spheres(s->fields.size());
  for (size_t i = 0; i < s->fields.size(); ++i) {
    const json& f = want["fields"][i];
    EXPECT_EQ(s->fields[i].uri, f["uri"].get<std::string>());
    EXPECT_EQ(s->fields[i].name, f["name"].get<std::string>());
    const std::string resolved = resolveSceneUri(path.string(), s->fields[i].uri);
    EXPECT_EQ(resolved, (path.parent_path() / f["path"].get<std::string>()).string());
    EXPECT_EQ(fs::exists(resolved), f["exists"].get<bool>()) << resolved;
    allExist = allExist && f["exists"].get<bool>();
    if (f["exists"].get<bool>()) {
      auto file = File::open(resolved);
      ASSERT_TRUE(file) << file.error().toString();
      spheres[i] = file->field().sphere;
    }
  }
  ASSERT_EQ(s->instances.size(), want["instances"].size());
  for (size_t i = 0; i < s->instances.size(); ++i) {
    const SceneInstance& got = s->instances[i];
    const json& w = want["instances"][i];
    const std::string at = "instances[" + std::to_string(i) + "]";
    EXPECT_EQ(got.field, w["field"].get<uint32_t>()) << at;
    EXPECT_EQ(got.name, w["name"].get<std::string>()) << at;
    expectFloat(got.translation.x, w["translation"][0], at + ".translation[0]");
    expectFloat(got.translation.y, w["translation"][1], at + ".translation[1]");
    expectFloat(got.translation.z, w["translation"][2], at + ".translation[2]");
    for (size_t k = 0; k < 4; ++k) expectFloat(got.rotation[k], w["rotation"][k], at + ".rotation[" + std::to_string(k) + "]");
    expectFloat(got.scale, w["scale"], at + ".scale");
    EXPECT_EQ(w.contains("worldSphere"), want["fields"][got.field]["exists"].get<bool>()) << at;
    if (!w.contains("worldSphere")) continue;
    const Sphere& o = spheres[got.field];
    const Vec3 c = got.rigidTransform().toWorldPoint({o.center[0], o.center[1], o.center[2]});
    expectNear(c.x, w["worldSphere"]["center"][0], at + " sphere x");
    expectNear(c.y, w["worldSphere"]["center"][1], at + " sphere y");
    expectNear(c.z, w["worldSphere"]["center"][2], at + " sphere z");
    expectNear(double(got.scale) * o.radius, w["worldSphere"]["radius"], at + " sphere radius");
  }
  if (allExist) {
    auto loaded = loadScene(path.string());
    ASSERT_TRUE(loaded) << loaded.error().toString();
    EXPECT_EQ(loaded->get()->files.size(), s->fields.size());
  }
}

INSTANTIATE_TEST_SUITE_P(SceneVectors, ValidSceneVector, ::testing::ValuesIn(listVectors("valid")), vff::test::paramCaseName);

// Enough vectors, and every rule of spec/scene.md section 5 pinned by one at least.
TEST(SceneVectors, EveryRuleHasVectors) {
  const auto invalid = listVectors("invalid"), valid = listVectors("valid");
  EXPECT_GE(invalid.size(), 30u);
  EXPECT_GE(valid.size(), 8u);
  std::set<std::string> ids;
  for (const std::string& v : invalid) ids.insert(v.substr(8, 5));
  EXPECT_EQ(ids, (std::set<std::string>{"11001", "11002", "11003", "11004", "11005"}));
}

}  // namespace
}  // namespace vff
