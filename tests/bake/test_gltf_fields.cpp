// The glTF extension VFF_visibility_field read back (readGltfFields): each rule 14001-14011 on a
// file that breaks it, in the spec's order, the matches 14101-14104, and packGlbWithFields' layout.
// The files are made here: a box as a glTF (gltf_writer) and a small field baked from it in memory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "gltf_writer.h"
#include "vff/bake/baker.h"
#include "vff/bake/gltf_fields.h"
#include "vff/bake/procedural.h"
#include "vff/validate.h"
#include "vff/vff.h"

namespace vff::bake {
namespace {

namespace fs = std::filesystem;
using namespace gltftest;
using nlohmann::json;

std::string hex(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

class GltfFields : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_gltffields_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    box_ = makeShape("box");
    Mesh checked = box_;
    ASSERT_TRUE(checkMesh(&checked, "box").ok());
    hash_ = hex(geometryHash(checked));
    payload_ = bakePayload(json{{"vff.source", {{"geometryHash", hash_}}}});
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A small field of the box with `meta` as its META.
  std::vector<uint8_t> bakePayload(const json& meta) {
    BakeOptions bo;
    bo.positionParam = 2;
    bo.mapResolution = 8;
    bo.threads = 1;
    auto scene = Scene::create(box_, 1);
    EXPECT_TRUE(scene.ok());
    auto baked = bakeField(*scene, bo);
    EXPECT_TRUE(baked.ok());
    WriteOptions wo;
    wo.metadataJson = meta.dump();
    auto bytes = writeMemory(baked->field, baked->distance, {}, wo);
    EXPECT_TRUE(bytes.ok()) << bytes.error().message;
    return *bytes;
  }

  // The box's glTF with its field in a bufferView (the extension as `ext` gives it, "bufferView"
  // filled in when absent and `embed`); `edit` changes the document last.
  std::string file(const std::string& name, json ext, bool embed = true,
                   const std::function<void(json&)>& edit = {}) {
    GltfDoc doc = makeGltf(box_, {});
    if (embed && ext.is_object() && !ext.contains("bufferView") && !ext.contains("uri"))
      ext["bufferView"] = doc.addView(payload_.data(), payload_.size(), 0);
    doc.json["meshes"][0]["extensions"][kGltfFieldExtension] = ext;
    doc.use(kGltfFieldExtension, false);
    if (edit) edit(doc.json);
    const std::string path = (dir_ / name).string();
    EXPECT_TRUE(save(doc, path, name.size() > 4 && name.substr(name.size() - 4) == ".glb"));
    return path;
  }

  json ext() const {
    return {{"mimeType", kVffMediaType}, {"geometryHash", hash_}, {"min", {-1.0, -0.5, -0.25}}, {"max", {1.0, 0.5, 0.25}}};
  }

  // The one error of `path` (its rule), after checking there is exactly one.
  GltfFieldProblem onlyError(const std::string& path) {
    auto r = readGltfFields(path);
    EXPECT_TRUE(r.ok());
    std::vector<GltfFieldProblem> errors;
    for (const auto& p : r->problems)
      if (p.severity == GltfSeverity::kError) errors.push_back(p);
    EXPECT_EQ(errors.size(), 1u);
    return errors.empty() ? GltfFieldProblem{} : errors[0];
  }

  void write(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

  fs::path dir_;
  Mesh box_;
  std::string hash_;
  std::vector<uint8_t> payload_;
};

TEST_F(GltfFields, ExactFieldIsUsable) {
  const std::string path = file("a.glb", ext());
  auto r = readGltfFields(path);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->meshCount, 1);
  EXPECT_TRUE(r->problems.empty());
  ASSERT_EQ(r->fields.size(), 1u);
  const GltfField& f = r->fields[0];
  EXPECT_EQ(f.mesh, 0);
  EXPECT_EQ(f.path, "/meshes/0/extensions/VFF_visibility_field");
  EXPECT_TRUE(f.valid);
  EXPECT_EQ(f.match, GltfFieldMatch::kExact);
  EXPECT_TRUE(f.usable());
  EXPECT_EQ(f.meshGeometryHash, hash_);
  EXPECT_EQ(f.bytes, payload_);
  EXPECT_EQ(f.meshMin, (std::array<float, 3>{-1.0f, -0.5f, -0.25f}));
  EXPECT_EQ(f.meshMax, (std::array<float, 3>{1.0f, 0.5f, 0.25f}));
  auto file = File::openMemory(f.bytes);
  ASSERT_TRUE(file.ok());
  EXPECT_DOUBLE_EQ(f.tolerance, 2.0 * file->field().sphere.radius / 255.0);
  ASSERT_EQ(f.nodes.size(), 1u);
  EXPECT_TRUE(f.nodes[0].answered);
  auto g = gltfMeshGeometry(path, 0);
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->geometryHash, hash_);
  EXPECT_EQ(g->min, f.meshMin);
}

TEST_F(GltfFields, GltfTextWithDataUriPayloadIsRead) {
  json e = ext();
  e.erase("mimeType");  // optional with uri
  std::string b64;
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < payload_.size(); i += 3) {
    uint32_t v = uint32_t(payload_[i]) << 16;
    if (i + 1 < payload_.size()) v |= uint32_t(payload_[i + 1]) << 8;
    if (i + 2 < payload_.size()) v |= payload_[i + 2];
    b64 += k[(v >> 18) & 63];
    b64 += k[(v >> 12) & 63];
    b64 += i + 1 < payload_.size() ? k[(v >> 6) & 63] : '=';
    b64 += i + 2 < payload_.size() ? k[v & 63] : '=';
  }
  e["uri"] = "data:application/vnd.vff;base64," + b64;
  auto r = readGltfFields(file("a.gltf", e));
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->fields.size(), 1u);
  EXPECT_TRUE(r->problems.empty()) << r->problems[0].message;
  EXPECT_EQ(r->fields[0].bytes, payload_);
  EXPECT_EQ(r->fields[0].match, GltfFieldMatch::kExact);
}

