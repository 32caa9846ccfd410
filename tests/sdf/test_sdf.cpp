// test_sdf.cpp - the signed-distance-field peer of the experiments (sdf/, vff/sdf/sdf_field.h)
// against exact casts: sphere tracing hits where Embree does, within a tolerance in voxels; rays
// that pass clear of the surface miss; the memory budget holds; the cone estimate and the
// placement do what sdf_field.h says. The comparison in vff-experiments is only as fair as this
// peer is correct.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "vff/bake/embree_reference.h"
#include "vff/sdf/sdf_field.h"
#include "vff/bake/procedural.h"

namespace {

using vff::Vec3;
using vffx::SdfField;

Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 scale(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
float len(Vec3 a) { return std::sqrt(dot(a, a)); }
Vec3 unit(Vec3 a) { return scale(a, 1.0f / len(a)); }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closestOnTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = sub(p, b);
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return add(a, scale(ab, d1 / (d1 - d3)));
  const Vec3 cp = sub(p, c);
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return add(a, scale(ac, d2 / (d2 - d6)));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const float denom = 1.0f / (va + vb + vc);
  return add(a, add(scale(ab, vb * denom), scale(ac, vc * denom)));
}

float distanceToMesh(const vff::bake::Mesh& m, Vec3 p) {
  float best = INFINITY;
  const float* v = m.positions.data();
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const uint32_t* ix = &m.indices[3 * t];
    const Vec3 a{v[3 * ix[0]], v[3 * ix[0] + 1], v[3 * ix[0] + 2]};
    const Vec3 b{v[3 * ix[1]], v[3 * ix[1] + 1], v[3 * ix[1] + 2]};
    const Vec3 c{v[3 * ix[2]], v[3 * ix[2] + 1], v[3 * ix[2] + 2]};
    best = std::min(best, len(sub(p, closestOnTriangle(p, a, b, c))));
  }
  return best;
}

SdfField build(const vff::bake::Mesh& m, uint64_t budget, vffx::SdfValues values = vffx::SdfValues::kFp8) {
  auto sdf = SdfField::build(m, {.budgetBytes = budget, .values = values});
  EXPECT_TRUE(sdf) << (sdf ? "" : sdf.error().toString());
  return std::move(*sdf);
}

Vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<float> n;
  return unit(Vec3{n(rng), n(rng), n(rng)});
}

