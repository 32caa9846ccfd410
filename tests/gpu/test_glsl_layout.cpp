// The GLSL include (gpu/glsl/vff_query.glsl) against the C++ it must agree with, without any GL
// context (as NanoVDB checks PNanoVDB.h against NanoVDB.h), so it runs where GL and EGL are missing:
// * every top-level `const` of the include: the enum values of vff/format.h and
//   vff::kQueryNeighbours, or one of the few math constants listed here; a constant the test
//   cannot parse or does not know fails, naming it;
// * the default bindings (#define VFF_*_BINDING) against vff::gl::Bindings;
// * the uniform block VffFieldBlock (member names, types, order, std140 offsets and size) against
//   vff::gl::FieldBlock, and the storage block VffPositionsBlock (one vec4 array, std430);
// * what the loader fills in (makeFieldBlock, makePositionsBuffer) against libvff's definitions:
//   one code step is vff::quantizationStep, positions are PositionSet::position, the neighbour
//   lists are vff::queryNeighbours.
// The parser reads the include's own declaration style, one declaration per line, and nothing else.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "vff/encoding.h"
#include "vff/gl/loader.h"
#include "vff/gl/refine_loader.h"
#include "vff/gl/scene_loader.h"
#include "vff/refine.h"
#include "vff/vff.h"

