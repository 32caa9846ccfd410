// Scene descriptions (spec/scene.md): the reader's rules, the writer's text, the transforms.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <utility>

#include "vff/scene_description.h"
#include "vff/strict_json.h"

namespace vff {
namespace {

const char* kExample = R"({
  "asset": {"format": "vff-scene", "version": 1, "generator": "test"},
  "fields": [{"uri": "a.vff", "name": "bunny", "source": {"file": "x.glb", "mesh": 0}}, {"uri": "sub/b.vff"}],
  "instances": [
    {"field": 0, "name": "left", "translation": [-2, 0, 0.5]},
    {"field": 1, "rotation": [0, 0.70710678, 0, 0.70710678], "scale": 0.5, "extras": {"k": [1, 2]}}
  ],
  "unknownMember": true
})";

TEST(SceneDescription, ParsesTheSpecExampleShape) {
  auto s = parseSceneDescription(kExample, "ex.json");
  ASSERT_TRUE(s) << s.error().toString();
  EXPECT_EQ(s->generator, "test");
  ASSERT_EQ(s->fields.size(), 2u);
  EXPECT_EQ(s->fields[0].uri, "a.vff");
  EXPECT_EQ(s->fields[0].name, "bunny");
  EXPECT_EQ(s->fields[0].sourceJson, R"({"file":"x.glb","mesh":0})");
  ASSERT_EQ(s->instances.size(), 2u);
  EXPECT_EQ(s->instances[0].translation.z, 0.5f);
  EXPECT_EQ(s->instances[0].scale, 1.0f);
  EXPECT_EQ(s->instances[0].rotation[3], 1.0f);
  EXPECT_EQ(s->instances[1].field, 1u);
  EXPECT_EQ(s->instances[1].extrasJson, R"({"k":[1,2]})");
}

// world(p) = translation + rotate(rotation, scale * p), the quaternion as glTF defines it.
TEST(SceneDescription, TransformIsTranslationRotationScale) {
  SceneInstance i;
  i.translation = {1, 2, 3};
  i.rotation = {0, float(std::sqrt(0.5)), 0, float(std::sqrt(0.5))};  // +90 degrees about y
  i.scale = 2;
  const RigidTransform t = i.rigidTransform();
  const Vec3 w = t.toWorldPoint({1, 0, 0});  // x -> -z under +90 degrees about y
  EXPECT_NEAR(w.x, 1.0f, 1e-6f);
  EXPECT_NEAR(w.y, 2.0f, 1e-6f);
  EXPECT_NEAR(w.z, 3.0f - 2.0f, 1e-6f);
  const auto q = quaternionFromRotation(t.rotation);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(q[size_t(k)], i.rotation[size_t(k)], 1e-6f);
}

TEST(SceneDescription, QuaternionFromRotationRoundTripsEveryBranch) {
  // Rotations whose largest diagonal term is each of the four candidates, and w < 0 folded to w > 0.
  const std::array<float, 4> qs[] = {{0.1f, 0.2f, 0.3f, 0.927362f}, {0.95f, 0.1f, 0.2f, 0.2179f},
                                     {0.1f, 0.95f, 0.2f, 0.2179f},   {0.1f, 0.2f, 0.95f, 0.2179f},
                                     {0, 0, 1, 0}};
  for (auto q : qs) {
    const double n = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
    for (float& c : q) c = float(c / n);
    SceneInstance i;
    i.rotation = q;
    const auto back = quaternionFromRotation(i.rigidTransform().rotation);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(back[size_t(k)], q[size_t(k)], 2e-6f) << k;
  }
}

TEST(SceneDescription, WriterTextReadsBackToTheSameValues) {
  auto s = parseSceneDescription(kExample, "ex.json");
  ASSERT_TRUE(s);
  s->instances[0].translation.x = 0.1f;  // the shortest text that reads back as the same float
  auto text = formatSceneDescription(*s);
  ASSERT_TRUE(text) << text.error().toString();
  EXPECT_NE(text->find("\"translation\": [0.1, 0, 0.5]"), std::string::npos) << *text;
  auto back = parseSceneDescription(*text, "back.json");
  ASSERT_TRUE(back) << back.error().toString();
  ASSERT_EQ(back->instances.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back->instances[i].translation.x, s->instances[i].translation.x);
    EXPECT_EQ(back->instances[i].scale, s->instances[i].scale);
    for (size_t k = 0; k < 4; ++k) EXPECT_NEAR(back->instances[i].rotation[k], s->instances[i].rotation[k], 1e-7f);
    EXPECT_EQ(back->instances[i].extrasJson, s->instances[i].extrasJson);
  }
  EXPECT_EQ(back->fields[0].sourceJson, s->fields[0].sourceJson);
  auto again = formatSceneDescription(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *text);
}

