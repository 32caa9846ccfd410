// Decoded distances of baked fields against exact Embree ray casts on the same sample directions:
// hits within one quantisation step, misses exact. The reference uses rtcIntersect1 on its own
// scene, not the baker's packet path.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/bake/embree_reference.h"
#include "vff/vff.h"

namespace vff::bake {
namespace {

using Reference = bake::EmbreeReference;

struct Stats {
  uint64_t hits = 0, misses = 0;
  double worstStepRatio = 0;
};

// Checks every texel of every map of `baked` against exact casts.
Stats checkAgainstReference(const Mesh& mesh, const BakedField& baked) {
  Reference ref(mesh);
  const FieldDesc& f = baked.field;
  auto ps = PositionSet::fromField(f);
  EXPECT_TRUE(ps.ok());
  const uint32_t m = f.mapResolution;
  const uint64_t mb = distanceMapBytes(f.distanceEncoding, m);
  const float R = f.sphere.radius;
  Stats st;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    const Vec3 u = ps->position(k);
    const Vec3 o{f.sphere.center[0] + R * u.x, f.sphere.center[1] + R * u.y, f.sphere.center[2] + R * u.z};
    const Frame fr = frameFromNormal({-u.x, -u.y, -u.z});
    auto map = std::span<const uint8_t>(baked.distance).subspan(k * mb, mb);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const Vec3 local = texelDirection(f.directionScheme, m, i, j);
        // As the baker does (and spec/geometry.md says): start 1e-4 R behind the entry point so a
        // surface touching it counts as a hit at distance 0.
        const Vec3 d = toWorld(fr, local);
        const float back = 1e-4f * R;
        float t = ref.cast({o.x - back * d.x, o.y - back * d.y, o.z - back * d.z}, d);
        if (t >= 0) t = std::max(0.0f, t - back);
        const Texel tx = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, map, m, i, j), R, local.z);
        if (t < 0) {
          ++st.misses;
          EXPECT_FALSE(tx.hit) << "map " << k << " texel " << i << "," << j << ": exact cast misses";
          continue;
        }
        ++st.hits;
        EXPECT_TRUE(tx.hit) << "map " << k << " texel " << i << "," << j << ": exact cast hits at " << t;
        if (f.distanceEncoding == DistanceEncoding::kBit1 || !tx.hit) continue;
        const float step = quantizationStep(f.distanceEncoding, R, local.z);
        const double ratio = std::fabs(double(tx.distance) - t) / step;
        st.worstStepRatio = std::max(st.worstStepRatio, ratio);
        EXPECT_LE(ratio, 1.0) << "map " << k << " texel " << i << "," << j << ": " << tx.distance << " vs " << t;
      }
  }
  return st;
}

BakeOptions smallOptions(DistanceEncoding e, uint32_t n = 3, uint32_t m = 16) {
  BakeOptions o;
  o.positionParam = n;  // octa-hemi2: 50 maps
  o.mapResolution = m;
  o.encoding = e;
  return o;
}

class BakeShapes : public ::testing::TestWithParam<std::string> {};

TEST_P(BakeShapes, DistancesMatchExactCasts) {
  Mesh mesh = makeShape(GetParam());
  ASSERT_GT(mesh.triangleCount(), 0u);
  ASSERT_TRUE(checkMesh(&mesh, GetParam()).ok());
  auto scene = Scene::create(mesh);
  ASSERT_TRUE(scene.ok());
  for (auto e : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm8Chord, DistanceEncoding::kUnorm16Diameter,
                 DistanceEncoding::kBit1}) {
    auto baked = bakeField(*scene, smallOptions(e));
    ASSERT_TRUE(baked.ok()) << baked.error().toString();
    Stats st = checkAgainstReference(mesh, *baked);
    EXPECT_GT(st.hits, 0u);
    if (GetParam() != "sphere") {
      EXPECT_GT(st.misses, 0u);  // (every inward ray hits the sphere)
    }
    std::printf("[ %s %s ] %llu hits, %llu misses, worst |decoded - exact| = %.3f steps\n", GetParam().c_str(),
                distanceEncodingName(e), (unsigned long long)st.hits, (unsigned long long)st.misses, st.worstStepRatio);
  }
}

