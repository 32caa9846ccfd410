// The glTF extensions vff-bake reads (KHR_mesh_quantization, KHR_draco_mesh_compression,
// EXT_meshopt_compression), on files made from a procedural mesh by gltf_writer (quantized by
// hand, compressed with the libraries' encoders): the importer returns the vertices of the
// uncompressed file (quantized: within half a quantization step), and the baked fields are equal.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <tuple>

#include "gltf_writer.h"
#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/bake/sphere.h"

namespace vff::bake {
namespace {

namespace fs = std::filesystem;
using namespace gltftest;

// A small torus knot with unit vertex normals.
Mesh knot() {
  Mesh m = makeTorusKnot(2, 3, 0.15f, 48, 8);
  if (m.normals.size() != m.positions.size()) {
    m.normals.assign(m.positions.size(), 0.0f);
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      const float* a = &m.positions[3 * m.indices[t]];
      const float* b = &m.positions[3 * m.indices[t + 1]];
      const float* c = &m.positions[3 * m.indices[t + 2]];
      const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      for (size_t k = 0; k < 3; ++k)
        for (size_t d = 0; d < 3; ++d) m.normals[3 * m.indices[t + k] + d] += n[d];
    }
  }
  for (size_t i = 0; i < m.normals.size(); i += 3) {
    const float l = std::sqrt(m.normals[i] * m.normals[i] + m.normals[i + 1] * m.normals[i + 1] +
                              m.normals[i + 2] * m.normals[i + 2]);
    for (size_t d = 0; d < 3; ++d) m.normals[i + d] = l > 0 ? m.normals[i + d] / l : 1.0f;
  }
  return m;
}

class GltfExtensions : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_gltfext_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Saves doc and loads it back through loadMesh.
  Mesh roundTrip(const GltfDoc& doc, const std::string& name, bool glb) {
    const std::string p = (dir_ / name).string();
    EXPECT_TRUE(save(doc, p, glb)) << p;
    Result<Mesh> m = loadMesh(p);
    EXPECT_TRUE(m.ok()) << (m.ok() ? std::string() : m.error().toString());
    return m.ok() ? std::move(*m) : Mesh{};
  }
  fs::path dir_;
};

// Largest difference between the vertex positions of a and b (same order), and between their
// normal directions.
double maxPositionError(const Mesh& a, const Mesh& b) {
  double e = 0;
  for (size_t i = 0; i < a.positions.size(); ++i) e = std::max(e, std::fabs(double(a.positions[i]) - b.positions[i]));
  return e;
}
double maxNormalError(const Mesh& a, const Mesh& b) {
  double e = 0;
  for (size_t i = 0; i < a.normals.size(); i += 3) {
    double l = 0;
    for (size_t d = 0; d < 3; ++d) l += double(b.normals[i + d]) * b.normals[i + d];
    l = std::sqrt(l);
    for (size_t d = 0; d < 3; ++d) e = std::max(e, std::fabs(double(a.normals[i + d]) - b.normals[i + d] / l));
  }
  return e;
}