TEST(SceneDescription, NegativeZeroReadsBackNegative) {
  // "-0" is the integer 0 to a JSON reader; the writer gives a negative zero a fraction, so that the
  // text reads back to the same bits and formats to the same bytes (found by the scene fuzz target).
  auto s = parseSceneDescription(kExample, "ex.json");
  ASSERT_TRUE(s);
  s->instances[0].translation.y = -0.0f;
  s->instances[0].rotation = {-0.0f, 0.0f, 0.0f, 1.0f};
  auto text = formatSceneDescription(*s);
  ASSERT_TRUE(text) << text.error().toString();
  EXPECT_NE(text->find("\"translation\": [-2, -0.0, 0.5]"), std::string::npos) << *text;
  auto back = parseSceneDescription(*text, "back.json");
  ASSERT_TRUE(back) << back.error().toString();
  EXPECT_TRUE(std::signbit(back->instances[0].translation.y));
  EXPECT_TRUE(std::signbit(back->instances[0].rotation[0]));
  auto again = formatSceneDescription(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *text);
}

TEST(SceneDescription, WriterRefusesWhatTheReaderRefuses) {
  SceneDescription s;
  s.fields.push_back({"a.vff", "", ""});
  s.instances.push_back({});
  s.instances[0].field = 1;
  auto text = formatSceneDescription(s);
  ASSERT_FALSE(text);
  EXPECT_EQ(text.error().code, Code::kSceneFieldIndex);
  // A name that JSON cannot hold is refused, not thrown.
  s.instances[0].field = 0;
  s.fields[0].name = "\xC3\x28";
  auto utf8 = formatSceneDescription(s);
  ASSERT_FALSE(utf8);
  EXPECT_EQ(utf8.error().message, "scene: fields[0]: a string that is not UTF-8");
  s.fields[0].name = "ok";
  s.instances[0].scale = 0;
  auto scale = formatSceneDescription(s);
  ASSERT_FALSE(scale);
  EXPECT_EQ(scale.error().code, Code::kSceneValue);
  EXPECT_NE(text.error().message.find("instances[0].field"), std::string::npos) << text.error().message;
}

struct Bad {
  const char* json;
  Code code;
  const char* where;  // expected in the message
};

TEST(SceneDescription, EveryRuleHasItsError) {
  const std::string head = R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":"a.vff"}],"instances":[)";
  const Bad bad[] = {
      {"not json", Code::kSceneJson, "bad.json:1:"},
      {"[1]", Code::kSceneJson, "not an object"},
      {R"({"fields":[],"instances":[]})", Code::kSceneValue, "bad.json: asset: a required member is missing"},
      {R"({"asset":{"format":"gltf","version":1},"fields":[],"instances":[]})", Code::kSceneVersion, "\"gltf\""},
      {R"({"asset":{"format":"vff-scene","version":2},"fields":[],"instances":[]})", Code::kSceneVersion,
       "asset.version: is 2"},
      {R"({"asset":{"format":"vff-scene","version":1},"instances":[]})", Code::kSceneValue, "fields"},
      {R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":""}],"instances":[]})", Code::kSceneUri,
       "fields[0].uri"},
      {R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":"https://x/a.vff"}],"instances":[]})",
       Code::kSceneUri, "URI scheme"},
      {R"({"asset":{"format":"vff-scene","version":1},"fields":[{"name":"x"}],"instances":[]})", Code::kSceneValue,
       "fields[0].uri"},
      {nullptr, Code::kSceneFieldIndex, "instances[0].field"},  // {"field":1}
      {nullptr, Code::kSceneValue, "instances[0].rotation"},
      {nullptr, Code::kSceneValue, "instances[0].scale"},
      {nullptr, Code::kSceneValue, "instances[0].translation[2]"},
      {nullptr, Code::kSceneValue, "instances[0].translation"},
  };
  const std::string tails[] = {R"({"field":1}]})", R"({"field":0,"rotation":[0,0,0,2]}]})",
                               R"({"field":0,"scale":0}]})", R"({"field":0,"translation":[0,0,1e39]}]})",
                               R"({"field":0,"translation":[0,0]}]})"};
  size_t tail = 0;
  for (const Bad& b : bad) {
    const std::string text = b.json ? std::string(b.json) : head + tails[tail++];
    auto s = parseSceneDescription(text, "bad.json");
    ASSERT_FALSE(s) << text;
    EXPECT_EQ(s.error().code, b.code) << text << ": " << s.error().message;
    EXPECT_NE(s.error().message.find("bad.json"), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find(b.where), std::string::npos) << s.error().message;
  }
}