namespace vff {
namespace {

std::string readGlsl(const std::string& file = "vff_query.glsl") {
  std::ifstream in(std::string(VFF_GLSL_DIR) + "/" + file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The include's lines, with `//` comments and trailing blanks removed.
std::vector<std::string> glslLines(const std::string& file = "vff_query.glsl") {
  std::vector<std::string> lines;
  std::istringstream in(readGlsl(file));
  for (std::string line; std::getline(in, line);) {
    if (const size_t c = line.find("//"); c != std::string::npos) line.erase(c);
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// ---- Constants -----------------------------------------------------------------------------------

// A top-level `const` of the include (a declaration that begins in column 0; it may span lines).
struct GlslConstant {
  std::string name, type, value;  // value: the initialiser's text
  bool parsed = false;
  std::string text;               // the declaration as written
};

std::vector<GlslConstant> glslConstants() {
  static const std::regex decl(R"(^const (uint|int|float) ([A-Za-z_][A-Za-z0-9_]*)(\[[0-9]+\])? = ([^;]+);$)");
  std::vector<GlslConstant> out;
  const std::vector<std::string> lines = glslLines();
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("const ", 0) != 0) continue;
    GlslConstant c;
    c.text = lines[i];
    while (c.text.find(';') == std::string::npos && i + 1 < lines.size()) c.text += " " + lines[++i];
    std::smatch m;
    if (std::regex_match(c.text, m, decl)) {
      c.parsed = true;
      c.type = m[1].str() + m[3].str();
      c.name = m[2];
      c.value = m[4];
    }
    out.push_back(c);
  }
  return out;
}

// The format values the include spells, by their GLSL names.
const std::map<std::string, uint32_t>& expectedUintConstants() {
  static const std::map<std::string, uint32_t> k = {
      {"VFF_POSITION_OCTA_HEMI2", uint32_t(PositionScheme::kOctaHemi2)},
      {"VFF_POSITION_EA_OCTA_GRID", uint32_t(PositionScheme::kEqualAreaOctaGrid)},
      {"VFF_POSITION_FIBONACCI", uint32_t(PositionScheme::kSphericalFibonacci)},
      {"VFF_DIRECTION_CONCENTRIC_EQUAL_AREA", uint32_t(DirectionScheme::kConcentricEqualArea)},
      {"VFF_DIRECTION_HEMI_OCTAHEDRAL", uint32_t(DirectionScheme::kHemiOctahedral)},
      {"VFF_ENCODING_UNORM8_DIAMETER", uint32_t(DistanceEncoding::kUnorm8Diameter)},
      {"VFF_ENCODING_UNORM8_CHORD", uint32_t(DistanceEncoding::kUnorm8Chord)},
      {"VFF_ENCODING_UNORM16_DIAMETER", uint32_t(DistanceEncoding::kUnorm16Diameter)},
      {"VFF_ENCODING_BIT1", uint32_t(DistanceEncoding::kBit1)},
      {"VFF_ENCODING_BC4_DIAMETER", uint32_t(DistanceEncoding::kBc4Diameter)},
      {"VFF_NORMAL_NONE", uint32_t(NormalEncoding::kNone)},
      {"VFF_NEIGHBOURS", kQueryNeighbours},
  };
  return k;
}

// Constants of the include's own arithmetic, with no C++ counterpart to check against.
const std::map<std::string, std::string>& localConstants() {
  static const std::map<std::string, std::string> k = {
      {"kVffPi", "float"},          // pi, for the concentric map's angles
      {"kVffQuarterPi", "float"},   // pi / 4
      {"VFF_FIB", "uint[22]"},      // Fibonacci numbers, for the nearest Fibonacci sample
      {"VFF_OFF_OBJECT", "float"},  // the intraBias that selects spec/geometry.md 7.4 (vff::RayOrigin::kOffObject)
  };
  return k;
}

TEST(GlslConstants, EveryConstantIsParsedAndKnown) {
  const std::vector<GlslConstant> all = glslConstants();
  ASSERT_FALSE(all.empty()) << "no top-level const in " << VFF_GLSL_DIR << "/vff_query.glsl";
  for (const GlslConstant& c : all) {
    if (!c.parsed) {
      ADD_FAILURE() << "cannot parse the GLSL constant declaration: " << c.text;
      continue;
    }
    const bool format = expectedUintConstants().count(c.name) != 0;
    const auto local = localConstants().find(c.name);
    EXPECT_TRUE(format || local != localConstants().end())
        << "the GLSL constant " << c.name << " is checked against nothing: add it to this test";
    if (local != localConstants().end()) {
      EXPECT_EQ(c.type, local->second) << "the GLSL constant " << c.name;
    }
  }
}

TEST(GlslConstants, FormatValuesMatchTheCppHeaders) {
  std::map<std::string, GlslConstant> byName;
  for (const GlslConstant& c : glslConstants()) byName[c.name] = c;
  static const std::regex uintLiteral(R"(^([0-9]+)u$)");
  for (const auto& [name, value] : expectedUintConstants()) {
    const auto it = byName.find(name);
    if (it == byName.end()) {
      ADD_FAILURE() << "the GLSL constant " << name << " is missing";
      continue;
    }
    std::smatch m;
    if (it->second.type != "uint" || !std::regex_match(it->second.value, m, uintLiteral)) {
      ADD_FAILURE() << "the GLSL constant " << name << " is not a uint literal: " << it->second.text;
      continue;
    }
    EXPECT_EQ(std::stoul(m[1]), value) << "the GLSL constant " << name << " differs from the C++ value";
  }
  EXPECT_EQ(gl::kNeighbours, kQueryNeighbours);
  EXPECT_EQ(kQueryNeighbours % 4, 0u) << "the neighbour lists are read as whole vec4";
}

TEST(GlslConstants, DefaultBindingsMatchLoaderBindings) {
  static const std::regex define(R"(^#define (VFF_[A-Z]+_BINDING) ([0-9]+)$)");
  std::map<std::string, uint32_t> found;
  for (const char* file : {"vff_query.glsl", "vff_refine.glsl"})
    for (const std::string& line : glslLines(file)) {
      std::smatch m;
      if (std::regex_match(line, m, define)) found[m[1]] = uint32_t(std::stoul(m[2]));
    }
  const gl::Bindings b;
  const gl::RefinementBindings rb;  // the refined path's (vff_refine.glsl)
  const std::map<std::string, uint32_t> expected = {{"VFF_FIELD_BINDING", b.field},
                                                    {"VFF_MAPS_BINDING", b.maps},
                                                    {"VFF_POSITIONS_BINDING", b.positions},
                                                    {"VFF_NORMALS_BINDING", b.normals},
                                                    {"VFF_UNSURE_BINDING", rb.unsure},
                                                    {"VFF_VERTICES_BINDING", rb.vertices},
                                                    {"VFF_BVH_BINDING", rb.bvh},
                                                    {"VFF_TRIANGLES_BINDING", rb.triangles},
                                                    {"VFF_REFINE_BINDING", rb.block}};
  for (const auto& [name, value] : expected) {
    const auto it = found.find(name);
    if (it == found.end()) {
      ADD_FAILURE() << "the GLSL default " << name << " is missing";
      continue;
    }
    EXPECT_EQ(it->second, value) << "the GLSL default " << name << " differs from vff::gl::Bindings";
  }
  EXPECT_EQ(found.size(), expected.size()) << "a GLSL binding default is checked against nothing";
  // Distinct numbers: the declarations stay valid for Vulkan (one namespace per descriptor set).
  std::set<uint32_t> numbers;
  for (const auto& [name, value] : expected) numbers.insert(value);
  EXPECT_EQ(numbers.size(), expected.size()) << "two GLSL binding defaults share a number";
}

// ---- Blocks --------------------------------------------------------------------------------------

struct Member {
  std::string type, name;
  size_t offset = 0, size = 0;
};

// The members of the block that begins with the line `header`, up to the line `footer`.
std::vector<Member> glslBlock(const std::string& header, const std::string& footer,
                              const std::string& file = "vff_query.glsl") {
  static const std::regex member(R"(^  (float|int|uint|vec[234]|ivec[234]|uvec[234]) ([A-Za-z_][A-Za-z0-9_]*)(\[\])?;$)");
  std::vector<Member> out;
  const std::vector<std::string> lines = glslLines(file);
  size_t i = 0;
  while (i < lines.size() && lines[i] != header) ++i;
  if (i == lines.size()) {
    ADD_FAILURE() << "the GLSL block is missing: " << header;
    return out;
  }
  for (++i; i < lines.size() && lines[i] != footer; ++i) {
    if (lines[i].empty()) continue;
    std::smatch m;
    if (!std::regex_match(lines[i], m, member)) {
      ADD_FAILURE() << "cannot parse the GLSL block member: " << lines[i];
      continue;
    }
    out.push_back({m[1].str() + m[3].str(), m[2], 0, 0});
  }
  if (i == lines.size()) ADD_FAILURE() << "the GLSL block does not end with " << footer;
  return out;
}

// std140 offsets of scalar and vector members: base alignment 4 (scalars), 8 (two components),
// 16 (three and four), size 4 per component.
void layoutStd140(std::vector<Member>& members) {
  size_t at = 0;
  for (Member& m : members) {
    const char last = m.type.back();
    const size_t n = (last >= '2' && last <= '4') ? size_t(last - '0') : 1;
    const size_t align = n == 1 ? 4 : n == 2 ? 8 : 16;
    m.offset = (at + align - 1) / align * align;
    m.size = 4 * n;
    at = m.offset + m.size;
  }
}

template <class T>
constexpr const char* glslTypeOf() {
  if constexpr (std::is_same_v<T, float>) return "float";
  else if constexpr (std::is_same_v<T, uint32_t>) return "uint";
  else if constexpr (std::is_same_v<T, int32_t>) return "int";
  else if constexpr (std::is_same_v<T, float[3]>) return "vec3";
  else if constexpr (std::is_same_v<T, float[4]>) return "vec4";
  else static_assert(sizeof(T) == 0, "a FieldBlock member of a type this test does not map to GLSL");
}

#define VFF_FIELD_MEMBER(m) \
  Member { glslTypeOf<decltype(gl::FieldBlock::m)>(), #m, offsetof(gl::FieldBlock, m), sizeof(gl::FieldBlock::m) }

// vff::gl::FieldBlock member by member (a member missing here fails the tiling check below).
std::vector<Member> cppFieldBlock() {
  static_assert(std::is_standard_layout_v<gl::FieldBlock>);
  return {VFF_FIELD_MEMBER(sphereCenter),   VFF_FIELD_MEMBER(sphereRadius),     VFF_FIELD_MEMBER(positionScheme),
          VFF_FIELD_MEMBER(positionParam),  VFF_FIELD_MEMBER(mapCount),         VFF_FIELD_MEMBER(directionScheme),
          VFF_FIELD_MEMBER(mapResolution),  VFF_FIELD_MEMBER(distanceEncoding), VFF_FIELD_MEMBER(missCode),
          VFF_FIELD_MEMBER(normalEncoding), VFF_FIELD_MEMBER(target),           VFF_FIELD_MEMBER(gutter),
          VFF_FIELD_MEMBER(tileSize),       VFF_FIELD_MEMBER(tilesPerRow),      VFF_FIELD_MEMBER(tilesPerColumn),
          VFF_FIELD_MEMBER(sliceWidth),     VFF_FIELD_MEMBER(sliceHeight),      VFF_FIELD_MEMBER(sliceCount),
          VFF_FIELD_MEMBER(intraBias),      VFF_FIELD_MEMBER(distanceScale),    VFF_FIELD_MEMBER(invRadius),
          VFF_FIELD_MEMBER(twoRadius),      VFF_FIELD_MEMBER(neighbourOffset),  VFF_FIELD_MEMBER(kernelRadius2),
          VFF_FIELD_MEMBER(reserved0),      VFF_FIELD_MEMBER(reserved1)};
}

TEST(GlslLayout, FieldBlockMatchesTheLoaderStruct) {
  std::vector<Member> glsl = glslBlock("layout(std140, binding = VFF_FIELD_BINDING) uniform VffFieldBlock {",
                                       "} vffField;");
  layoutStd140(glsl);
  const std::vector<Member> cpp = cppFieldBlock();
  // The listed C++ members cover FieldBlock without gaps, so none is left out of the comparison.
  size_t end = 0;
  for (const Member& m : cpp) {
    EXPECT_EQ(m.offset, end) << "vff::gl::FieldBlock::" << m.name << " does not follow the member before it";
    end = m.offset + m.size;
  }
  EXPECT_EQ(end, sizeof(gl::FieldBlock)) << "vff::gl::FieldBlock has members this test does not list";
  for (size_t i = 0; i < std::max(glsl.size(), cpp.size()); ++i) {
    if (i >= glsl.size()) {
      ADD_FAILURE() << "VffFieldBlock lacks vff::gl::FieldBlock::" << cpp[i].name;
      continue;
    }
    if (i >= cpp.size()) {
      ADD_FAILURE() << "VffFieldBlock." << glsl[i].name << " has no vff::gl::FieldBlock member";
      continue;
    }
    const Member &g = glsl[i], &c = cpp[i];
    EXPECT_EQ(g.name, c.name) << "member " << i << " of VffFieldBlock";
    EXPECT_EQ(g.type, c.type) << "VffFieldBlock." << g.name;
    EXPECT_EQ(g.offset, c.offset) << "the std140 offset of VffFieldBlock." << g.name;
    EXPECT_EQ(g.size, c.size) << "the size of VffFieldBlock." << g.name;
  }
  // A std140 block's size is rounded up to a vec4.
  const size_t glslEnd = glsl.empty() ? 0 : glsl.back().offset + glsl.back().size;
  EXPECT_EQ((glslEnd + 15) / 16 * 16, sizeof(gl::FieldBlock)) << "the std140 size of VffFieldBlock";
}

TEST(GlslLayout, PositionsBlockIsOneVec4Array) {
  // makePositionsBuffer's floats are read four at a time: std430 vec4 array, stride 16.
  const std::vector<Member> glsl = glslBlock(
      "layout(std430, binding = VFF_POSITIONS_BINDING) readonly buffer VffPositionsBlock {", "};");
  ASSERT_EQ(glsl.size(), 1u);
  EXPECT_EQ(glsl[0].type, "vec4[]");
  EXPECT_EQ(glsl[0].name, "vffPositions");
}

// ---- The scene's structures (gpu/glsl/vff_scene.glsl) ---------------------------------------------
// Its storage blocks hold arrays of these structs (std430); with only scalars, vec3 followed by a
// scalar, and vec4 members, std430 offsets equal the std140 ones computed here, and the structs'
// sizes are multiples of 16 (their array stride).

void expectSameMembers(const std::vector<Member>& glsl, const std::vector<Member>& cpp, size_t cppSize,
                       const std::string& what) {
  size_t end = 0;
  for (const Member& m : cpp) {
    EXPECT_EQ(m.offset, end) << what << ": the C++ member " << m.name << " does not follow the one before it";
    end = m.offset + m.size;
  }
  EXPECT_EQ(end, cppSize) << what << ": the C++ struct has members this test does not list";
  ASSERT_EQ(glsl.size(), cpp.size()) << what;
  for (size_t i = 0; i < glsl.size(); ++i) {
    EXPECT_EQ(glsl[i].name, cpp[i].name) << what << " member " << i;
    EXPECT_EQ(glsl[i].type, cpp[i].type) << what << "." << glsl[i].name;
    EXPECT_EQ(glsl[i].offset, cpp[i].offset) << what << "." << glsl[i].name;
    EXPECT_EQ(glsl[i].size, cpp[i].size) << what << "." << glsl[i].name;
  }
  EXPECT_EQ(cppSize % 16, 0u) << what << ": an array stride is a multiple of 16";
}

#define VFF_MEMBER_AT(glslType, glslName, type, member, extra, bytes) \
  Member { glslType, glslName, offsetof(type, member) + (extra), bytes }

TEST(GlslSceneLayout, SceneFieldIsTheFieldBlockThenItsPlace) {
  std::vector<Member> glsl = glslBlock("struct VffSceneField {", "};", "vff_scene.glsl");
  layoutStd140(glsl);
  std::vector<Member> cpp = cppFieldBlock();
  static_assert(offsetof(gl::SceneFieldBlock, field) == 0);
  cpp.push_back(VFF_MEMBER_AT("uint", "mapsLayer", gl::SceneFieldBlock, mapsLayer, 0, 4));
  cpp.push_back(VFF_MEMBER_AT("uint", "normalsLayer", gl::SceneFieldBlock, normalsLayer, 0, 4));
  cpp.push_back(VFF_MEMBER_AT("uint", "positionsBase", gl::SceneFieldBlock, positionsBase, 0, 4));
  cpp.push_back(VFF_MEMBER_AT("uint", "reserved2", gl::SceneFieldBlock, reserved2, 0, 4));
  expectSameMembers(glsl, cpp, sizeof(gl::SceneFieldBlock), "VffSceneField");
}

TEST(GlslSceneLayout, SceneInstanceMatchesTheLoaderStruct) {
  std::vector<Member> glsl = glslBlock("struct VffSceneInstance {", "};", "vff_scene.glsl");
  layoutStd140(glsl);
  using I = gl::SceneInstanceBlock;
  const std::vector<Member> cpp = {
      VFF_MEMBER_AT("vec4", "rotation0", I, rotation, 0, 16), VFF_MEMBER_AT("vec4", "rotation1", I, rotation, 16, 16),
      VFF_MEMBER_AT("vec4", "rotation2", I, rotation, 32, 16), VFF_MEMBER_AT("vec3", "translation", I, translation, 0, 12),
      VFF_MEMBER_AT("float", "invScale", I, invScale, 0, 4),   VFF_MEMBER_AT("vec4", "sphere", I, sphere, 0, 16),
      VFF_MEMBER_AT("uint", "id", I, id, 0, 4),                VFF_MEMBER_AT("uint", "field", I, field, 0, 4),
      VFF_MEMBER_AT("float", "scale", I, scale, 0, 4),         VFF_MEMBER_AT("uint", "reserved", I, reserved, 0, 4)};
  expectSameMembers(glsl, cpp, sizeof(I), "VffSceneInstance");
}

TEST(GlslSceneLayout, SceneNodeMatchesTheExportedNode) {
  std::vector<Member> glsl = glslBlock("struct VffSceneNode {", "};", "vff_scene.glsl");
  layoutStd140(glsl);
  using N = SceneNode;
  const std::vector<Member> cpp = {
      VFF_MEMBER_AT("vec4", "loX", N, lo, 0, 16),     VFF_MEMBER_AT("vec4", "loY", N, lo, 16, 16),
      VFF_MEMBER_AT("vec4", "loZ", N, lo, 32, 16),    VFF_MEMBER_AT("vec4", "hiX", N, hi, 0, 16),
      VFF_MEMBER_AT("vec4", "hiY", N, hi, 16, 16),    VFF_MEMBER_AT("vec4", "hiZ", N, hi, 32, 16),
      VFF_MEMBER_AT("uvec4", "child", N, child, 0, 16), VFF_MEMBER_AT("uvec4", "count", N, count, 0, 16),
      VFF_MEMBER_AT("uvec4", "valid", N, valid, 0, 16)};  // valid, then the three reserved words
  expectSameMembers(glsl, cpp, sizeof(N), "VffSceneNode");
}

TEST(GlslSceneLayout, NodesHeaderMatchesTheLoaderStruct) {
  // The block's scalars up to the node array.
  std::vector<Member> glsl = glslBlock(
      "layout(std430, binding = VFF_SCENE_NODES_BINDING) readonly buffer VffSceneNodesBlock {",
      "  VffSceneNode vffSceneNodes[];", "vff_scene.glsl");
  layoutStd140(glsl);
  using H = gl::SceneNodesHeader;
  const std::vector<Member> cpp = {VFF_MEMBER_AT("uint", "vffSceneNodeCount", H, nodeCount, 0, 4),
                                   VFF_MEMBER_AT("float", "vffSceneMaxRadius", H, maxRadius, 0, 4),
                                   VFF_MEMBER_AT("uint", "vffSceneInstanceCount", H, instanceCount, 0, 4),
                                   VFF_MEMBER_AT("uint", "vffSceneReserved", H, reserved, 0, 4)};
  expectSameMembers(glsl, cpp, sizeof(H), "VffSceneNodesBlock's header");
}

TEST(GlslSceneLayout, DefaultBindingsAndStackMatchTheLoader) {
  static const std::regex def(R"(^#define (VFF_SCENE_[A-Z_]+) ([0-9]+)$)");
  std::map<std::string, uint32_t> found;
  for (const std::string& line : glslLines("vff_scene.glsl")) {
    std::smatch m;
    if (std::regex_match(line, m, def)) found[m[1]] = uint32_t(std::stoul(m[2]));
  }
  const gl::SceneBindings b;
  const gl::Bindings single;
  const std::map<std::string, uint32_t> expected = {{"VFF_SCENE_FIELDS_BINDING", b.fields},
                                                    {"VFF_SCENE_INSTANCES_BINDING", b.instances},
                                                    {"VFF_SCENE_NODES_BINDING", b.nodes},
                                                    {"VFF_SCENE_STACK", gl::kSceneStack}};
  EXPECT_EQ(found, expected);
  // The fields' resources are vff_query.glsl's, at its default bindings.
  EXPECT_EQ(b.maps, single.maps);
  EXPECT_EQ(b.positions, single.positions);
  EXPECT_EQ(b.normals, single.normals);
}

TEST(GlslSceneLayout, ShaderSourceReplacesTheIncludeLine) {
  const std::string scene = readGlsl("vff_scene.glsl"), query = readGlsl("vff_query.glsl");
  const std::string src = gl::sceneShaderSource(scene, query);
  EXPECT_EQ(src.find("#include \"vff_query.glsl\""), std::string::npos);
  EXPECT_EQ(src.size(), scene.size() - std::string("#include \"vff_query.glsl\"").size() + query.size());
  // The macros that select the field come before the include's text.
  EXPECT_LT(src.find("#define VFF_FIELD vffSceneFields"), src.find("#ifndef VFF_QUERY_GLSL"));
}

// ---- What the loader fills in, against libvff ------------------------------------------------------

FieldDesc makeField(PositionScheme p, uint32_t n, DirectionScheme d, DistanceEncoding e, uint32_t m, float radius) {
  return {.sphere = {{0.25f, -1.5f, 3.0f}, radius}, .positionScheme = p, .positionParam = n,
          .mapCount = positionCount(p, n).value(), .directionScheme = d, .mapResolution = m, .distanceEncoding = e};
}

TEST(GlslLayout, DistanceScaleIsQuantizationStep) {
  for (float radius : {1.0f, 1.28641f, 0.1f, 37.5f, 3.0e-3f})
    for (DistanceEncoding e : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm8Chord,
                               DistanceEncoding::kUnorm16Diameter, DistanceEncoding::kBit1,
                               DistanceEncoding::kBc4Diameter}) {
      const FieldDesc f =
          makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea, e, 32, radius);
      auto layout = computeLayout(f, {});
      ASSERT_TRUE(layout.ok()) << layout.error().toString();
      auto b = gl::makeFieldBlock(f, *layout);
      ASSERT_TRUE(b.ok()) << b.error().toString();
      // unorm8-chord's step is per texel (the table in the positions buffer); bit1 has none.
      const float expected =
          e == DistanceEncoding::kUnorm8Chord ? 0.0f : quantizationStep(e, radius, 1.0f);
      EXPECT_TRUE(sameBits(b->distanceScale, expected))
          << distanceEncodingName(e) << " R " << radius << ": " << b->distanceScale << " vs " << expected;
      EXPECT_EQ(b->missCode, missCode(e));
      EXPECT_EQ(b->distanceEncoding, uint32_t(e));
    }
}

TEST(GlslLayout, PositionsBufferHoldsLibvffValues) {
  for (DirectionScheme d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
    for (DistanceEncoding e : {DistanceEncoding::kUnorm8Chord, DistanceEncoding::kUnorm8Diameter}) {
      const FieldDesc f = makeField(PositionScheme::kSphericalFibonacci, 100, d, e, 37, 1.28641f);
      auto layout = computeLayout(f, {});
      ASSERT_TRUE(layout.ok()) << layout.error().toString();
      auto b = gl::makeFieldBlock(f, *layout);
      auto buf = gl::makePositionsBuffer(f);
      ASSERT_TRUE(b.ok() && buf.ok());
      auto ps = PositionSet::fromField(f);
      ASSERT_TRUE(ps.ok());
      const std::vector<uint32_t> nb = queryNeighbours(*ps);
      ASSERT_EQ(buf->size(), size_t(b->neighbourOffset) * 4 + nb.size());
      for (uint32_t k = 0; k < f.mapCount; ++k) {
        const Vec3 u = ps->position(k);
        const float* p = &(*buf)[4 * size_t(k)];
        EXPECT_TRUE(sameBits(p[0], u.x) && sameBits(p[1], u.y) && sameBits(p[2], u.z) && p[3] == 0.0f)
            << "position " << k;
      }
      const uint32_t m = f.mapResolution;
      if (e == DistanceEncoding::kUnorm8Chord) {
        EXPECT_EQ(b->neighbourOffset, f.mapCount + (m * m + 3) / 4);
        for (uint32_t j = 0; j < m; ++j)
          for (uint32_t i = 0; i < m; ++i) {
            const float cosAlpha = texelDirection(d, m, i, j).z;
            const float step = quantizationStep(e, f.sphere.radius, cosAlpha);
            const float got = (*buf)[size_t(f.mapCount) * 4 + size_t(j) * m + i];
            EXPECT_TRUE(sameBits(got, step)) << "chord step of texel " << i << "," << j;
          }
      } else {
        EXPECT_EQ(b->neighbourOffset, f.mapCount);
      }
      for (size_t i = 0; i < nb.size(); ++i) {
        const float expected = nb[i] == UINT32_MAX ? -1.0f : float(nb[i]);
        EXPECT_EQ((*buf)[size_t(b->neighbourOffset) * 4 + i], expected) << "neighbour list entry " << i;
      }
    }
}

}  // namespace
}  // namespace vff

namespace vff {
namespace {

// ---- What the scene loader plans (planScene), without GL ----------------------------------------

LayoutDesc layoutOf(const FieldDesc& f, uint32_t maxSize, uint32_t gutter,
                    LayoutTarget target = LayoutTarget::kTexture2DArray) {
  LayoutLimits l;
  l.target = target;
  l.maxTextureSize = maxSize;
  l.gutter = gutter;
  return computeLayout(f, l).value();
}

TEST(GlslSceneLayout, PlanAppendsEachFieldsSlicesAndPositions) {
  const FieldDesc a = makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea,
                                DistanceEncoding::kUnorm8Diameter, 32, 1.0f);
  FieldDesc b = makeField(PositionScheme::kEqualAreaOctaGrid, 9, DirectionScheme::kHemiOctahedral,
                          DistanceEncoding::kUnorm8Chord, 16, 2.0f);
  b.normalEncoding = NormalEncoding::kOctSnorm16;
  const FieldDesc c = makeField(PositionScheme::kSphericalFibonacci, 100, DirectionScheme::kConcentricEqualArea,
                                DistanceEncoding::kBit1, 32, 0.5f);
  const FieldDesc fields[] = {a, b, c};
  const LayoutDesc layouts[] = {layoutOf(a, 256, 1), layoutOf(b, 128, 0), layoutOf(c, 512, 0)};
  auto plan = gl::planScene(fields, layouts);
  ASSERT_TRUE(plan.ok()) << plan.error().toString();
  ASSERT_EQ(plan->fields.size(), 3u);
  uint32_t layer = 0, base = 0, width = 0, height = 0;
  for (int f = 0; f < 3; ++f) {
    const gl::SceneFieldBlock& s = plan->fields[f];
    EXPECT_EQ(s.mapsLayer, layer) << "field " << f;
    EXPECT_EQ(s.positionsBase, base) << "field " << f;
    // The block is the single field's (neighbourOffset stays relative to the field's base).
    const gl::FieldBlock single = gl::makeFieldBlock(fields[f], layouts[f]).value();
    EXPECT_EQ(std::memcmp(&s.field, &single, sizeof single), 0) << "field " << f;
    const std::vector<float> positions = gl::makePositionsBuffer(fields[f]).value();
    for (size_t i = 0; i < positions.size(); ++i)
      ASSERT_TRUE(sameBits(plan->positions[size_t(base) * 4 + i], positions[i])) << "field " << f << " float " << i;
    layer += layouts[f].sliceCount;
    base += uint32_t((positions.size() + 3) / 4);
    width = std::max(width, fields[f].distanceEncoding == DistanceEncoding::kBit1 ? layouts[f].sliceWidth / 8
                                                                                  : layouts[f].sliceWidth);
    height = std::max(height, layouts[f].sliceHeight);
  }
  EXPECT_EQ(plan->mapsLayers, layer);
  EXPECT_EQ(plan->mapsWidth, width);
  EXPECT_EQ(plan->mapsHeight, height);
  EXPECT_EQ(plan->positions.size(), size_t(base) * 4);
  EXPECT_FALSE(plan->wideTexels);
  // Only b has normals: its slices alone, from layer 0.
  EXPECT_EQ(plan->fields[1].normalsLayer, 0u);
  EXPECT_EQ(plan->normalsLayers, layouts[1].sliceCount);
  EXPECT_EQ(plan->normalsWidth, layouts[1].sliceWidth);
}

TEST(GlslSceneLayout, PlanRefusesWhatOneTextureCannotHold) {
  const FieldDesc u8 = makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea,
                                 DistanceEncoding::kUnorm8Diameter, 32, 1.0f);
  const FieldDesc u16 = makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea,
                                  DistanceEncoding::kUnorm16Diameter, 32, 1.0f);
  const FieldDesc bc4 = makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea,
                                  DistanceEncoding::kBc4Diameter, 32, 1.0f);
  auto code = [](std::initializer_list<FieldDesc> f, std::initializer_list<LayoutDesc> l) {
    auto p = gl::planScene(std::vector<FieldDesc>(f), std::vector<LayoutDesc>(l));
    return p.ok() ? Code::kOk : p.error().code;
  };
  EXPECT_EQ(code({u16, u16}, {layoutOf(u16, 256, 0), layoutOf(u16, 512, 1)}), Code::kOk);
  EXPECT_EQ(code({u8, u16}, {layoutOf(u8, 256, 0), layoutOf(u16, 256, 0)}), Code::kUnsupported);
  EXPECT_EQ(code({u8, bc4}, {layoutOf(u8, 256, 0), layoutOf(bc4, 256, 0)}), Code::kUnsupported);
  EXPECT_EQ(code({u8}, {layoutOf(u8, 256, 0, LayoutTarget::kTexture3D)}), Code::kUnsupported);
  EXPECT_EQ(code({}, {}), Code::kInvalidArgument);
}