// The triangles of m as position triples, each rotated to start at its smallest vertex (winding
// kept), sorted: equal for meshes with the same triangles in any vertex and triangle order.
std::vector<std::array<float, 9>> triangleSet(const Mesh& m) {
  std::vector<std::array<float, 9>> out;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    std::array<std::array<float, 3>, 3> v;
    for (size_t k = 0; k < 3; ++k)
      for (size_t d = 0; d < 3; ++d) v[k][d] = m.positions[3 * m.indices[t + k] + d];
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    std::array<float, 9> flat;
    for (size_t k = 0; k < 9; ++k) flat[k] = v[k / 3][k % 3];
    out.push_back(flat);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The distance maps of a small bake of m inside the given sphere (the plain mesh's, so that only the
// triangles can make a difference).
std::vector<uint8_t> bakeDistances(const Mesh& m, const Sphere& sphere) {
  BakeOptions o;
  o.positionParam = 3;
  o.mapResolution = 16;
  o.sphere = sphere;
  Result<Scene> scene = Scene::create(m, 1);
  EXPECT_TRUE(scene.ok()) << scene.error().toString();
  if (!scene.ok()) return {};
  Result<BakedField> baked = bakeField(*scene, o);
  EXPECT_TRUE(baked.ok()) << baked.error().toString();
  return baked.ok() ? baked->distance : std::vector<uint8_t>{};
}

class GltfQuantized : public GltfExtensions, public ::testing::WithParamInterface<std::tuple<int, bool>> {};

// Every integer position type, normalized or not, with BYTE or SHORT normals: the importer's
// vertices are the mesh's within the quantization error, through the node's dequantizing transform.
TEST_P(GltfQuantized, VerticesWithinTheQuantizationError) {
  const Mesh m = knot();
  const auto [type, normalized] = GetParam();
  const int normalType = type == kByte || type == kUByte ? kByte : kShort;
  const Quantization q{type, normalized, normalType};
  const Mesh got = roundTrip(makeGltf(m, q), "q.glb", true);
  ASSERT_EQ(got.positions.size(), m.positions.size());
  EXPECT_EQ(got.indices, m.indices);
  const double bound = quantizationError(m, q);
  EXPECT_GT(maxPositionError(m, got), bound / 100) << "not quantized at all?";
  EXPECT_LE(maxPositionError(m, got), bound * 1.001 + 1e-6);
  ASSERT_EQ(got.normals.size(), m.normals.size());
  EXPECT_LE(maxNormalError(m, got), normalType == kByte ? 0.02 : 2e-4);
}

std::string quantizedName(const ::testing::TestParamInfo<std::tuple<int, bool>>& p) {
  const int t = std::get<0>(p.param);
  const std::string base = t == kByte ? "Byte" : t == kUByte ? "UnsignedByte" : t == kShort ? "Short" : "UnsignedShort";
  return base + (std::get<1>(p.param) ? "Normalized" : "");
}
INSTANTIATE_TEST_SUITE_P(Types, GltfQuantized,
                         ::testing::Combine(::testing::Values(kByte, kUByte, kShort, kUShort), ::testing::Bool()),
                         quantizedName);

// The plain writer's file loads as the mesh itself, .gltf (external .bin) and .glb alike.
TEST_F(GltfExtensions, PlainFilesLoadExactly) {
  const Mesh m = knot();
  for (bool glb : {false, true}) {
    const Mesh got = roundTrip(makeGltf(m, {}), glb ? "p.glb" : "p.gltf", glb);
    EXPECT_EQ(got.positions, m.positions);
    EXPECT_EQ(got.normals, m.normals);
    EXPECT_EQ(got.indices, m.indices);
  }
}

// An unsigned integer normal is not one the extension allows: unsupported, naming the attribute.
TEST_F(GltfExtensions, DisallowedNormalTypeIsUnsupported) {
  GltfDoc doc = makeGltf(knot(), {kUShort, true, kShort});
  doc.json["accessors"][1]["componentType"] = kUShort;
  const std::string p = (dir_ / "bad.gltf").string();
  ASSERT_TRUE(save(doc, p, false));
  Result<Mesh> got = loadMesh(p);
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.error().code, Code::kMeshUnsupported);
  EXPECT_NE(got.error().message.find("NORMAL: component type 5123"), std::string::npos) << got.error().message;
}

// Sequential Draco keeps the vertex and triangle order: the importer returns the mesh itself.
TEST_F(GltfExtensions, DracoSequentialLoadsTheMeshExactly) {
  const Mesh m = knot();
  const Mesh got = roundTrip(makeDracoGltf(m, true), "d.gltf", false);
  EXPECT_EQ(got.positions, m.positions);
  EXPECT_EQ(got.normals, m.normals);
  EXPECT_EQ(got.indices, m.indices);
}

// Edgebreaker reorders vertices and triangles: the same triangles, and the same field as the plain
// file's, loaded in the same process (Draco's copy of tinygltf must not replace the importer's).
TEST_F(GltfExtensions, DracoEdgebreakerBakesTheSameField) {
  const Mesh m = knot();
  const Mesh plain = roundTrip(makeGltf(m, {}), "p.gltf", false);
  const Mesh draco = roundTrip(makeDracoGltf(m, false), "d.glb", true);
  ASSERT_EQ(draco.triangleCount(), m.triangleCount());
  EXPECT_NE(draco.positions, plain.positions) << "edgebreaker kept the order: this test checks nothing";
  EXPECT_EQ(triangleSet(draco), triangleSet(m));
  const Sphere s = minimalEnclosingSphere(plain.positions);
  const std::vector<uint8_t> a = bakeDistances(plain, s), b = bakeDistances(draco, s);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, b);
}

// Draco data that does not decode is invalid input naming the primitive.
TEST_F(GltfExtensions, CorruptDracoDataIsInvalidInput) {
  GltfDoc doc = makeDracoGltf(knot(), false);
  for (size_t i = 16; i < doc.bin.size(); ++i) doc.bin[i] = uint8_t(i * 37);
  const std::string p = (dir_ / "bad.glb").string();
  ASSERT_TRUE(save(doc, p, true));
  Result<Mesh> got = loadMesh(p);
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.error().code, Code::kMeshParse);
  EXPECT_NE(got.error().message.find("bad.glb: mesh '' primitive 0: Draco data cannot be decoded"), std::string::npos)
      << got.error().message;
}