TEST(SceneDescription, FilesAndUris) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("vff_scene_desc_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "s.vffscene.json").string();
  auto s = parseSceneDescription(kExample, "ex.json");
  ASSERT_TRUE(s);
  ASSERT_TRUE(writeSceneDescription(path, *s));
  auto back = readSceneDescription(path);
  ASSERT_TRUE(back) << back.error().toString();
  EXPECT_EQ(back->fields.size(), 2u);
  EXPECT_EQ(resolveSceneUri(path, "sub/b.vff"), (dir / "sub/b.vff").string());
  EXPECT_EQ(resolveSceneUri(path, "/abs/c.vff"), "/abs/c.vff");
  EXPECT_EQ(resolveSceneUri("s.json", "b.vff"), "b.vff");
  EXPECT_EQ(resolveSceneUri("d/s.json", "a%20b%2Fc%25.vff"), "d/a b/c%.vff");
  EXPECT_EQ(resolveSceneUri("d/s.json", "%2Fabs.vff"), "/abs.vff");
  auto missing = readSceneDescription((dir / "none.json").string());
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, Code::kIoOpen);
  // No temporary is left beside the file.
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  std::filesystem::remove_all(dir);
}

// A writer's names go through encodeSceneUri: the reader accepts them and resolves them back.
TEST(SceneDescription, EncodedUrisResolveToTheirPaths) {
  const std::string names[] = {"a.vff", "my scene #1.mesh0.vff", "100%?.vff", "C:x.vff", "c:/d/e.vff", "tab\tx.vff",
                               "back\\slash.vff", "sub/d\xC3\xA9j\xC3\xA0.vff", "/abs/x:y.vff"};
  for (const std::string& name : names) {
    const std::string uri = encodeSceneUri(name);
    auto s = parseSceneDescription(R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":)" +
                                       nlohmann::json(uri).dump() + R"(}],"instances":[]})", "e.json");
    ASSERT_TRUE(s) << name << ": " << s.error().toString();
    EXPECT_EQ(resolveSceneUri("d/e.json", s->fields[0].uri), name[0] == '/' ? name : "d/" + name) << uri;
  }
  EXPECT_EQ(encodeSceneUri("my scene #1.vff"), "my scene %231.vff");
  EXPECT_EQ(encodeSceneUri("C:x.vff"), "C%3Ax.vff");
  EXPECT_EQ(encodeSceneUri("dir/C:x.vff"), "dir/C:x.vff");
}

// "Finite" and "> 0" hold of the binary32 values (spec/scene.md section 1, rule 4).
TEST(SceneDescription, NumbersAreCheckedInBinary32) {
  const std::string head = R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":"a.vff"}],"instances":[)";
  auto big = parseSceneDescription(head + R"({"field":0,"translation":[0,1e39,0]}]})", "b.json");
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error().code, Code::kSceneValue);
  EXPECT_EQ(big.error().message, "b.json: instances[0].translation[1]: the number 1e+39 is not finite in binary32");
  auto tiny = parseSceneDescription(head + R"({"field":0,"scale":1e-50}]})", "b.json");
  ASSERT_FALSE(tiny);
  EXPECT_EQ(tiny.error().message, "b.json: instances[0].scale: must be positive in binary32, got 1e-50");
  // FLT_MAX and the largest binary64 below the halfway point to 2^128 round to FLT_MAX: finite.
  auto edge = parseSceneDescription(head + R"({"field":0,"translation":[3.4028235e38,3.4028235677973362e38,0]}]})", "b.json");
  ASSERT_TRUE(edge) << edge.error().toString();
  EXPECT_EQ(edge->instances[0].translation.y, 3.4028235e38f);
  auto half = parseSceneDescription(head + R"({"field":0,"translation":[0,3.4028235677973366e38,0]}]})", "b.json");
  ASSERT_FALSE(half);
  EXPECT_EQ(half.error().code, Code::kSceneValue);
}