// ---- The refined path (vff_refine.glsl) and what loadRefinement uploads, without GL -----------------

TEST(GlslRefineLayout, RefineBlockMatchesTheLoaderStruct) {
  std::vector<Member> glsl =
      glslBlock("layout(std140, binding = VFF_REFINE_BINDING) uniform VffRefineBlock {", "} vffRefine;",
                "vff_refine.glsl");
  layoutStd140(glsl);
  using B = gl::RefineBlock;
  const std::vector<Member> cpp = {VFF_MEMBER_AT("float", "margin", B, margin, 0, 4),
                                   VFF_MEMBER_AT("uint", "triangleCount", B, triangleCount, 0, 4),
                                   VFF_MEMBER_AT("uint", "nodeCount", B, nodeCount, 0, 4),
                                   VFF_MEMBER_AT("uint", "stackDepth", B, stackDepth, 0, 4)};
  expectSameMembers(glsl, cpp, sizeof(B), "VffRefineBlock");
}

TEST(GlslRefineLayout, StorageBlocksAreWordArrays) {
  // makeRefinementBuffers' vectors are uploaded as they are: std430 arrays of 4-byte words (the
  // BVH's 8 words a node read as two uvec4).
  const std::pair<const char*, const char*> blocks[] = {
      {"layout(std430, binding = VFF_UNSURE_BINDING) readonly buffer VffUnsureBlock {", "uint[] vffUnsure"},
      {"layout(std430, binding = VFF_VERTICES_BINDING) readonly buffer VffVerticesBlock {", "float[] vffVertices"},
      {"layout(std430, binding = VFF_BVH_BINDING) readonly buffer VffBvhBlock {", "uvec4[] vffBvh"},
      {"layout(std430, binding = VFF_TRIANGLES_BINDING) readonly buffer VffTrianglesBlock {", "uint[] vffTriangles"}};
  for (const auto& [header, member] : blocks) {
    const std::vector<Member> glsl = glslBlock(header, "};", "vff_refine.glsl");
    ASSERT_EQ(glsl.size(), 1u) << header;
    EXPECT_EQ(glsl[0].type + " " + glsl[0].name, member) << header;
  }
}