TEST_F(GltfFields, RelativeUriPayloadIsRead) {
  std::ofstream(dir_ / "my field.vff", std::ios::binary)
      .write(reinterpret_cast<const char*>(payload_.data()), std::streamsize(payload_.size()));
  json e = ext();
  e["uri"] = "my%20field.vff";
  auto r = readGltfFields(file("a.glb", e));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->problems.empty());
  EXPECT_TRUE(r->fields[0].usable());
}

TEST_F(GltfFields, NotGltfIs14001) {
  static const char kShort[] = "glTF\x02\0\0\0\x40\0\0\0garbage";  // claims 64 bytes, has 19
  write((dir_ / "x.glb").string(), std::string(kShort, sizeof kShort - 1));
  auto p = onlyError((dir_ / "x.glb").string());
  EXPECT_EQ(p.rule, GltfFieldRule::kContainer);
  EXPECT_NE(p.message.find("length"), std::string::npos) << p.message;
  write((dir_ / "x.gltf").string(), "{ not json");
  EXPECT_EQ(onlyError((dir_ / "x.gltf").string()).rule, GltfFieldRule::kContainer);
  const std::string v1 = file("v1.gltf", ext(), true, [](json& d) { d["asset"]["version"] = "1.0"; });
  p = onlyError(v1);
  EXPECT_EQ(p.rule, GltfFieldRule::kContainer);
  EXPECT_EQ(p.path, "/asset/version");
  auto r = readGltfFields(v1);
  EXPECT_TRUE(r->fields.empty());  // the file ends there
  EXPECT_FALSE(readGltfFields((dir_ / "missing.glb").string()).ok());
}

TEST_F(GltfFields, RequiredIs14002AndNotUsedIs14003) {
  auto p = onlyError(file("r.glb", ext(), true, [](json& d) { d["extensionsRequired"] = {kGltfFieldExtension}; }));
  EXPECT_EQ(p.rule, GltfFieldRule::kRequired);
  EXPECT_EQ(p.format("r.glb"), "r.glb: /extensionsRequired: gltf-required (14002): " + p.message);
  p = onlyError(file("u.glb", ext(), true, [](json& d) { d.erase("extensionsUsed"); }));
  EXPECT_EQ(p.rule, GltfFieldRule::kUsed);
}

TEST_F(GltfFields, BadExtensionValuesAre14004) {
  const auto rule = [&](const std::string& name, const json& e) { return onlyError(file(name, e)); };
  EXPECT_EQ(rule("a.glb", json::array()).rule, GltfFieldRule::kExtensionValue);
  json e = ext();
  e["geometryHash"] = "ABCDEF0123456789";
  auto p = rule("b.glb", e);
  EXPECT_EQ(p.rule, GltfFieldRule::kExtensionValue);
  EXPECT_EQ(p.path, "/meshes/0/extensions/VFF_visibility_field/geometryHash");
  e = ext();
  e["min"] = {2, 0, 0};
  EXPECT_EQ(rule("c.glb", e).rule, GltfFieldRule::kExtensionValue);
  e = ext();
  e.erase("max");
  EXPECT_EQ(rule("d.glb", e).path, "/meshes/0/extensions/VFF_visibility_field/max");
  e = ext();
  e["bufferView"] = "0";
  EXPECT_EQ(rule("e.glb", e).rule, GltfFieldRule::kExtensionValue);
}