TEST(SceneDescription, MinorVersionIsANonNegativeInteger) {
  const auto with = [](const std::string& minor) {
    return parseSceneDescription(R"({"asset":{"format":"vff-scene","version":1,"minorVersion":)" + minor +
                                     R"(},"fields":[],"instances":[]})", "m.json");
  };
  for (const char* good : {"0", "7", "-0", "18446744073709551615"}) EXPECT_TRUE(with(good)) << good;
  // An integer is written without a fraction or an exponent (spec/scene.md section 1), unlike JSON
  // Schema's integers by value; one beyond 64 bits is out of range, refused the same way.
  const std::pair<const char*, const char*> bad[] = {{"-1", "-1"}, {"\"1\"", "\"1\""}, {"1.5", "1.5"},
                                                     {"null", "null"}, {"2.0", "2.0"}, {"2e1", "20.0"},
                                                     {"18446744073709551616", "1.8446744073709552e+19"},
                                                     {"-9223372036854775808", "-9223372036854775808"}};
  for (const auto& [text, shownAs] : bad) {
    auto r = with(text);
    ASSERT_FALSE(r) << text;
    EXPECT_EQ(r.error().code, Code::kSceneValue) << text;
    EXPECT_EQ(r.error().message, std::string("m.json: asset.minorVersion: expected a non-negative integer, got ") + shownAs);
  }
}

