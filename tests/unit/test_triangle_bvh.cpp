// The refined query's exact step against a test of every triangle: the binary BVH
// (libvff/src/refine/triangle_bvh.h, the one the GPU walks) finds the same first hit and the same
// occlusion for random rays through a triangle soup, and the wide BVH the CPU casts through
// (wide_bvh.h) answers exactly as the binary one.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "refine/triangle_bvh.h"
#include "refine/wide_bvh.h"

namespace vff::detail {
namespace {

bool bruteForce(const std::vector<float>& p, const std::vector<uint32_t>& ix, Vec3 o, Vec3 d, float tmax, float* best) {
  bool found = false;
  *best = tmax;
  for (size_t t = 0; t < ix.size(); t += 3) {
    auto v = [&](int k) { return Vec3{p[3 * ix[t + k]], p[3 * ix[t + k] + 1], p[3 * ix[t + k] + 2]}; };
    const Vec3 a = v(0), b = v(1), c = v(2);
    const Vec3 e1{b.x - a.x, b.y - a.y, b.z - a.z}, e2{c.x - a.x, c.y - a.y, c.z - a.z};
    const Vec3 pv{d.y * e2.z - d.z * e2.y, d.z * e2.x - d.x * e2.z, d.x * e2.y - d.y * e2.x};
    const float det = e1.x * pv.x + e1.y * pv.y + e1.z * pv.z;
    if (det == 0) continue;
    const Vec3 tv{o.x - a.x, o.y - a.y, o.z - a.z};
    const float u = (tv.x * pv.x + tv.y * pv.y + tv.z * pv.z) / det;
    const Vec3 q{tv.y * e1.z - tv.z * e1.y, tv.z * e1.x - tv.x * e1.z, tv.x * e1.y - tv.y * e1.x};
    const float w = (d.x * q.x + d.y * q.y + d.z * q.z) / det;
    const float th = (e2.x * q.x + e2.y * q.y + e2.z * q.z) / det;
    if (u >= 0 && w >= 0 && u + w <= 1 && th >= 0 && th <= *best) *best = th, found = true;
  }
  return found;
}

// Small triangles scattered in a cube, a few large ones.
void soup(uint32_t triangles, std::vector<float>* p, std::vector<uint32_t>* ix) {
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(-1, 1), s(0.02f, 0.3f);
  for (uint32_t t = 0; t < triangles; ++t) {
    const float cx = u(g), cy = u(g), cz = u(g), size = t % 100 == 0 ? 1.0f : s(g);
    for (int v = 0; v < 3; ++v) {
      p->insert(p->end(), {cx + size * u(g), cy + size * u(g), cz + size * u(g)});
      ix->push_back(uint32_t(ix->size()));
    }
  }
}

TEST(TriangleBvh, MatchesATestOfEveryTriangle) {
  std::mt19937 g(5);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<float> p;
  std::vector<uint32_t> ix;
  soup(3000, &p, &ix);
  const TriangleBvh bvh(p, ix);
  ASSERT_FALSE(bvh.empty());
  int hits = 0;
  for (int r = 0; r < 5000; ++r) {
    const Vec3 o{3 * u(g), 3 * u(g), 3 * u(g)}, at{u(g), u(g), u(g)};
    const Vec3 d{at.x - o.x, at.y - o.y, at.z - o.z};
    const float tmax = r % 2 ? INFINITY : 1.0f;
    float tb = 0, tx = 0;
    Vec3 n;
    const bool b = bruteForce(p, ix, o, d, tmax, &tb);
    const bool x = bvh.intersect(o, d, 0, tmax, &tx, &n);
    ASSERT_EQ(b, x) << "ray " << r;
    ASSERT_EQ(b, bvh.occluded(o, d, 0, tmax)) << "ray " << r;
    if (b) {
      ++hits;
      ASSERT_NEAR(tb, tx, 1e-5f * tb) << "ray " << r;
      ASSERT_NEAR(n.x * n.x + n.y * n.y + n.z * n.z, 1.0f, 1e-5f);
      ASSERT_LE(n.x * d.x + n.y * d.y + n.z * d.z, 0.0f);
    }
  }
  EXPECT_GT(hits, 1000);
}

// Random rays, and axis-parallel ones starting on the planes of the triangles' vertices (the box
// tests' NaN case: a ray on a box's face): the same hits, the same t to the bit, the same normal.
void expectWideAnswersAsBinary(uint32_t triangles) {
  std::vector<float> p;
  std::vector<uint32_t> ix;
  soup(triangles, &p, &ix);
  const TriangleBvh bin(p, ix);
  const WideBvh wide(bin);
  ASSERT_FALSE(wide.empty());
  std::mt19937 g(11);
  std::uniform_real_distribution<float> u(-1, 1);
  int hits = 0;
  for (int r = 0; r < 6000; ++r) {
    Vec3 o{3 * u(g), 3 * u(g), 3 * u(g)}, d{u(g) - o.x, u(g) - o.y, u(g) - o.z};
    if (r % 3 == 0) {  // along an axis, through a vertex: on the planes of boxes' faces
      const int axis = r / 3 % 3;
      const float* v = &p[3 * size_t(g() % (p.size() / 3))];
      float oa[3] = {v[0], v[1], v[2]}, da[3] = {0.0f, r % 2 ? -0.0f : 0.0f, 0.0f};
      oa[axis] += 3.0f;
      da[axis] = -1.0f;
      o = {oa[0], oa[1], oa[2]};
      d = {da[0], da[1], da[2]};
    }
    const float tmin = r % 5 == 0 ? 0.5f : 0.0f, tmax = r % 2 ? INFINITY : 2.0f;
    float tb = 0, tw = 0;
    Vec3 nb, nw;
    const bool b = bin.intersect(o, d, tmin, tmax, &tb, &nb);
    ASSERT_EQ(b, wide.intersect(o, d, tmin, tmax, &tw, &nw)) << "ray " << r;
    ASSERT_EQ(bin.occluded(o, d, tmin, tmax), wide.occluded(o, d, tmin, tmax)) << "ray " << r;
    ASSERT_EQ(b, bin.occluded(o, d, tmin, tmax)) << "ray " << r;
    if (!b) continue;
    ++hits;
    ASSERT_EQ(tb, tw) << "ray " << r;
    ASSERT_EQ(nb.x, nw.x) << "ray " << r;
    ASSERT_EQ(nb.y, nw.y) << "ray " << r;
    ASSERT_EQ(nb.z, nw.z) << "ray " << r;
  }
  EXPECT_GT(hits, triangles < 10 ? 5 : 1000);
}

TEST(WideBvh, AnswersAsTheBinaryBvh) { expectWideAnswersAsBinary(3000); }
TEST(WideBvh, AnswersAsTheBinaryBvhForOneLeaf) { expectWideAnswersAsBinary(5); }
TEST(WideBvh, AnswersAsTheBinaryBvhForOneTriangle) { expectWideAnswersAsBinary(1); }

// Four children a node: fewer, larger nodes, and fewer bytes than the binary BVH's.
TEST(WideBvh, HoldsFewerBytesThanTheBinaryBvh) {
  std::vector<float> p;
  std::vector<uint32_t> ix;
  soup(3000, &p, &ix);
  const TriangleBvh bin(p, ix);
  const WideBvh wide(bin);
  const uint64_t binNodes = bin.nodes().size_bytes(), wideNodes = wide.bytes() - bin.triangles().size_bytes();
  EXPECT_LT(wideNodes, binNodes) << wide.nodeCount() << " wide nodes, " << bin.nodes().size()
                                                        << " binary";
  EXPECT_LE(wide.nodeCount(), bin.nodes().size() / 3 + 1);
}

}  // namespace
}  // namespace vff::detail
