#include "vff/bake/sphere.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace vff::bake {
namespace {

struct P {
  double x, y, z;
};
P sub(P a, P b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
P add(P a, P b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
P mul(P a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(P a, P b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
P cross(P a, P b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

struct Ball {
  P c{0, 0, 0};
  double r2 = -1;  // empty
};

Ball fromTwo(P a, P b) { return {mul(add(a, b), 0.5), dot(sub(a, b), sub(a, b)) * 0.25}; }

bool inside(const Ball& b, P p, double eps) { return dot(sub(p, b.c), sub(p, b.c)) <= b.r2 * (1 + eps) + eps; }

// The smallest ball with a, b, c on its boundary (the circumcircle's ball), or the best of the
// pairwise balls when the points are (nearly) collinear.
Ball fromThree(P a, P b, P c, double eps) {
  const P ab = sub(b, a), ac = sub(c, a);
  const P n = cross(ab, ac);
  const double d = 2 * dot(n, n);
  if (d <= 1e-30 * dot(ab, ab) * dot(ac, ac) || d == 0) {
    Ball best = fromTwo(a, b);
    for (Ball cand : {fromTwo(a, c), fromTwo(b, c)})
      if (cand.r2 > best.r2) best = cand;
    return best;
  }
  const P o = mul(add(mul(cross(n, ab), dot(ac, ac)), mul(cross(ac, n), dot(ab, ab))), 1.0 / d);
  (void)eps;
  return {add(a, o), dot(o, o)};
}

// The ball with a, b, c, d on its boundary, or the smallest enclosing ball of the four points when
// they are (nearly) coplanar.
Ball fromFour(P a, P b, P c, P d, double eps) {
  const P ab = sub(b, a), ac = sub(c, a), ad = sub(d, a);
  const double det = 2 * dot(ab, cross(ac, ad));
  const double scale = std::sqrt(dot(ab, ab) * dot(ac, ac) * dot(ad, ad));
  if (std::fabs(det) <= 1e-14 * scale || det == 0) {
    Ball best;
    const P pts[4] = {a, b, c, d};
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        for (int k = j + 1; k < 4; ++k) {
          Ball cand = fromThree(pts[i], pts[j], pts[k], eps);
          bool all = true;
          for (const P& q : pts) all = all && inside(cand, q, 1e-9);
          if (all && (best.r2 < 0 || cand.r2 < best.r2)) best = cand;
        }
    return best;
  }
  const P o = mul(add(add(mul(cross(ac, ad), dot(ab, ab)), mul(cross(ad, ab), dot(ac, ac))), mul(cross(ab, ac), dot(ad, ad))),
                  1.0 / det);
  return {add(a, o), dot(o, o)};
}

}  // namespace

Sphere minimalEnclosingSphere(std::span<const float> xyz) {
  const size_t n = xyz.size() / 3;
  std::vector<P> pts(n);
  for (size_t i = 0; i < n; ++i) pts[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  // Fixed-seed Fisher-Yates: the expected linear running time of Welzl's algorithm, and the same
  // result on every platform (std::mt19937_64 is fully specified; std::shuffle is not).
  std::mt19937_64 rng(0x5eed);
  for (size_t i = n; i > 1; --i) std::swap(pts[i - 1], pts[size_t(rng() % i)]);
  const double eps = 1e-12;
  Ball b;
  if (n) b = {pts[0], 0};
  for (size_t i = 1; i < n; ++i) {
    if (inside(b, pts[i], eps)) continue;
    b = {pts[i], 0};
    for (size_t j = 0; j < i; ++j) {
      if (inside(b, pts[j], eps)) continue;
      b = fromTwo(pts[i], pts[j]);
      for (size_t k = 0; k < j; ++k) {
        if (inside(b, pts[k], eps)) continue;
        b = fromThree(pts[i], pts[j], pts[k], eps);
        for (size_t l = 0; l < k; ++l) {
          if (inside(b, pts[l], eps)) continue;
          b = fromFour(pts[i], pts[j], pts[k], pts[l], eps);
        }
      }
    }
  }
  Sphere s;
  s.center[0] = float(b.c.x);
  s.center[1] = float(b.c.y);
  s.center[2] = float(b.c.z);
  // Radius from the float centre, so every point is inside the sphere as stored.
  double r = 0;
  for (const P& p : pts) {
    const P d = sub(p, P{s.center[0], s.center[1], s.center[2]});
    r = std::max(r, std::sqrt(dot(d, d)));
  }
  float rf = float(r);
  if (double(rf) < r) rf = std::nextafter(rf, INFINITY);
  s.radius = std::max(rf, std::numeric_limits<float>::min());
  return s;
}

}  // namespace vff::bake