// True when a ray moved sideways by `tol` (four ways) misses the mesh: the ray passes within tol of
// an edge or a silhouette, where the sampled distance rounds the shape off by up to a voxel.
bool nearSilhouette(const vff::bake::EmbreeReference& exact, Vec3 origin, Vec3 dir, float tol) {
  const Vec3 a = unit(cross(dir, std::fabs(dir.x) < 0.9f * len(dir) ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
  const Vec3 b = unit(cross(dir, a));
  for (Vec3 side : {a, scale(a, -1), b, scale(b, -1)})
    if (exact.cast(add(origin, scale(side, tol)), dir) < 0) return true;
  return false;
}

// Rays from a shell around the mesh's bounding sphere aimed inside it. For each: the exact first
// hit (Embree); a hit the tracer reports must lie within tolerance of the surface (earlier than the
// exact hit is then right: the ray passes that close to the surface there) and not behind the
// exact hit by more than the tolerance spread along the ray (tol / cos); an exact hit not at grazing incidence (|cos| >= 0.25) nor within tolerance of a silhouette
// (nearSilhouette) must be found; an exact miss must stay a
// miss unless the tracer's hit point is within tolerance of the surface (a ray grazing an edge).
// Returns the failures, printing the first few.
int checkAgainstExact(const vff::bake::Mesh& m, const SdfField& sdf, float tolVoxels, int rays) {
  vff::bake::EmbreeReference exact(m);
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi = scale(lo, -1);
  for (size_t i = 0; i < m.vertexCount(); ++i) {
    const Vec3 p{m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Vec3 centre = scale(add(lo, hi), 0.5f);
  const float radius = 0.5f * len(sub(hi, lo));
  const float tol = tolVoxels * sdf.voxelSize();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  int failures = 0, hits = 0;
  for (int i = 0; i < rays; ++i) {
    const Vec3 origin = add(centre, scale(randomUnit(rng), radius * (1.2f + u(rng))));
    // Half the rays aim at a vertex (thin shapes get hits too), half anywhere inside the sphere.
    const size_t vertex = size_t(u(rng) * float(m.vertexCount())) % m.vertexCount();
    const Vec3 target = i % 2 ? Vec3{m.positions[3 * vertex], m.positions[3 * vertex + 1], m.positions[3 * vertex + 2]}
                              : add(centre, scale(randomUnit(rng), radius * std::cbrt(u(rng))));
    const Vec3 dir = scale(sub(target, origin), 0.5f + u(rng));  // not unit: t in its multiples
    Vec3 ng{};
    const float te = exact.cast(origin, dir, &ng);
    const vffx::SdfHit h = sdf.intersect({origin, dir});
    const float cosine = te >= 0 ? std::fabs(dot(unit(ng), unit(dir))) : 0.0f;
    const char* why = nullptr;
    if (h.hit) {
      ++hits;
      const Vec3 p = add(origin, scale(dir, h.t));
      if (distanceToMesh(m, p) > tol) why = "hit off the surface";
      // Later than the exact hit (beyond the band the incidence spreads it over): through a surface.
      else if (te >= 0 && cosine >= 0.25f && (h.t - te) * len(dir) > tol / cosine) why = "hit behind the exact hit";
    } else if (te >= 0 && cosine >= 0.25f && !nearSilhouette(exact, origin, dir, tol)) {
      why = "missed a clear hit";
    }
    if (why && ++failures <= 5)
      ADD_FAILURE() << why << ": ray " << i << " exact t " << te << " (cos " << cosine << "), sdf hit " << h.hit
                    << " t " << h.t << " (|d| " << len(dir) << ", voxel " << sdf.voxelSize() << ", steps " << h.steps << ")";
  }
  EXPECT_GT(hits, rays / 5) << "too few hits to test anything";
  return failures;
}

TEST(Sdf, SphereHitsExactCastsWithinOneVoxel) {
  const vff::bake::Mesh m = vff::bake::makeSphere(1.0f, 32, 64);
  for (vffx::SdfValues values : {vffx::SdfValues::kFp8, vffx::SdfValues::kFloat}) {
    const SdfField sdf = build(m, 256 << 10, values);
    EXPECT_LT(sdf.voxelSize(), 0.1f);
    EXPECT_EQ(checkAgainstExact(m, sdf, 1.0f, 300), 0);
  }
}

TEST(Sdf, BoxHitsExactCastsWithinOneVoxel) {
  const vff::bake::Mesh m = vff::bake::makeBox(1.0f, 0.5f, 0.25f);
  const SdfField sdf = build(m, 256 << 10);
  EXPECT_EQ(checkAgainstExact(m, sdf, 1.0f, 400), 0);
}

TEST(Sdf, ProceduralShapesHitExactCasts) {
  for (const char* name : {"torus-knot", "bowl", "rod"}) {
    SCOPED_TRACE(name);
    const vff::bake::Mesh m = vff::bake::makeShape(name);
    const SdfField sdf = build(m, 512 << 10);
    EXPECT_EQ(checkAgainstExact(m, sdf, 1.0f, 200), 0);
  }
}

TEST(Sdf, RaysClearOfTheSurfaceMiss) {
  const vff::bake::Mesh m = vff::bake::makeSphere(1.0f, 48, 96);
  const SdfField sdf = build(m, 128 << 10);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 300; ++i) {
    // A line passing the centre at 1 + 2 voxels .. 3: the sphere (radius 1, its facets inside) is
    // never within reach of the hit threshold.
    const Vec3 axis = randomUnit(rng);
    Vec3 side = unit(cross(axis, randomUnit(rng)));
    const float clearance = 1.0f + 2.0f * sdf.voxelSize() + 2.0f * u(rng);
    const Vec3 origin = add(scale(side, clearance), scale(axis, -4.0f));
    const vffx::SdfHit h = sdf.intersect({origin, axis});
    EXPECT_FALSE(h.hit) << "ray " << i << " passing at " << clearance << " hit at t " << h.t;
  }
  // Rays that never meet the grid's box take no step.
  const vffx::SdfHit away = sdf.intersect({{0, 5, 0}, {0, 1, 0}});
  EXPECT_FALSE(away.hit);
  EXPECT_EQ(away.steps, 0);
  // The box is clipped to [tmin, tmax]: a ray stopping short of the sphere misses.
  EXPECT_FALSE(sdf.occluded({{0, 0, 3}, {0, 0, -1}, 0.0f, 1.8f}));
  EXPECT_TRUE(sdf.occluded({{0, 0, 3}, {0, 0, -1}, 0.0f, 2.2f}));
}

TEST(Sdf, MemoryBudgetIsHonoured) {
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  float previousVoxel = INFINITY, xmin = INFINITY, xmax = -INFINITY;
  for (size_t i = 0; i < m.vertexCount(); ++i) {
    xmin = std::min(xmin, m.positions[3 * i]);
    xmax = std::max(xmax, m.positions[3 * i]);
  }
  const double extent = double(xmax - xmin);
  for (uint64_t budget : {uint64_t(64) << 10, uint64_t(256) << 10, uint64_t(1) << 20}) {
    const SdfField sdf = build(m, budget);
    EXPECT_LE(sdf.bytes(), budget);
    EXPECT_GT(sdf.nanovdbBytes(), sdf.bytes());  // the same leaves, and NanoVDB's tree above them
    EXPECT_GE(double(sdf.bytes()), 0.85 * double(budget)) << "voxel " << sdf.voxelSize() << " after "
                                                               << sdf.builds() << " builds";
    EXPECT_LT(sdf.voxelSize(), previousVoxel);
    previousVoxel = sdf.voxelSize();
    EXPECT_EQ(sdf.denseBytes(), uint64_t(sdf.dims(0)) * sdf.dims(1) * sdf.dims(2));  // one byte a value
    // The active box spans the shape plus its band on each side.
    const double h = sdf.voxelSize();
    EXPECT_GE(double(sdf.dims(0)) * h, extent);
    EXPECT_LE(double(sdf.dims(0)) * h, extent + 2.0 * (sdf.bandVoxels() + 1.0) * h);
  }
  auto tooSmall = SdfField::build(m, {.budgetBytes = 512});
  ASSERT_FALSE(tooSmall);
  EXPECT_EQ(tooSmall.error().code, vff::Code::kInvalidArgument);
}

TEST(Sdf, ConeEstimateFollowsClearanceOverDistance) {
  const vff::bake::Mesh m = vff::bake::makeSphere(1.0f, 64, 128);
  const SdfField sdf = build(m, 512 << 10, vffx::SdfValues::kFloat);
  // A ray passing the unit sphere at clearance c, its closest approach a distance D from the
  // origin: min over t of 0.5 + 0.5 d(t) / (t tan) is about 0.5 + 0.5 c / (D tan) (a little less,
  // past the closest point), for clearances within the band; beyond it the grid knows of no
  // surface. A ray through the sphere: the disc is covered, 0.
  const float h = sdf.voxelSize(), D = 2.0f, tan = 0.05f;
  for (float c : {0.8f * h, 1.6f * h, 2.4f * h}) {
    const vff::Ray ray{{1.0f + c, 0, -D}, {0, 0, 1}, 0.0f, 4.0f};
    const float v = sdf.visibility(ray, {.coneTan = tan});
    const float expected = std::min(1.0f, 0.5f + 0.5f * c / (D * tan));
    EXPECT_NEAR(v, expected, 0.1f * expected + 0.15f * h / (D * tan)) << "clearance " << c / h << " voxels";
    EXPECT_FALSE(sdf.occluded(ray));
  }
  const float beyond = (sdf.bandVoxels() + 2.0f) * h;
  EXPECT_EQ(sdf.visibility({{1.0f + beyond, 0, -D}, {0, 0, 1}, 0.0f, 4.0f}, {.coneTan = tan}), 1.0f);
  // The axis inside the surface by a quarter of the cone's radius there: 0.5 - 0.125.
  const float r = D * tan;
  EXPECT_NEAR(sdf.visibility({{1.0f - 0.25f * r, 0, -D}, {0, 0, 1}, 0.0f, 2.0f}, {.coneTan = tan}), 0.375f, 0.06f);
  // A hit: 0; far from the object: 1; the light's disc of radius r at tmax: tan = r / (tmax |d|).
  EXPECT_EQ(sdf.visibility({{0, 0, -3}, {0, 0, 1}, 0.0f, 6.0f}, {.coneTan = 0.1f}), 0.0f);
  EXPECT_EQ(sdf.visibility({{3, 3, -3}, {0, 0, 1}, 0.0f, 6.0f}, {.coneTan = 0.1f}), 1.0f);
  const vff::Ray toLight{{1.1f, 0, -2}, {0, 0, 8}, 0.0f, 1.0f};
  EXPECT_FLOAT_EQ(sdf.visibility(toLight, {.coneRadiusAtEnd = 1.6f}), sdf.visibility(toLight, {.coneTan = 0.2f}));
}

TEST(Sdf, PlacedGridAnswersWorldRays) {
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  SdfField sdf = build(m, 256 << 10);
  std::mt19937 rng(11);
  std::vector<vff::Ray> object;
  for (int i = 0; i < 100; ++i) object.push_back({scale(randomUnit(rng), 3.0f), randomUnit(rng)});
  for (vff::Ray& r : object) r.direction = unit(sub(scale(randomUnit(rng), 0.5f), r.origin));
  std::vector<vffx::SdfHit> before;
  for (const vff::Ray& r : object) before.push_back(sdf.intersect(r));
  sdf.transform = vff::RigidTransform::fromAxisAngle({1, 2, 3}, 0.7f, {4, -1, 2}, 2.0f);
  int hits = 0;
  for (size_t i = 0; i < object.size(); ++i) {
    const vff::Ray w{sdf.transform.toWorldPoint(object[i].origin), sdf.transform.toWorldVector(object[i].direction)};
    const vffx::SdfHit h = sdf.intersect(w);
    ASSERT_EQ(h.hit, before[i].hit) << "ray " << i;
    if (!h.hit) continue;
    ++hits;
    EXPECT_NEAR(h.t, before[i].t, 1e-3f) << "ray " << i;
    const Vec3 n = sdf.transform.toWorldVector(before[i].normal);
    EXPECT_NEAR(dot(h.normal, unit(n)), 1.0f, 1e-3f) << "ray " << i;
  }
  EXPECT_GT(hits, 20);
}

TEST(Sdf, NormalsFollowTheSurface) {
  const vff::bake::Mesh m = vff::bake::makeSphere(1.0f, 48, 96);
  const SdfField sdf = build(m, 256 << 10);
  std::mt19937 rng(5);
  for (int i = 0; i < 100; ++i) {
    const Vec3 o = scale(randomUnit(rng), 3.0f);
    const vffx::SdfHit h = sdf.intersect({o, scale(o, -1.0f)});
    ASSERT_TRUE(h.hit);
    EXPECT_GT(dot(h.normal, unit(o)), 0.995f) << "ray " << i;
  }
}

// Stepping over the tree's empty blocks finds the hits the plain trace finds, at the same t within
// a voxel, in fewer steps.
TEST(Sdf, EmptySpaceSkippingKeepsTheHits) {
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const SdfField sdf = build(m, 512 << 10);
  std::mt19937 rng(13);
  int hits = 0;
  long stepsPlain = 0, stepsSkipping = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 o = scale(randomUnit(rng), 3.0f);
    const vff::Ray ray{o, sub(scale(randomUnit(rng), 0.8f), o)};
    const vffx::SdfHit plain = sdf.intersect(ray, {.skipEmpty = false});
    const vffx::SdfHit skipping = sdf.intersect(ray);
    stepsPlain += plain.steps;
    stepsSkipping += skipping.steps;
    ASSERT_EQ(plain.hit, skipping.hit) << "ray " << i;
    if (!plain.hit) continue;
    ++hits;
    EXPECT_NEAR(plain.t * len(ray.direction), skipping.t * len(ray.direction), sdf.voxelSize()) << "ray " << i;
  }
  EXPECT_GT(hits, 50);
  EXPECT_LT(stepsSkipping, stepsPlain);
}

}  // namespace
