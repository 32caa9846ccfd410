// baked_fields.h - the baked test fields of the GPU suites: a torus knot in every position scheme,
// direction scheme, encoding and layout target, written to memory with small slices (several
// slices; a gutter of 1 except for bit1) so that fetches cross slices and skip gutters.
#pragma once

#include <string>

#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/vff.h"

namespace vff::gputest {

struct FieldCase {
  PositionScheme positions;
  DirectionScheme directions;
  DistanceEncoding encoding;
  LayoutTarget target = LayoutTarget::kTexture2DArray;
};

inline std::string caseName(const FieldCase& c) {
  std::string s = c.positions == PositionScheme::kOctaHemi2            ? "OctaHemi2"
                  : c.positions == PositionScheme::kEqualAreaOctaGrid ? "EaOctaGrid"
                                                                       : "Fibonacci";
  s += c.directions == DirectionScheme::kConcentricEqualArea ? "_Concentric" : "_HemiOct";
  switch (c.encoding) {
    case DistanceEncoding::kUnorm8Diameter: s += "_Unorm8Diameter"; break;
    case DistanceEncoding::kUnorm8Chord: s += "_Unorm8Chord"; break;
    case DistanceEncoding::kUnorm16Diameter: s += "_Unorm16Diameter"; break;
    case DistanceEncoding::kBc4Diameter: s += "_Bc4Diameter"; break;
    default: s += "_Bit1"; break;
  }
  if (c.target == LayoutTarget::kTexture3D) s += "_3D";
  return s;
}

// `shape`: one of bake::makeShape's (the scene tests use several).
inline Result<File> bakeFile(const FieldCase& c, bool normals, const std::string& shape = "torus-knot") {
  const bake::Mesh mesh = bake::makeShape(shape);
  auto scene = bake::Scene::create(mesh);
  if (!scene) return scene.error();
  bake::BakeOptions o;
  o.positionScheme = c.positions;
  o.positionParam = c.positions == PositionScheme::kOctaHemi2          ? 4u
                    : c.positions == PositionScheme::kEqualAreaOctaGrid ? 9u
                                                                        : 100u;
  o.directionScheme = c.directions;
  o.mapResolution = 32;
  o.encoding = c.encoding;
  o.normals = normals;
  auto baked = bake::bakeField(*scene, o);
  if (!baked) return baked.error();
  WriteOptions w;
  w.layout.target = c.target;
  w.layout.maxTextureSize = 256;
  // bit1 and bc4-diameter allow no gutter (rule 7002).
  w.layout.gutter = c.encoding == DistanceEncoding::kBit1 || c.encoding == DistanceEncoding::kBc4Diameter ? 0 : 1;
  auto bytes = writeMemory(baked->field, baked->distance, baked->normals, w);
  if (!bytes) return bytes.error();
  return File::openBuffer(std::move(*bytes));
}

}  // namespace vff::gputest