TEST(SceneDescription, VersionIsTheInteger1AsWritten) {
  const auto with = [](const std::string& version) {
    return parseSceneDescription(R"({"asset":{"format":"vff-scene","version":)" + version +
                                     R"(},"fields":[],"instances":[]})", "v.json");
  };
  EXPECT_TRUE(with("1"));
  for (const char* bad : {"1.0", "1e0", "\"1\"", "-1", "18446744073709551617"}) {
    auto r = with(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_EQ(r.error().code, Code::kSceneVersion) << bad;
  }
  EXPECT_EQ(with("1.0").error().message, "v.json: asset.version: is 1.0; this reader implements version 1");
}

// `field` is an integer as written (no fraction, no exponent, within 64 bits), then an index.
TEST(SceneDescription, FieldIsAnIntegerAsWrittenThenAnIndex) {
  const auto with = [](const std::string& field) {
    return parseSceneDescription(R"({"asset":{"format":"vff-scene","version":1},"fields":[{"uri":"a.vff"},)"
                                 R"({"uri":"b.vff"}],"instances":[{"field":)" + field + "}]}", "f.json");
  };
  const std::pair<const char*, uint32_t> good[] = {{"1", 1}, {"0", 0}, {"-0", 0}};
  for (const auto& [text, index] : good) {
    auto r = with(text);
    ASSERT_TRUE(r) << text << ": " << r.error().toString();
    EXPECT_EQ(r->instances[0].field, index) << text;
  }
  for (const char* bad : {"1.0", "0e5", "1e30", "18446744073709551616", "-9223372036854775809", "true"}) {
    auto r = with(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_EQ(r.error().code, Code::kSceneValue) << bad;
    EXPECT_EQ(r.error().message.rfind("f.json: instances[0].field: expected an integer, got ", 0), 0u) << r.error().message;
  }
  for (const char* out : {"2", "-1", "18446744073709551615", "-9223372036854775808"}) {
    auto r = with(out);
    ASSERT_FALSE(r) << out;
    EXPECT_EQ(r.error().code, Code::kSceneFieldIndex) << out;
    EXPECT_EQ(r.error().message, std::string("f.json: instances[0].field: index ") + out + " is not one of the 2 fields");
  }
}

// The JSON text rules (vff/strict_json.h, spec/scene.md section 1), one case each.
TEST(StrictJson, AcceptsABomAndWhitespaceAround) {
  EXPECT_FALSE(checkStrictJson("\xEF\xBB\xBF {\"a\": [1, 2.5e-3, true, null, \"x\"]}\r\n\t "));
  EXPECT_FALSE(checkStrictJson("[1e308, -1e308, 1e-400, 18446744073709551616]"));
}

std::string where(std::string_view text) {
  const auto p = checkStrictJson(text);
  if (!p) return "accepted";
  return describeJsonProblem(*p, "f.json");
}

TEST(StrictJson, RefusesTrailingBytesNulAndAHalfBom) {
  using namespace std::string_literals;
  EXPECT_EQ(where("{\"a\":1}\0"s), "f.json:1:8: a NUL byte after the JSON value (only whitespace may follow it)");
  EXPECT_EQ(where("{\"a\":\n 1}\n x"), "f.json:3:2: a byte after the JSON value (only whitespace may follow it)");
  EXPECT_EQ(where("{\"a\":[1,\0]}"s), "f.json:1:9: a[1]: a NUL byte (JSON allows none outside strings, and in a string only as \\u0000)");
  EXPECT_EQ(where("[]{}"), "f.json:1:3: a byte after the JSON value (only whitespace may follow it)");
  EXPECT_NE(where("\xEF\xBB{}"), "accepted");
  EXPECT_NE(where("\xEF\xBB\xBF\xEF\xBB\xBF{}"), "accepted");
}

TEST(StrictJson, RefusesNumbersBeyondBinary64AndPlacesThem) {
  EXPECT_EQ(where("{\"extras\": {\"k\": [0,\n  1e400]}}"),
            "f.json:2:3: extras.k[1]: the number 1e400 is not representable as a finite binary64");
  EXPECT_EQ(where("[-1e309]"), "f.json:1:2: [0]: the number -1e309 is not representable as a finite binary64");
}

TEST(StrictJson, RefusesRepeatedNamesAtTheSecondOne) {
  EXPECT_EQ(where("{\"a\": {\"b\": 1,\n \"b\": 2}}"), "f.json:2:2: a.b: the member name \"b\" is repeated in one object");
  EXPECT_EQ(where("{\"a b\": 1, \"a b\": 1}"), "f.json:1:12: [\"a b\"]: the member name \"a b\" is repeated in one object");
  EXPECT_EQ(where("[{\"a\": 1}, {\"a\": 1}]"), "accepted");  // one name per object
}

TEST(StrictJson, NestsAtMost64Deep) {
  const std::string ok = std::string(64, '[') + std::string(64, ']');
  EXPECT_EQ(where(ok), "accepted");
  const std::string deep = std::string(65, '[') + std::string(65, ']');
  const auto p = checkStrictJson(deep);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->byte, 64u);
  EXPECT_EQ(p->column, 65u);
  EXPECT_EQ(p->message, "objects and arrays nest deeper than 64 (a reader limit)");
  // Far deeper than any stack would hold: refused all the same, at the same place.
  const auto far = checkStrictJson(std::string(1000000, '['));
  ASSERT_TRUE(far);
  EXPECT_EQ(far->byte, 64u);
}

TEST(StrictJson, PathsNameTheValueBeingRead) {
  EXPECT_EQ(where("{\"asset\": {\"version\": 1} \"fields\": []}"),
            "f.json:1:33: asset: syntax error while parsing object - unexpected string literal; expected '}'");
  EXPECT_EQ(where("{\"a\": [{\"b\": 1}, {\"c\": [1,, 2]}]}"),
            "f.json:1:27: a[1].c[1]: syntax error while parsing value - unexpected ','; expected '[', '{', or a literal");
}

TEST(StrictJson, RefusesBadUtf8AndLoneSurrogates) {
  // The message does not echo the bytes that are not UTF-8.
  EXPECT_EQ(where("{\"a\": \"\xC3\x28\"}"), "f.json:1:9: a: syntax error while parsing value - invalid string: ill-formed UTF-8 byte");
  EXPECT_NE(where(R"({"a": "\ud800"})"), "accepted");
  EXPECT_EQ(where(R"({"a": "\ud83d\ude00"})"), "accepted");
}

TEST(StrictJson, PathsQuoteNamesThatAreNotIdentifiers) {
  std::string p = "instances[3]";
  appendJsonPathKey(p, "rotation");
  EXPECT_EQ(p, "instances[3].rotation");
  std::string q;
  appendJsonPathKey(q, "fields");
  appendJsonPathKey(q, "1x");
  EXPECT_EQ(q, "fields[\"1x\"]");
}

}  // namespace
}  // namespace vff
