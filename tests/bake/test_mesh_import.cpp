#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "vff/bake/procedural.h"

namespace vff::bake {
namespace {

namespace fs = std::filesystem;

class MeshImport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_mesh_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  fs::path dir_;
};

// A glTF with one triangle (positions + uint16 indices) under a translated, scaled node.
std::string triangleGltf(const std::string& primitiveExtra = "", const std::string& topExtra = "",
                         int accessorCount = 3) {
  std::vector<uint8_t> buf(36 + 8, 0);
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(buf.data(), pos, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(buf.data() + 36, idx, 6);
  return R"({"asset":{"version":"2.0"},)" + topExtra + R"("scene":0,"scenes":[{"nodes":[0]}],
  "nodes":[{"mesh":0,"translation":[10,0,0],"scale":[2,2,2]}],
  "meshes":[{"name":"tri","primitives":[{"attributes":{"POSITION":0},"indices":1)" + primitiveExtra + R"(}]}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":)" + std::to_string(accessorCount) +
         R"(,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
               {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
  "buffers":[{"byteLength":44,"uri":"data:application/octet-stream;base64,)" + base64(buf) + R"("}]})";
}

TEST_F(MeshImport, ObjRoundTripThroughOpenMesh) {
  Mesh knot = makeTorusKnot(2, 3, 0.15f, 64, 8);
  const std::string p = (dir_ / "knot.obj").string();
  ASSERT_TRUE(writeObj(knot, p).ok());
  MeshInfo info;
  auto m = loadMesh(p, &info);
  ASSERT_TRUE(m.ok()) << m.error().toString();
  EXPECT_EQ(info.format, "obj");
  EXPECT_EQ(m->triangleCount(), knot.triangleCount());
  EXPECT_FALSE(m->normals.empty());
}

TEST_F(MeshImport, ObjQuadsAreTriangulated) {
  auto m = loadMesh(write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  ASSERT_TRUE(m.ok()) << m.error().toString();
  EXPECT_EQ(m->triangleCount(), 2u);
}

TEST_F(MeshImport, OffAndStlAndPly) {
  auto off = loadMesh(write("t.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  ASSERT_TRUE(off.ok()) << off.error().toString();
  EXPECT_EQ(off->triangleCount(), 1u);
  auto stl = loadMesh(write("t.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                     "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n"));
  ASSERT_TRUE(stl.ok()) << stl.error().toString();
  EXPECT_EQ(stl->triangleCount(), 1u);
  auto ply = loadMesh(write("t.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                     "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                     "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  ASSERT_TRUE(ply.ok()) << ply.error().toString();
  EXPECT_EQ(ply->triangleCount(), 1u);
}

TEST_F(MeshImport, GltfAppliesNodeTransforms) {
  auto m = loadMesh(write("tri.gltf", triangleGltf()));
  ASSERT_TRUE(m.ok()) << m.error().toString();
  ASSERT_EQ(m->triangleCount(), 1u);
  EXPECT_FLOAT_EQ(m->positions[3], 12.0f);  // vertex (1,0,0) scaled by 2, moved by 10
  EXPECT_FLOAT_EQ(m->positions[7], 2.0f);
}

TEST_F(MeshImport, GltfPointsAreAnError) {
  auto m = loadMesh(write("p.gltf", triangleGltf(R"(,"mode":0)")));
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.error().code, Code::kMeshUnsupported);
  EXPECT_NE(m.error().message.find("p.gltf"), std::string::npos);
}

TEST_F(MeshImport, GltfRequiredUnknownExtensionIsUnsupported) {
  auto m = loadMesh(write("d.gltf", triangleGltf("", R"("extensionsUsed":["EXT_unheard_of"],"extensionsRequired":["KHR_draco_mesh_compression","EXT_unheard_of"],)")));
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.error().code, Code::kMeshUnsupported) << m.error().toString();
  EXPECT_NE(m.error().message.find("d.gltf: requires the glTF extension EXT_unheard_of"), std::string::npos)
      << m.error().message;
}

TEST_F(MeshImport, GltfAccessorOutOfBoundsIsAnError) {
  auto m = loadMesh(write("oob.gltf", triangleGltf("", "", 1000)));
  ASSERT_FALSE(m.ok());
  EXPECT_TRUE(m.error().code == Code::kMeshIndex || m.error().code == Code::kMeshParse) << m.error().toString();
}

TEST_F(MeshImport, BadInputsGetClearErrors) {
  EXPECT_EQ(loadMesh((dir_ / "missing.obj").string()).error().code, Code::kIoOpen);
  EXPECT_EQ(loadMesh(write("x.xyz", "1 2 3")).error().code, Code::kMeshFormat);
  EXPECT_EQ(loadMesh(write("empty.obj", "")).error().code, Code::kMeshEmpty);
  EXPECT_EQ(loadMesh(write("novert.obj", "# nothing\n")).error().code, Code::kMeshEmpty);
  auto nanObj = loadMesh(write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"));
  ASSERT_FALSE(nanObj.ok());  // OpenMesh drops the vertex it cannot parse: no triangle is left
  EXPECT_NE(nanObj.error().message.find("nan.obj"), std::string::npos);
  auto degen = loadMesh(write("degen.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"));
  ASSERT_FALSE(degen.ok());
  EXPECT_EQ(degen.error().code, Code::kMeshDegenerate);
  EXPECT_NE(degen.error().message.find("degen.obj"), std::string::npos);
  EXPECT_FALSE(loadMesh(write("garbage.glb", std::string("\x01\x02\x03garbage", 10))).ok());
}

TEST_F(MeshImport, HostileObjAndPlyGetClearErrors) {
  // Inputs that crash, hang or exhaust memory in OpenMesh 9 itself (found by tests/fuzz) are refused
  // before it sees them.
  struct Case {
    const char* name;
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "line 4: face index 9 refers to a vertex"},
      {"neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "face index -4"},
      {"badnormal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", "refers to a normal"},
      {"token.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 elemen3//1 3\n", "is not v, v/vt"},
      {"short.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least three corners"},
      {"noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "no end_header"},
      {"keyword.ply", "ply\nformat ascii 1.0\nproper3 0 2 3\nend_header\n", "line 3: unknown PLY header keyword"},
      {"version.ply", "ply\nformat ascii ~1.0\nend_header\n", "PLY format line"},
      {"count.ply", "ply\nformat ascii 1.0\nelement vertex y\nend_header\n", "PLY element line"},
      {"list.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
       "5555555555553 0 1 2\n",
       "a list length is not an integer"},
      {"short.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n\x01\x02\x03",
       "the file ends inside the body"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "face index '7' is not a vertex"},
      {"corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n99999999 0 1 2\n", "corner count"},
      {"counts.off", "OFF\n-3 1 0\n", "counts line"},
      {"sameline.off", "OFF\t0 0\n", "own line"},
  };
  for (const Case& c : cases) {
    auto m = loadMesh(write(c.name, c.text));
    ASSERT_FALSE(m.ok()) << c.name;
    EXPECT_EQ(m.error().code, Code::kMeshParse) << c.name << ": " << m.error().message;
    EXPECT_NE(m.error().message.find(c.name), std::string::npos) << m.error().message;
    EXPECT_NE(m.error().message.find(c.says), std::string::npos) << m.error().message;
  }
  // Valid corner forms still load, negative (relative) indices included.
  auto ok = loadMesh(write("forms.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 -1/1\n"));
  ASSERT_TRUE(ok.ok()) << ok.error().toString();
  EXPECT_EQ(ok->triangleCount(), 1u);
}

TEST_F(MeshImport, NonFiniteVertexIsNamed) {
  std::string g = triangleGltf();
  auto m = loadMesh(write("ok.gltf", g));
  ASSERT_TRUE(m.ok());
  Mesh bad = *m;
  bad.positions[4] = std::nanf("");
  Status s = checkMesh(&bad, "bad.gltf");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, Code::kMeshNonFinite);
  EXPECT_NE(s.error().message.find("vertex 1"), std::string::npos) << s.error().message;
  bad = *m;
  bad.positions[0] = INFINITY;
  EXPECT_EQ(checkMesh(&bad, "inf").error().code, Code::kMeshNonFinite);
}

TEST_F(MeshImport, DegenerateTrianglesAreDroppedAndCounted) {
  auto m = loadMesh(write("mixed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n"));
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->triangleCount(), 1u);
  EXPECT_EQ(m->droppedDegenerate, 1u);
}

}  // namespace
}  // namespace vff::bake