// meshopt's vertex codec is lossless and its index codec keeps the triangles (rotated at most): the
// same field as the plain file's, read past a fallback buffer without a uri.
TEST_F(GltfExtensions, MeshoptBakesTheSameField) {
  const Mesh m = knot();
  const Mesh plain = roundTrip(makeGltf(m, {}), "p.glb", true);
  const Mesh packed = roundTrip(makeMeshoptGltf(m, {}), "m.glb", true);
  EXPECT_EQ(packed.positions, m.positions);
  EXPECT_EQ(packed.normals, m.normals);
  EXPECT_EQ(triangleSet(packed), triangleSet(m));
  const Sphere s = minimalEnclosingSphere(plain.positions);
  const std::vector<uint8_t> a = bakeDistances(plain, s), b = bakeDistances(packed, s);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, b);
}

// The INDICES mode gives the index sequence back exactly; a .gltf with an external buffer.
TEST_F(GltfExtensions, MeshoptIndexSequenceLoadsTheMeshExactly) {
  const Mesh m = knot();
  Meshopt o;
  o.indexSequence = true;
  const Mesh got = roundTrip(makeMeshoptGltf(m, o), "m.gltf", false);
  EXPECT_EQ(got.positions, m.positions);
  EXPECT_EQ(got.indices, m.indices);
}

// The filters: EXPONENTIAL positions (16-bit mantissas) and OCTAHEDRAL (8-bit) or QUATERNION
// (16-bit) normals decode to the mesh's values within what those bits keep. A quaternion and its
// negation are the same rotation: the normals compare up to sign.
TEST_F(GltfExtensions, MeshoptFiltersDecode) {
  const Mesh m = knot();
  for (const char* normalFilter : {"OCTAHEDRAL", "QUATERNION"}) {
    SCOPED_TRACE(normalFilter);
    Meshopt o;
    o.exponentialPositions = true;
    o.normalFilter = normalFilter;
    o.indexSequence = true;
    const Mesh got = roundTrip(makeMeshoptGltf(m, o), "f.glb", true);
    ASSERT_EQ(got.positions.size(), m.positions.size());
    ASSERT_EQ(got.normals.size(), m.normals.size());
    EXPECT_EQ(got.indices, m.indices);
    const double posError = maxPositionError(m, got);
    EXPECT_GT(posError, 0.0);
    EXPECT_LT(posError, 1.1 * std::ldexp(1.0, -14));
    Mesh flipped = got;
    for (float& x : flipped.normals) x = -x;
    double nrmError = 0;
    for (size_t i = 0; i < m.normals.size(); i += 3) {
      double e[2] = {0, 0};
      for (size_t d = 0; d < 3; ++d) {
        e[0] = std::max(e[0], std::fabs(double(m.normals[i + d]) - got.normals[i + d]));
        e[1] = std::max(e[1], std::fabs(double(m.normals[i + d]) - flipped.normals[i + d]));
      }
      nrmError = std::max(nrmError, std::string(normalFilter) == "OCTAHEDRAL" ? e[0] : std::min(e[0], e[1]));
    }
    EXPECT_LT(nrmError, std::string(normalFilter) == "OCTAHEDRAL" ? 0.03 : 2e-4);
  }
}

// Compressed bytes that do not decode: invalid input naming the buffer view.
TEST_F(GltfExtensions, CorruptMeshoptDataIsInvalidInput) {
  GltfDoc doc = makeMeshoptGltf(knot(), {});
  for (size_t i = 0; i < doc.bin.size(); ++i) doc.bin[i] = uint8_t(0xff - i % 7);
  const std::string p = (dir_ / "bad.glb").string();
  ASSERT_TRUE(save(doc, p, true));
  Result<Mesh> got = loadMesh(p);
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.error().code, Code::kMeshParse);
  EXPECT_NE(got.error().message.find("bad.glb: bufferView 0: meshopt data cannot be decoded"), std::string::npos)
      << got.error().message;
}

// A count the compressed bytes cannot hold is refused before the memory it claims is allocated.
TEST_F(GltfExtensions, MeshoptCountBeyondTheDataIsRefused) {
  GltfDoc doc = makeMeshoptGltf(knot(), {});
  doc.json["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = 2000000000;
  const std::string p = (dir_ / "huge.gltf").string();
  ASSERT_TRUE(save(doc, p, false));
  Result<Mesh> got = loadMesh(p);
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.error().code, Code::kMeshParse);
  EXPECT_NE(got.error().message.find("huge.gltf: bufferView 0: 2000000000 elements cannot come from"),
            std::string::npos)
      << got.error().message;
}

}  // namespace
}  // namespace vff::bake
