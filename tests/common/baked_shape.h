// baked_shape.h - a procedural shape (vff/bake/procedural.h) baked in memory, with its query: the
// fields of the query, scene and Embree tests. For test programs that link vff_bake.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/vff.h"

namespace vff::test {

// The mesh, the baked maps and the query that borrows them, kept alive together.
struct BakedShape {
  bake::Mesh mesh;
  bake::BakedField field;
  FieldQuery query;
};

// bake::makeShape(shape) baked with positionParam n and mapResolution m; a failure fails the test.
inline std::unique_ptr<BakedShape> bakeShape(const std::string& shape, uint32_t n, uint32_t m, bool normals = false,
                                             DistanceEncoding e = DistanceEncoding::kUnorm8Diameter) {
  auto b = std::make_unique<BakedShape>();
  b->mesh = bake::makeShape(shape);
  auto scene = bake::Scene::create(b->mesh);
  EXPECT_TRUE(scene.ok());
  bake::BakeOptions o;
  o.positionParam = n;
  o.mapResolution = m;
  o.encoding = e;
  o.normals = normals;
  auto baked = bake::bakeField(*scene, o);
  EXPECT_TRUE(baked.ok()) << baked.error().toString();
  b->field = std::move(*baked);
  auto q = FieldQuery::fromMaps(b->field.field, b->field.distance, b->field.normals);
  EXPECT_TRUE(q.ok()) << q.error().toString();
  b->query = std::move(*q);
  return b;
}

// The scene tests' two fields, baked once per program at n 8, m 16: the torus knot with normals, and
// the bowl, with normals when `bowlNormals`.
inline const std::vector<std::unique_ptr<BakedShape>>& knotAndBowl(bool bowlNormals) {
  const auto make = [](bool normals) {
    auto* v = new std::vector<std::unique_ptr<BakedShape>>;
    v->push_back(bakeShape("torus-knot", 8, 16, true));
    v->push_back(bakeShape("bowl", 8, 16, normals));
    return v;
  };
  if (bowlNormals) {
    static const auto* withNormals = make(true);
    return *withNormals;
  }
  static const auto* without = make(false);
  return *without;
}

}  // namespace vff::test
