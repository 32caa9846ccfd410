// glTF scenes split into objects (vff/bake/gltf.h): each object's geometry under each of its
// placements is exactly the part of the whole scene (loadMesh) that its node holds.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "vff/bake/gltf.h"
#include "vff/bake/procedural.h"
#include "vff/scene_description.h"

namespace vff::bake {
namespace {

namespace fs = std::filesystem;

class GltfScene : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_gltf_scene_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "s.gltf").string();
    ASSERT_TRUE(writeSampleGltfScene(path_));
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string path_;
};

// The triangles of every object placed by its placements, in the scene's node order, against the
// whole scene's: the same vertices within float rounding.
void expectPlacedObjectsAreTheScene(const std::vector<GltfObject>& objects, const Mesh& whole) {
  struct Placed {
    const GltfObject* object;
    RigidTransform transform;
  };
  std::vector<std::pair<int, Placed>> byNode;
  for (const GltfObject& o : objects)
    for (const GltfPlacement& p : o.placements) {
      SceneInstance i;
      i.translation = p.translation;
      i.rotation = p.rotation;
      i.scale = p.scale;
      byNode.push_back({p.node, {&o, i.rigidTransform()}});
    }
  std::sort(byNode.begin(), byNode.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  size_t t = 0;
  for (const auto& [node, placed] : byNode) {
    const Mesh& g = placed.object->geometry;
    for (size_t k = 0; k < g.indices.size(); ++k, ++t) {
      ASSERT_LT(t, whole.indices.size());
      const uint32_t v = g.indices[k], w = whole.indices[t];
      const Vec3 p = placed.transform.toWorldPoint({g.positions[3 * v], g.positions[3 * v + 1], g.positions[3 * v + 2]});
      EXPECT_NEAR(p.x, whole.positions[3 * w], 2e-5f) << "node " << node << " index " << k;
      EXPECT_NEAR(p.y, whole.positions[3 * w + 1], 2e-5f) << "node " << node << " index " << k;
      EXPECT_NEAR(p.z, whole.positions[3 * w + 2], 2e-5f) << "node " << node << " index " << k;
    }
  }
  EXPECT_EQ(t, whole.indices.size());
}

TEST_F(GltfScene, SplitByMeshSharesAMeshBetweenSimilarNodes) {
  MeshInfo info;
  auto objects = loadGltfObjects(path_, {.split = GltfSplit::kMesh}, &info);
  ASSERT_TRUE(objects) << objects.error().toString();
  ASSERT_EQ(objects->size(), 2u);
  EXPECT_EQ((*objects)[0].name, "box");
  EXPECT_EQ((*objects)[0].node, -1);  // in the mesh's own frame
  ASSERT_EQ((*objects)[0].placements.size(), 2u);
  EXPECT_FLOAT_EQ((*objects)[0].placements[0].scale, 2.0f);
  EXPECT_EQ((*objects)[1].node, 3);  // the non-uniform scale is baked in
  EXPECT_EQ((*objects)[1].placements[0].scale, 1.0f);
  EXPECT_EQ(info.gltfScenes, (std::vector<std::string>{"main", "second"}));
  EXPECT_EQ(info.gltfScene, 0);
  auto whole = loadMesh(path_);
  ASSERT_TRUE(whole);
  expectPlacedObjectsAreTheScene(*objects, *whole);
}

TEST_F(GltfScene, SplitByNodeGivesEachNodeItsObject) {
  auto objects = loadGltfObjects(path_, {.split = GltfSplit::kNode});
  ASSERT_TRUE(objects) << objects.error().toString();
  ASSERT_EQ(objects->size(), 3u);
  for (const GltfObject& o : *objects) EXPECT_EQ(o.placements.size(), 1u);
  EXPECT_EQ((*objects)[1].name, "boxB");
  auto whole = loadMesh(path_);
  ASSERT_TRUE(whole);
  expectPlacedObjectsAreTheScene(*objects, *whole);
}

TEST_F(GltfScene, SceneOptionPicksTheScene) {
  MeshInfo info;
  auto second = loadMesh(path_, &info, {.gltfScene = 1});
  ASSERT_TRUE(second) << second.error().toString();
  EXPECT_EQ(info.gltfScene, 1);
  Mesh bowl = makeBowl(0.1f, 8, 16);
  ASSERT_TRUE(checkMesh(&bowl, "bowl"));
  ASSERT_EQ(second->triangleCount(), bowl.triangleCount());
  EXPECT_FLOAT_EQ(second->positions[0], bowl.positions[0] + 5.0f);  // the node's translation
  auto objects = loadGltfObjects(path_, {.split = GltfSplit::kMesh, .scene = 1});
  ASSERT_TRUE(objects);
  ASSERT_EQ(objects->size(), 1u);
  EXPECT_EQ(geometryHash((*objects)[0].geometry), geometryHash(bowl));
  auto none = loadMesh(path_, nullptr, {.gltfScene = 2});
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().code, Code::kInvalidArgument);
  EXPECT_NE(none.error().message.find("there is no scene 2"), std::string::npos) << none.error().message;
}

TEST(GeometryHash, DependsOnTheTrianglesOnly) {
  Mesh a = makeTorusKnot(2, 3, 0.15f, 32, 6);
  // The same triangles with unshared vertices, in reverse order, each rotated to start elsewhere.
  Mesh b;
  for (size_t t = a.triangleCount(); t-- > 0;)
    for (size_t k : {1, 2, 0}) {
      const uint32_t v = a.indices[3 * t + k];
      b.positions.insert(b.positions.end(), {a.positions[3 * v], a.positions[3 * v + 1], a.positions[3 * v + 2]});
      b.indices.push_back(uint32_t(b.indices.size()));
    }
  EXPECT_EQ(geometryHash(a), geometryHash(b));
  EXPECT_NE(meshHash(a), meshHash(b));
  // Another winding is another surface orientation, and a moved vertex other geometry.
  Mesh c = b;
  std::swap(c.indices[0], c.indices[1]);
  EXPECT_NE(geometryHash(c), geometryHash(b));
  Mesh d = b;
  d.positions[4] = std::nextafter(d.positions[4], 10.0f);
  EXPECT_NE(geometryHash(d), geometryHash(b));
}

}  // namespace
}  // namespace vff::bake
