#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "vff/bake/procedural.h"
#include "vff/bake/sphere.h"

namespace vff::bake {
namespace {

double dist(const Sphere& s, const float* p) {
  const double dx = double(p[0]) - s.center[0], dy = double(p[1]) - s.center[1], dz = double(p[2]) - s.center[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

TEST(Sphere, BoxSphereIsHalfDiagonal) {
  Mesh box = makeBox(1.0f, 0.5f, 0.25f);
  Sphere s = minimalEnclosingSphere(box.positions);
  EXPECT_NEAR(s.radius, std::sqrt(1.0 + 0.25 + 0.0625), 1e-6);
  EXPECT_NEAR(s.center[0], 0.0, 1e-6);
}

TEST(Sphere, TighterThanTheBoundingBoxSphere) {
  // A tetrahedron-like cloud: the AABB's sphere is larger than the minimal one.
  const std::vector<float> pts = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  Sphere s = minimalEnclosingSphere(pts);
  // Minimal sphere of the right-corner tetrahedron: through the three unit points, radius sqrt(3)/3*...
  // Its centre is the circumcentre of (1,0,0),(0,1,0),(0,0,1) = (1/3,1/3,1/3), radius sqrt(2/3).
  EXPECT_NEAR(s.radius, std::sqrt(2.0 / 3.0), 1e-6);
  EXPECT_NEAR(s.center[0], 1.0 / 3.0, 1e-6);
  EXPECT_LT(s.radius, std::sqrt(3.0) / 2.0);  // the AABB's sphere
}

TEST(Sphere, EncloseEveryPointAndTouchTheHull) {
  std::mt19937 rng(7);
  std::normal_distribution<float> g;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> pts;
    const int n = 10 + trial * 50;
    for (int i = 0; i < n; ++i) pts.insert(pts.end(), {g(rng) * 2, g(rng), g(rng) * 0.5f + 3});
    Sphere s = minimalEnclosingSphere(pts);
    double far = 0;
    for (int i = 0; i < n; ++i) {
      const double d = dist(s, &pts[size_t(3 * i)]);
      EXPECT_LE(d, double(s.radius));
      far = std::max(far, d);
    }
    EXPECT_NEAR(far, s.radius, 1e-5 * s.radius);  // some point is on the boundary
    // Minimality: moving the centre a little in any axis direction cannot shrink the radius.
    for (int axis = 0; axis < 3; ++axis)
      for (float step : {-1e-3f, 1e-3f}) {
        Sphere t = s;
        t.center[axis] += step;
        double r = 0;
        for (int i = 0; i < n; ++i) r = std::max(r, dist(t, &pts[size_t(3 * i)]));
        EXPECT_GE(r, double(s.radius) - 1e-6);
      }
  }
}

TEST(Sphere, Deterministic) {
  Mesh knot = makeTorusKnot();
  Sphere a = minimalEnclosingSphere(knot.positions), b = minimalEnclosingSphere(knot.positions);
  EXPECT_EQ(0, std::memcmp(&a, &b, sizeof a));
}

}  // namespace
}  // namespace vff::bake
