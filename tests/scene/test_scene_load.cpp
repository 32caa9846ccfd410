// loadScene (vff/scene_description.h): a scene description's fields opened and its instances placed
// answer as the loop over Instances of the same files and transforms; errors name the field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff {
namespace {

namespace fs = std::filesystem;

class SceneLoad : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_scene_load_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_ / "fields");
    // Two synthetic fields of different shapes.
    const FieldDesc a = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 2, 8);
    const FieldDesc b = test::smallField(DistanceEncoding::kUnorm16Diameter, NormalEncoding::kNone, 1, 16);
    for (const auto& [name, f] : {std::pair{"a.vff", a}, std::pair{"b.vff", b}}) {
      auto w = Writer::create((dir_ / "fields" / name).string(), f);
      ASSERT_TRUE(w) << w.error().toString();
      ASSERT_TRUE(w->writeMaps(Plane::kDistance, test::syntheticDistance(f)));
      ASSERT_TRUE(w->finish());
    }
    desc_.fields = {{"fields/a.vff", "a", ""}, {"fields/b.vff", "b", ""}};
    const float h = 0.70710678f;
    const std::array<float, 4> rotations[] = {{0, 0, 0, 1}, {0, h, 0, h}, {h, 0, 0, h}};
    for (uint32_t i = 0; i < 3; ++i) {
      SceneInstance s;
      s.field = i == 1 ? 1 : 0;
      s.translation = {float(i) * 2.5f, 0.5f * float(i), -1.0f};
      s.rotation = rotations[i];
      s.scale = i == 2 ? 0.5f : 1.0f;
      desc_.instances.push_back(s);
    }
    path_ = (dir_ / "s.vffscene.json").string();
    ASSERT_TRUE(writeSceneDescription(path_, desc_));
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string path_;
  SceneDescription desc_;
};

TEST_F(SceneLoad, AnswersAsTheLoopOverItsInstances) {
  auto loaded = loadScene(path_);
  ASSERT_TRUE(loaded) << loaded.error().toString();
  const Scene& scene = (*loaded)->scene;
  ASSERT_EQ(scene.size(), 3u);
  ASSERT_TRUE(scene.committed());
  // The same files opened apart, placed by the same transforms.
  std::vector<File> files;
  std::vector<FieldQuery> queries;
  files.reserve(2);
  for (const char* n : {"a.vff", "b.vff"}) files.push_back(File::open((dir_ / "fields" / n).string()).value());
  for (const File& f : files) queries.push_back(FieldQuery::fromFile(f).value());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int hits = 0;
  for (int r = 0; r < 2000; ++r) {
    Ray ray;
    ray.origin = {u(rng) * 8.0f, u(rng) * 6.0f, 6.0f};
    ray.direction = {u(rng) * 0.6f + 0.3f, u(rng) * 0.3f, -1.0f};
    SceneHit best;
    best.t = ray.tmax;
    for (uint32_t i = 0; i < 3; ++i) {
      const Instance inst{&queries[desc_.instances[i].field], desc_.instances[i].rigidTransform()};
      const QueryHit h = inst.intersect(ray);
      if (h.hit && h.t < best.t) {
        static_cast<QueryHit&>(best) = h;
        best.instance = i;
      }
    }
    auto got = scene.intersect(ray);
    ASSERT_TRUE(got);
    ASSERT_EQ(got->hit, best.hit) << r;
    if (!best.hit) continue;
    ++hits;
    EXPECT_EQ(got->instance, best.instance) << r;
    EXPECT_EQ(got->t, best.t) << r;
  }
  EXPECT_GT(hits, 50);  // the rays do reach the objects
}

TEST_F(SceneLoad, AMissingFieldIsNamed) {
  fs::remove(dir_ / "fields" / "b.vff");
  auto loaded = loadScene(path_);
  ASSERT_FALSE(loaded);
  EXPECT_EQ(loaded.error().code, Code::kIoOpen);
  EXPECT_NE(loaded.error().message.find("fields[1]"), std::string::npos) << loaded.error().message;
  EXPECT_NE(loaded.error().message.find("s.vffscene.json"), std::string::npos) << loaded.error().message;
}

TEST_F(SceneLoad, ACorruptFieldIsNamed) {
  const fs::path a = dir_ / "fields" / "a.vff";
  fs::resize_file(a, fs::file_size(a) - 1);
  auto loaded = loadScene(path_);
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().message.find("fields[0]"), std::string::npos) << loaded.error().message;
}

}  // namespace
}  // namespace vff
