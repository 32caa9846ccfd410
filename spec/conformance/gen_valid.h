// gen_valid.h - the valid conformance vectors: what each covers, how it is written, what a reader
// must decode from it (expected.json) and the generator's check that libvff reads it back
// (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <string>
#include <vector>

#include "gen_bytes.h"
#include "gen_scene.h"
#include "vff/vff.h"

namespace vff::gen {

// What is done to the written file before it is stored.
// kMetaText: the stored META replaced by ValidCase::metaText, a valid JSON text that is not in the
// writer's canonical form (spec/format.md section 9 edge cases).
enum class Post { kNone, kUnknownOptional, kUnknownCopySafe, kRoCompat, kMetaText };

struct ValidCase {
  std::string name;
  std::string description;
  FieldDesc field;
  WriteOptions options;
  bool metadata = false;
  Post post = Post::kNone;
  std::string metaText{};  // kMetaText only
  // Format 1.3: a REFN section (spec/format.md section 14) with this margin, the generator's own
  // unsure bits (refinementFor) and the octahedron of the scene's inner sphere, subdivided
  // `meshLevel` times. Written with WriteOptions::codec.
  bool refined = false;
  float margin = 0;
  uint32_t meshLevel = 0;
};

struct BuiltValid {
  ValidCase c;
  Content content;
  LayoutDesc layout;
  std::string metadata;  // canonical text; for Post::kMetaText the stored text as it is
  Bytes bytes;
  bool zstd = false;
  Refinement refinement;  // the source of REFN (empty unless c.refined)
};

// Every valid vector, in the order they are written.
std::vector<ValidCase> validCases();
// Writes the vector with libvff's writer, then applies its Post step.
BuiltValid buildValid(const ValidCase& c);
// Reads a valid vector back with libvff and compares it with the source data (fail() on a difference).
void checkValid(const BuiltValid& v);
// The expected.json of a valid vector (gen_expected_json.cpp).
std::string expectedJson(const BuiltValid& v);

}  // namespace vff::gen