TEST_F(GltfFields, BothOrNeitherSourceIs14005) {
  json e = ext();
  e["uri"] = "f.vff";
  e["bufferView"] = 0;
  EXPECT_EQ(onlyError(file("a.glb", e)).rule, GltfFieldRule::kFieldSource);
  EXPECT_EQ(onlyError(file("b.glb", ext(), false)).rule, GltfFieldRule::kFieldSource);
}

TEST_F(GltfFields, BadBufferViewIs14006) {
  json e = ext();
  e["bufferView"] = 99;
  EXPECT_EQ(onlyError(file("a.glb", e)).rule, GltfFieldRule::kBufferView);
  auto stride = [](json& d) { d["bufferViews"].back()["byteStride"] = 4; };
  EXPECT_EQ(onlyError(file("b.glb", ext(), true, stride)).rule, GltfFieldRule::kBufferView);
  auto outside = [](json& d) { d["bufferViews"].back()["byteLength"] = 1 << 30; };
  auto p = onlyError(file("c.glb", ext(), true, outside));
  EXPECT_EQ(p.rule, GltfFieldRule::kBufferView);
  EXPECT_NE(p.message.find("outside"), std::string::npos) << p.message;
}

TEST_F(GltfFields, BadUrisAre14007) {
  for (const char* uri : {"/abs/f.vff", "http://x/f.vff", "//host/f.vff", "f.vff?q", "f.vff#a", "a\\f.vff", "f%zz.vff",
                          "f%00.vff", "data:application/vnd.vff,AAAA"}) {
    json e = ext();
    e["uri"] = uri;
    auto p = onlyError(file("a.glb", e, false));
    EXPECT_EQ(p.rule, GltfFieldRule::kUri) << uri;
    EXPECT_FALSE(p.ioError) << uri;
  }
  json e = ext();
  e["uri"] = "missing.vff";
  auto p = onlyError(file("b.glb", e, false));
  EXPECT_EQ(p.rule, GltfFieldRule::kUri);
  EXPECT_TRUE(p.ioError);
}

TEST_F(GltfFields, MimeTypeIs14008) {
  json e = ext();
  e.erase("mimeType");
  EXPECT_EQ(onlyError(file("a.glb", e)).rule, GltfFieldRule::kMimeType);
  e["mimeType"] = "application/octet-stream";
  EXPECT_EQ(onlyError(file("b.glb", e)).rule, GltfFieldRule::kMimeType);
}

TEST_F(GltfFields, InvalidOrPartialPayloadIs14009) {
  payload_[payload_.size() / 2] ^= 0x55;
  const Report broken = validate(payload_);
  ASSERT_FALSE(broken.valid());
  auto p = onlyError(file("a.glb", ext()));
  EXPECT_EQ(p.rule, GltfFieldRule::kPayload);
  // The message names the first error's vff rule: its name and code.
  const std::string named = std::string(codeName(broken.issues[0].code)) + " (" + std::to_string(int(broken.issues[0].code)) + ")";
  EXPECT_NE(p.message.find(named), std::string::npos) << p.message;
  payload_ = bakePayload(json{{"vff.partial", {{"version", 1}}}, {"vff.source", {{"geometryHash", hash_}}}});
  p = onlyError(file("b.glb", ext()));
  EXPECT_EQ(p.rule, GltfFieldRule::kPayload);
  EXPECT_NE(p.message.find("partial"), std::string::npos) << p.message;
}

TEST_F(GltfFields, HashConflictIs14010) {
  payload_ = bakePayload(json{{"vff.source", {{"geometryHash", "0123456789abcdef"}}}});
  EXPECT_EQ(onlyError(file("a.glb", ext())).rule, GltfFieldRule::kHashConflict);
  payload_ = bakePayload(json::object());  // no hash in META: nothing to conflict with
  auto r = readGltfFields(file("b.glb", ext()));
  EXPECT_TRUE(r->problems.empty());
}

TEST_F(GltfFields, MeshWithoutTrianglesIs14011) {
  auto points = [](json& d) { d["meshes"][0]["primitives"][0]["mode"] = 0; };
  auto p = onlyError(file("a.glb", ext(), true, points));
  EXPECT_EQ(p.rule, GltfFieldRule::kMeshGeometry);
  EXPECT_EQ(p.path, "/meshes/0");
  auto r = readGltfFields(file("b.glb", ext(), true, points), {.checkGeometry = false});
  EXPECT_TRUE(r->problems.empty());
  EXPECT_EQ(r->fields[0].match, GltfFieldMatch::kUnchecked);
}