TEST(GlslRefineLayout, StackDefaultIsTheLoaders) {
  static const std::regex def(R"(^#define VFF_REFINE_STACK ([0-9]+)$)");
  int found = 0;
  for (const std::string& line : glslLines("vff_refine.glsl")) {
    std::smatch m;
    if (!std::regex_match(line, m, def)) continue;
    ++found;
    EXPECT_EQ(uint32_t(std::stoul(m[1])), gl::kRefineStack);
  }
  EXPECT_EQ(found, 1);
  gl::RefineBlock b;
  b.stackDepth = 17;
  EXPECT_EQ(gl::refinementShaderDefines(b), "#define VFF_REFINED\n#define VFF_REFINE_STACK 17\n");
  b.stackDepth = 0;  // a BVH of one leaf: GLSL arrays hold at least one entry
  EXPECT_EQ(gl::refinementShaderDefines(b), "#define VFF_REFINED\n#define VFF_REFINE_STACK 1\n");
}

// A field with random codes and random triangles inside its sphere: enough of both for unsure
// texels and a BVH of several levels.
struct SyntheticRefinement {
  FieldDesc field;
  std::vector<uint8_t> distance;
  Refinement refinement;
};

SyntheticRefinement syntheticRefinement() {
  SyntheticRefinement s;
  s.field = makeField(PositionScheme::kOctaHemi2, 4, DirectionScheme::kConcentricEqualArea,
                      DistanceEncoding::kUnorm8Diameter, 16, 1.28641f);
  std::mt19937 rng(8501);
  std::uniform_int_distribution<int> code(0, 255);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  s.distance.resize(size_t(s.field.mapCount) * 16 * 16);
  for (uint8_t& c : s.distance) c = uint8_t(code(rng));
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  for (uint32_t t = 0; t < 300; ++t) {
    for (int v = 0; v < 3; ++v) {
      for (int a = 0; a < 3; ++a) positions.push_back(s.field.sphere.center[a] + u(rng));
      indices.push_back(uint32_t(indices.size()));
    }
  }
  auto r = makeRefinement(s.field, s.distance, positions, indices);
  EXPECT_TRUE(r.ok()) << r.error().toString();
  if (r.ok()) s.refinement = std::move(*r);
  return s;
}