INSTANTIATE_TEST_SUITE_P(Procedural, BakeShapes, ::testing::Values("sphere", "box", "torus-knot", "bowl", "rod"),
                         [](const auto& param_info) {
                           std::string s = param_info.param;
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

TEST(Bake, AnalyticSphere) {
  // A finely tessellated unit sphere: every ray from the bounding sphere (radius ~1) enters it, and
  // the hit distance is ~0 at the texel whose direction is the inward normal.
  Mesh mesh = makeSphere(1.0f, 96, 192);
  auto scene = Scene::create(mesh);
  BakeOptions o = smallOptions(DistanceEncoding::kUnorm16Diameter, 2, 8);
  auto baked = bakeField(*scene, o);
  ASSERT_TRUE(baked.ok());
  EXPECT_NEAR(baked->field.sphere.radius, 1.0f, 1e-3f);
  // Every ray starts on the sphere and points inward, so it hits almost immediately.
  for (uint32_t k = 0; k < baked->field.mapCount; ++k) {
    auto map = std::span<const uint8_t>(baked->distance).subspan(k * 128, 128);
    for (uint32_t t = 0; t < 64; ++t) {
      const Texel tx = decodeDistance(o.encoding, loadCode(o.encoding, map, 8, t % 8, t / 8), 1.0f, 1.0f);
      ASSERT_TRUE(tx.hit);
      EXPECT_LT(tx.distance, 0.01f);
    }
  }
}

TEST(Bake, NormalsPointOutwardOnTheSphere) {
  Mesh mesh = makeSphere(0.5f, 48, 96);
  BakeOptions o = smallOptions(DistanceEncoding::kUnorm8Diameter, 2, 8);
  o.normals = true;
  o.sphere = Sphere{{0, 0, 0}, 1.0f};  // user-given sphere larger than the mesh: some rays miss
  auto scene = Scene::create(mesh);
  auto baked = bakeField(*scene, o);
  ASSERT_TRUE(baked.ok());
  auto ps = PositionSet::fromField(baked->field);
  uint64_t hits = 0;
  for (uint32_t k = 0; k < baked->field.mapCount; ++k) {
    const Vec3 u = ps->position(k);
    const Frame fr = frameFromNormal({-u.x, -u.y, -u.z});
    for (uint32_t t = 0; t < 64; ++t) {
      const Vec3 local = texelDirection(baked->field.directionScheme, 8, t % 8, t / 8);
      const uint32_t code = baked->distance[k * 64 + t];
      const Texel tx = decodeDistance(o.encoding, code, 1.0f, local.z);
      const uint8_t* nb = &baked->normals[(uint64_t(k) * 64 + t) * 4];
      if (!tx.hit) {
        EXPECT_EQ(nb[0] | nb[1] | nb[2] | nb[3], 0);  // misses store zero normals
        continue;
      }
      ++hits;
      const Vec3 d = toWorld(fr, local);
      const Vec3 p{u.x + tx.distance * d.x, u.y + tx.distance * d.y, u.z + tx.distance * d.z};
      const Vec3 n = decodeNormal(nb);
      const float len = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      EXPECT_NEAR(len, 0.5f, 0.01f);  // the decoded hit point lies on the sphere
      EXPECT_GT((n.x * p.x + n.y * p.y + n.z * p.z) / len, 0.99f);  // interpolated normal ~ radial
    }
  }
  EXPECT_GT(hits, 100u);
}

TEST(Bake, ByteIdenticalWhateverTheThreadCount) {
  Mesh mesh = makeTorusKnot();
  std::vector<uint8_t> first;
  for (unsigned threads : {1u, 2u, 8u}) {
    auto scene = Scene::create(mesh, threads);
    BakeOptions o = smallOptions(DistanceEncoding::kUnorm8Diameter, 4, 16);
    o.normals = true;
    o.threads = threads;
    auto baked = bakeField(*scene, o);
    ASSERT_TRUE(baked.ok());
    WriteOptions wo;
    wo.codec = Codec::kZstd;
    wo.zstdLevel = 3;
    auto bytes = writeMemory(baked->field, baked->distance, baked->normals, wo);
    ASSERT_TRUE(bytes.ok());
    if (first.empty()) first = *bytes;
    else EXPECT_EQ(first, *bytes) << threads << " threads";
  }
}

TEST(Bake, RejectsAbsurdParameters) {
  Mesh mesh = makeBox(1, 1, 1);
  BakeOptions o;
  o.positionParam = 0;
  EXPECT_EQ(describeBake(mesh, o).error().code, Code::kPositionScheme);
  o = {};
  o.encoding = DistanceEncoding::kBit1;
  o.mapResolution = 12;
  EXPECT_EQ(describeBake(mesh, o).error().code, Code::kMapResolution);
  o = {};
  o.sphere = Sphere{{0, 0, 0}, -1};
  EXPECT_EQ(describeBake(mesh, o).error().code, Code::kSphere);
}

TEST(Bake, SharedMeshesMatchExactCasts) {
  namespace fs = std::filesystem;
  const fs::path dir = VFF_SHARED_MESHES;
  if (!fs::is_directory(dir)) GTEST_SKIP() << "no shared meshes at " << dir.string() << ": skipped";
  int baked = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".obj") continue;
    auto mesh = loadMesh(entry.path().string());
    ASSERT_TRUE(mesh.ok()) << mesh.error().toString();
    auto scene = Scene::create(*mesh);
    auto field = bakeField(*scene, smallOptions(DistanceEncoding::kUnorm8Diameter, 2, 16));
    ASSERT_TRUE(field.ok());
    Stats st = checkAgainstReference(*mesh, *field);
    std::printf("[ %s ] %zu triangles: %llu hits, %llu misses, worst %.3f steps\n", entry.path().filename().c_str(),
                mesh->triangleCount(), (unsigned long long)st.hits, (unsigned long long)st.misses, st.worstStepRatio);
    ++baked;
  }
  EXPECT_GT(baked, 0);
}

}  // namespace
}  // namespace vff::bake