// A points or lines primitive beside the triangles is not part of the match: the field is exact.
TEST_F(GltfFields, PointsBesideTrianglesAreNotMatched) {
  auto withPoints = [](json& d) {
    json points = d["meshes"][0]["primitives"][0];
    points["mode"] = 0;
    points.erase("indices");
    d["meshes"][0]["primitives"].push_back(points);
  };
  const std::string path = file("a.glb", ext(), true, withPoints);
  auto r = readGltfFields(path);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->problems.empty());
  ASSERT_EQ(r->fields.size(), 1u);
  EXPECT_EQ(r->fields[0].match, GltfFieldMatch::kExact);
  EXPECT_EQ(r->fields[0].meshGeometryHash, hash_);
}

TEST_F(GltfFields, LaterMeshesAreStillCheckedAndNodesNoted) {
  auto edit = [&](json& d) {
    json second = d["meshes"][0];
    second["extensions"][kGltfFieldExtension]["mimeType"] = "text/plain";
    d["meshes"].push_back(d["meshes"][0]);   // mesh 1: a good field again
    d["meshes"].insert(d["meshes"].begin(), second);  // mesh 0: 14008
    d["nodes"] = {{{"mesh", 1}}, {{"mesh", 2}, {"scale", {1, 2, 1}}}, {{"mesh", 2}, {"scale", {-1, 1, 1}}},
                  {{"mesh", 2}, {"skin", 0}}};
    d["scenes"] = {{{"nodes", {0, 1, 2, 3}}}};
  };
  auto r = readGltfFields(file("a.glb", ext(), true, edit));
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->fields.size(), 3u);
  EXPECT_FALSE(r->fields[0].valid);
  EXPECT_TRUE(r->fields[1].usable());
  EXPECT_TRUE(r->fields[2].usable());
  ASSERT_EQ(r->fields[2].nodes.size(), 3u);
  EXPECT_EQ(r->fields[2].nodes[0].reason, "non-uniform scale");
  EXPECT_EQ(r->fields[2].nodes[1].reason, "mirror");
  EXPECT_EQ(r->fields[2].nodes[2].reason, "skin");
  std::vector<int> rules;
  for (const auto& p : r->problems) rules.push_back(int(p.rule));
  EXPECT_EQ(rules, (std::vector<int>{14008, 14104, 14104, 14104}));
}

TEST_F(GltfFields, PackedGlbAlignsPayloadsAndReplacesAnEarlierField) {
  const std::string in = file("in.gltf", ext());  // a .gltf with its buffer in in.bin and a field
  std::vector<uint8_t> other = payload_;
  auto glb = packGlbWithFields(in, {{0, other, "", hash_, {-1, -0.5f, -0.25f}, {1, 0.5f, 0.25f}}});
  ASSERT_TRUE(glb.ok()) << glb.error().message;
  uint32_t jsonLength = 0;
  std::memcpy(&jsonLength, glb->data() + 12, 4);
  EXPECT_EQ((28 + jsonLength) % 64, 0u);
  const json doc = json::parse(glb->begin() + 20, glb->begin() + 20 + jsonLength);
  const json& e = doc["meshes"][0]["extensions"][kGltfFieldExtension];
  const int view = e["bufferView"];
  EXPECT_EQ(view, int(doc["bufferViews"].size()) - 1);  // the new one, after the old field's view
  EXPECT_EQ((28 + jsonLength + doc["bufferViews"][size_t(view)]["byteOffset"].get<uint64_t>()) % 64, 0u);
  EXPECT_EQ(doc["buffers"].size(), 1u);
  EXPECT_FALSE(doc["buffers"][0].contains("uri"));
  EXPECT_EQ(std::count(doc["extensionsUsed"].begin(), doc["extensionsUsed"].end(), kGltfFieldExtension), 1);
  const std::string out = (dir_ / "sub").string();
  fs::create_directories(out);
  std::ofstream(out + "/o.glb", std::ios::binary).write(reinterpret_cast<const char*>(glb->data()), std::streamsize(glb->size()));
  auto r = readGltfFields(out + "/o.glb");
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->problems.empty());
  EXPECT_TRUE(r->fields[0].usable());
  auto again = packGlbWithFields(in, {{0, other, "", hash_, {-1, -0.5f, -0.25f}, {1, 0.5f, 0.25f}}});
  EXPECT_EQ(*again, *glb);  // deterministic
  EXPECT_FALSE(packGlbWithFields(in, {{3, other, "", hash_, {}, {}}}).ok());  // no mesh 3
}

}  // namespace
}  // namespace vff::bake