// The depth of node n's subtree's deepest leaf below n (recursively, as an independent check of
// the loader's walk).
uint32_t subtreeDepth(const std::vector<uint32_t>& nodes, size_t n) {
  if (nodes[8 * n + 7] != 0) return 0;
  return 1 + std::max(subtreeDepth(nodes, n + 1), subtreeDepth(nodes, nodes[8 * n + 3]));
}

TEST(GlslRefineLayout, BuffersHoldLibvffValues) {
  const SyntheticRefinement s = syntheticRefinement();
  const RefinementView view = s.refinement.view();
  ASSERT_FALSE(view.empty());
  ASSERT_GT(view.unsureTexels, 0u);
  auto b = gl::makeRefinementBuffers(s.field, view);
  ASSERT_TRUE(b.ok()) << b.error().toString();
  // The margin in object units is the CPU query's float product.
  EXPECT_TRUE(sameBits(b->block.margin, view.margin * s.field.sphere.radius));
  // Every texel's bit, where the shader reads it.
  const uint64_t texels = uint64_t(s.field.mapCount) * s.field.mapResolution * s.field.mapResolution;
  ASSERT_EQ(b->unsure.size(), (texels + 31) / 32);
  uint64_t set = 0;
  for (uint64_t x = 0; x < texels; ++x) {
    const bool bit = (b->unsure[x >> 5] >> (x & 31)) & 1u;
    ASSERT_EQ(bit, view.isUnsure(x)) << "texel " << x;
    set += bit;
  }
  EXPECT_EQ(set, view.unsureTexels);
  ASSERT_EQ(b->vertices.size(), view.positions.size());
  for (size_t i = 0; i < view.positions.size(); ++i) ASSERT_TRUE(sameBits(b->vertices[i], view.positions[i]));
  // The CPU query's BVH, word for word.
  const RefinementBvh bvh = buildRefinementBvh(view);
  EXPECT_EQ(b->nodes, bvh.nodes);
  EXPECT_EQ(b->triangles, bvh.triangles);
  EXPECT_EQ(b->block.nodeCount, bvh.nodes.size() / 8);
  EXPECT_EQ(b->block.triangleCount, view.indices.size() / 3);
  EXPECT_EQ(b->block.stackDepth, subtreeDepth(bvh.nodes, 0));
  EXPECT_GT(b->block.stackDepth, 2u);
  EXPECT_LE(b->block.stackDepth, gl::kRefineStack);
}

TEST(GlslRefineLayout, EmptyAndMismatchedRefinements) {
  const SyntheticRefinement s = syntheticRefinement();
  // No refinement: triangleCount 0 (the shader answers as kNearest), one word per buffer.
  auto empty = gl::makeRefinementBuffers(s.field, RefinementView{});
  ASSERT_TRUE(empty.ok()) << empty.error().toString();
  EXPECT_EQ(empty->block.triangleCount, 0u);
  EXPECT_EQ(empty->block.nodeCount, 0u);
  EXPECT_FALSE(empty->unsure.empty() || empty->vertices.empty() || empty->nodes.empty() || empty->triangles.empty());
  // Another field's refinement: FieldQuery::fromMaps's error.
  FieldDesc other = s.field;
  other.mapResolution = 32;
  auto bad = gl::makeRefinementBuffers(other, s.refinement.view());
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kInvalidArgument);
  auto cpu = FieldQuery::fromMaps(other, std::vector<uint8_t>(size_t(other.mapCount) * 32 * 32, 255), {},
                                  s.refinement.view());
  ASSERT_FALSE(cpu.ok());
  EXPECT_EQ(cpu.error().code, bad.error().code);
}

}  // namespace
}  // namespace vff
