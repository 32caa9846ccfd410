// The CPU query (vff/query.h) against exact Embree casts on procedural meshes: the spec's lookup
// at the sample points, inter-object rays, intra-object occlusion, ambient occlusion accuracy of
// both reconstructions, normals, transforms, batches and files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "common/baked_shape.h"
#include "common/rng.h"
#include "common/vec3.h"
#include "platform/huge_pages.h"  // private: detail::adviseHugePages
#include "vff/bake/embree_reference.h"
#include "vff/vff.h"

namespace vff {
namespace {

using Reference = bake::EmbreeReference;
using test::bakeShape;
using test::BakedShape;
using test::Rng;
using test::add;
using test::centerOf;
using test::dot3;
using test::mul;
using test::sub;
using test::unit;


// ---- The lookup of spec/geometry.md 7.2, texel by texel -----------------------------------------

TEST(Query, NearestIsTheSpecLookupAtSamplePoints) {
  // A ray that enters the sphere exactly at sample k along the direction of texel (i, j) must be
  // answered with that texel: t = entry + decoded distance.
  auto b = bakeShape("torus-knot", 4, 16);
  const FieldDesc& f = b->field.field;
  const float R = f.sphere.radius;
  const Vec3 c = centerOf(f);
  const PositionSet& ps = b->query.positions();
  uint32_t checked = 0, hits = 0;
  for (uint32_t k = 0; k < f.mapCount; k += 3) {
    const Vec3 u = ps.position(k);
    const Frame fr = ps.frame(k);
    for (uint32_t j = 0; j < f.mapResolution; j += 3)
      for (uint32_t i = 0; i < f.mapResolution; i += 3) {
        const Vec3 local = texelDirection(f.directionScheme, f.mapResolution, i, j);
        const Vec3 d = toWorld(fr, local);
        const Vec3 entry = add(c, mul(u, R));
        const Ray ray{sub(entry, mul(d, 0.5f * R)), d};  // starts outside, enters at the sample point
        const QueryHit h = b->query.intersect(ray);
        const auto map = std::span<const uint8_t>(b->field.distance).subspan(size_t(k) * f.mapResolution * f.mapResolution,
                                                                              size_t(f.mapResolution) * f.mapResolution);
        const Texel tx = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, map, f.mapResolution, i, j), R, local.z);
        ++checked;
        ASSERT_EQ(h.hit, tx.hit) << "map " << k << " texel " << i << "," << j;
        if (!tx.hit) continue;
        ++hits;
        EXPECT_NEAR(h.t, 0.5f * R + tx.distance, 2e-4f * R) << "map " << k << " texel " << i << "," << j;
        EXPECT_FALSE(h.inside);
      }
  }
  EXPECT_GT(hits, 50u);
  std::printf("[ query ] %u lookups at sample points, %u hits, all equal to the stored texels\n", checked, hits);
}

// ---- Inter-object rays against exact casts ------------------------------------------------------

struct RayStats {
  uint64_t rays = 0, agree = 0, bothHit = 0;
  double sumErr = 0;  // |t - exact| / R over rays where both hit
  std::vector<float> errs;
  double agreement() const { return rays ? double(agree) / double(rays) : 0; }
  double medianErr() {
    if (errs.empty()) return 0;
    std::nth_element(errs.begin(), errs.begin() + ptrdiff_t(errs.size() / 2), errs.end());
    return errs[errs.size() / 2];
  }
};

RayStats interObject(const BakedShape& b, Reconstruction mode, uint32_t count, uint64_t seed) {
  const FieldDesc& f = b.field.field;
  const float R = f.sphere.radius;
  const Vec3 c = centerOf(f);
  Reference ref(b.mesh);
  Rng rng(seed);
  RayStats st;
  QueryOptions o;
  o.reconstruction = mode;
  for (uint32_t r = 0; r < count; ++r) {
    // From a point outside the sphere towards a random point inside it.
    const Vec3 from = add(c, mul(rng.direction(), R * (1.2f + rng.uniform())));
    const Vec3 to = add(c, mul(rng.direction(), R * std::cbrt(rng.uniform())));
    const Vec3 d = unit(sub(to, from));
    const float exact = ref.cast(from, d);
    const QueryHit h = b.query.intersect(Ray{from, d}, o);
    ++st.rays;
    if (h.hit == (exact >= 0)) ++st.agree;
    if (h.hit && exact >= 0) {
      ++st.bothHit;
      st.errs.push_back(std::fabs(h.t - exact) / R);
    }
  }
  return st;
}

TEST(Query, InterObjectRaysAgreeWithExactCasts) {
  auto b = bakeShape("torus-knot", 32, 64);  // the paper's 4226 x 64 x 64
  for (Reconstruction mode : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    RayStats st = interObject(*b, mode, 20000, 7);
    const double med = st.medianErr();
    std::printf("[ query ] torus-knot 4226x64x64 %s: hit/miss agree %.2f%%, median |t - exact| = %.4f R (%llu hits)\n",
                mode == Reconstruction::kNearest ? "nearest" : "interpolated", 100 * st.agreement(), med,
                (unsigned long long)st.bothHit);
    EXPECT_GE(st.agreement(), mode == Reconstruction::kNearest ? 0.95 : 0.96);
    EXPECT_LE(med, 0.02);
    EXPECT_GT(st.bothHit, 1000u);
  }
}

// ---- Ambient occlusion on a ground plane: the paper's Fig. 3 at a small size --------------------

struct AoResult {
  double rmsNearest = 0, rmsInterpolated = 0;
};

// AO of a grid of points on the plane under the object (tangent to the mesh's lowest point), with
// `raysPerPoint` cosine-weighted rays of length `reach` * R. Errors on the 8-bit scale.
AoResult groundAo(const BakedShape& b, uint32_t grid, uint32_t raysPerPoint, float reach) {
  const FieldDesc& f = b.field.field;
  const float R = f.sphere.radius;
  const Vec3 c = centerOf(f);
  float zmin = INFINITY;
  for (size_t v = 2; v < b.mesh.positions.size(); v += 3) zmin = std::min(zmin, b.mesh.positions[v]);
  Reference ref(b.mesh);
  const Vec3 up{0, 0, 1};
  QueryOptions nearest, interp;
  interp.reconstruction = Reconstruction::kInterpolated;
  nearest.intraBias = interp.intraBias = 0;  // ground points are not on the object
  double e2n = 0, e2i = 0;
  for (uint32_t gy = 0; gy < grid; ++gy)
    for (uint32_t gx = 0; gx < grid; ++gx) {
      const Vec3 p{c.x + R * (2.4f * (float(gx) + 0.5f) / float(grid) - 1.2f),
                   c.y + R * (2.4f * (float(gy) + 0.5f) / float(grid) - 1.2f), zmin - 1e-4f * R};
      Rng rng(1000 + gy * grid + gx);
      double exact = 0, vn = 0, vi = 0;
      for (uint32_t r = 0; r < raysPerPoint; ++r) {
        const Vec3 d = rng.cosine(up);
        const Ray ray{p, d, 0.0f, reach * R};
        exact += ref.occluded(p, d, 0.0f, reach * R) ? 0.0 : 1.0;
        vn += b.query.visibility(ray, nearest);
        vi += b.query.visibility(ray, interp);
      }
      const double s = 255.0 / raysPerPoint;
      e2n += (exact - vn) * s * (exact - vn) * s;
      e2i += (exact - vi) * s * (exact - vi) * s;
    }
  const double nPts = double(grid) * grid;
  return {std::sqrt(e2n / nPts), std::sqrt(e2i / nPts)};
}

TEST(Query, GroundAmbientOcclusionIsAccurate) {
  // Ground AO under a procedural object at a small image size. Bounds asserted: nearest RMS <= 5 on
  // the 8-bit scale at the paper's 4226 x 64 x 64; interpolated below 0.95 x nearest at the same
  // memory, and within 1.2 x nearest-at-4226x64x64 with a quarter of the memory (4226 x 32 x 32).
  // (Measured: see the printed lines. On the bunny, vff-experiments ao, the quarter-memory field
  // interpolated beats the full one nearest; the 0.6 x goal at equal memory is not reached.)
  for (const char* shape : {"torus-knot", "bowl"}) {
    auto full = bakeShape(shape, 32, 64);
    auto quarter = bakeShape(shape, 32, 32);
    const AoResult a = groundAo(*full, 24, 256, INFINITY);
    const AoResult q = groundAo(*quarter, 24, 256, INFINITY);
    std::printf("[ query ] %s ground AO, 24x24 points x 256 rays: 4226x64x64 RMS nearest %.3f, interpolated %.3f "
                "(ratio %.2f); 4226x32x32 RMS nearest %.3f, interpolated %.3f\n",
                shape, a.rmsNearest, a.rmsInterpolated, a.rmsInterpolated / a.rmsNearest, q.rmsNearest,
                q.rmsInterpolated);
    EXPECT_LE(a.rmsNearest, 5.0) << shape;
    EXPECT_LE(a.rmsInterpolated, 0.95 * a.rmsNearest) << shape;
    EXPECT_LE(q.rmsInterpolated, 1.2 * a.rmsNearest) << shape;
    EXPECT_LT(q.rmsInterpolated, q.rmsNearest) << shape;
  }
}

// ---- Intra-object occlusion ---------------------------------------------------------------------

struct IntraStats {
  uint64_t rays = 0, agree = 0, falseOccluded = 0, missedOccluded = 0;
};

// Rays from points on the surface (triangle centroids, offset along the outward-facing side the
// ray leaves by) in cosine directions around the face normal.
IntraStats intraObject(const BakedShape& b, Reconstruction mode, uint32_t faces, uint32_t raysPerFace) {
  const float R = b.field.field.sphere.radius;
  Reference ref(b.mesh);
  QueryOptions o;
  o.reconstruction = mode;
  IntraStats st;
  const uint32_t tri = uint32_t(b.mesh.triangleCount());
  Rng rng(99);
  for (uint32_t s = 0; s < faces; ++s) {
    const uint32_t t = uint32_t(uint64_t(s) * tri / faces);
    Vec3 v[3];
    for (int a = 0; a < 3; ++a) {
      const uint32_t ix = b.mesh.indices[3 * t + a];
      v[a] = {b.mesh.positions[3 * ix], b.mesh.positions[3 * ix + 1], b.mesh.positions[3 * ix + 2]};
    }
    const Vec3 cr = {(v[1].y - v[0].y) * (v[2].z - v[0].z) - (v[1].z - v[0].z) * (v[2].y - v[0].y),
                          (v[1].z - v[0].z) * (v[2].x - v[0].x) - (v[1].x - v[0].x) * (v[2].z - v[0].z),
                          (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x)};
    if (!(dot3(cr, cr) > 1e-20f)) continue;  // a degenerate triangle (a pole of the sphere) has no normal
    const Vec3 ng = unit(cr);
    const Vec3 centroid = mul(add(add(v[0], v[1]), v[2]), 1.0f / 3);
    for (int side = 0; side < 2; ++side) {
      const Vec3 n = side ? mul(ng, -1) : ng;
      const Vec3 p = add(centroid, mul(n, 1e-3f * R));
      for (uint32_t r = 0; r < raysPerFace; ++r) {
        const Vec3 d = rng.cosine(n);
        const bool exact = ref.occluded(p, d, 0.0f, INFINITY);
        const bool field = b.query.occluded(Ray{p, d}, o);
        ++st.rays;
        if (exact == field) ++st.agree;
        else if (field) ++st.falseOccluded;
        else ++st.missedOccluded;
      }
    }
  }
  return st;
}

TEST(Query, IntraObjectOcclusionAgreesWithExactCasts) {
  // 16642 x 64 x 64 is the paper's configuration for intra-object occlusion (Fig. 5).
  auto b = bakeShape("torus-knot", 64, 64);
  for (Reconstruction mode : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    const IntraStats st = intraObject(*b, mode, 400, 40);
    const double rate = double(st.agree) / double(st.rays);
    std::printf("[ query ] torus-knot intra-object 16642x64x64 %s: %.2f%% agree (%llu rays; %llu falsely occluded, "
                "%llu missed)\n",
                mode == Reconstruction::kNearest ? "nearest" : "interpolated", 100 * rate,
                (unsigned long long)st.rays, (unsigned long long)st.falseOccluded,
                (unsigned long long)st.missedOccluded);
    EXPECT_GE(rate, 0.95);
  }
}

TEST(Query, IntraObjectRaysLeavingAConvexObjectAreFree) {
  // From the outside of a sphere nothing is ever occluded, and from the inside everything is.
  auto b = bakeShape("sphere", 16, 32);
  const IntraStats st = intraObject(*b, Reconstruction::kNearest, 300, 20);
  EXPECT_EQ(st.falseOccluded, 0u);
  EXPECT_GE(double(st.agree) / double(st.rays), 0.97);
}

// ---- Normals, transforms, batches, files, edge cases --------------------------------------------

TEST(Query, NormalsFromTheNormalFieldMatchTheSurface) {
  auto b = bakeShape("sphere", 16, 32, true);
  ASSERT_TRUE(b->query.hasNormals());
  const FieldDesc& f = b->field.field;
  const Vec3 c = centerOf(f);
  const float R = f.sphere.radius;
  Rng rng(3);
  for (Reconstruction mode : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    QueryOptions o;
    o.reconstruction = mode;
    int hits = 0;
    for (int r = 0; r < 2000; ++r) {
      const Vec3 from = add(c, mul(rng.direction(), 2 * R));
      const Vec3 d = unit(sub(add(c, mul(rng.direction(), 0.5f * R)), from));
      const QueryHit h = b->query.intersect(Ray{from, d}, o);
      if (!h.hit) continue;
      ++hits;
      ASSERT_TRUE(h.hasNormal);
      const Vec3 radial = unit(sub(h.point, c));
      EXPECT_GT(dot3(h.normal, radial), 0.97f) << "ray " << r;
    }
    EXPECT_GT(hits, 1500);
  }
}

TEST(Query, InstanceTransformsRaysAndResults) {
  auto b = bakeShape("torus-knot", 8, 32, true);
  Instance inst{&b->query, RigidTransform::fromAxisAngle({1, 2, 3}, 0.7f, {5, -2, 1}, 2.5f)};
  const Sphere ws = inst.worldSphere();
  EXPECT_NEAR(ws.radius, 2.5f * b->field.field.sphere.radius, 1e-5f);
  Rng rng(5);
  int hits = 0;
  for (int r = 0; r < 3000; ++r) {
    const Vec3 wc{ws.center[0], ws.center[1], ws.center[2]};
    const Vec3 from = add(wc, mul(rng.direction(), 2 * ws.radius));
    const Vec3 dir = mul(sub(add(wc, mul(rng.direction(), 0.5f * ws.radius)), from), 0.37f);  // not unit
    const Ray world{from, dir};
    const Ray object{inst.transform.toObjectPoint(from), inst.transform.toObjectVector(dir)};
    const QueryHit hw = inst.intersect(world), ho = b->query.intersect(object);
    ASSERT_EQ(hw.hit, ho.hit);
    if (!hw.hit) continue;
    ++hits;
    EXPECT_NEAR(hw.t, ho.t, 1e-4f * std::fabs(ho.t) + 1e-5f);
    const Vec3 p = inst.transform.toWorldPoint(ho.point);
    EXPECT_NEAR(hw.point.x, p.x, 1e-3f);
    EXPECT_NEAR(hw.point.y, p.y, 1e-3f);
    EXPECT_NEAR(hw.point.z, p.z, 1e-3f);
    const Vec3 n = unit(inst.transform.toWorldVector(ho.normal));
    EXPECT_GT(dot3(hw.normal, n), 0.9999f);
    EXPECT_EQ(inst.occluded(world), ho.hit);
  }
  EXPECT_GT(hits, 500);
}

// The batch calls of q (a FieldQuery or an Instance) answer exactly as its one-ray calls, in both
// reconstructions. Returns the number of hits (over both).
template <class Q>
int expectBatchesEqualSingleRays(const Q& q, const std::vector<Ray>& rays) {
  int hitCount = 0;
  for (Reconstruction mode : {Reconstruction::kNearest, Reconstruction::kInterpolated}) {
    QueryOptions o;
    o.reconstruction = mode;
    std::vector<QueryHit> hits(rays.size());
    std::vector<uint8_t> occ(rays.size());
    std::vector<float> vis(rays.size());
    std::vector<LookupSite> where(rays.size());
    q.intersect(rays, hits, o);
    q.occluded(rays, occ, o);
    q.visibility(rays, vis, o);
    q.sites(rays, where, o);
    for (size_t r = 0; r < rays.size(); ++r) {
      const QueryHit h = q.intersect(rays[r], o);
      const LookupSite s = q.site(rays[r], o);
      EXPECT_EQ(where[r].valid, s.valid) << "ray " << r;
      EXPECT_EQ(where[r].sample, s.sample) << "ray " << r;
      EXPECT_EQ(where[r].i, s.i) << "ray " << r;
      EXPECT_EQ(where[r].j, s.j) << "ray " << r;
      EXPECT_EQ(hits[r].hit, h.hit) << "ray " << r;
      EXPECT_EQ(hits[r].t, h.t) << "ray " << r;
      EXPECT_EQ(hits[r].point.x, h.point.x) << "ray " << r;
      EXPECT_EQ(hits[r].hasNormal, h.hasNormal) << "ray " << r;
      EXPECT_EQ(hits[r].normal.x, h.normal.x) << "ray " << r;
      EXPECT_EQ(hits[r].normal.y, h.normal.y) << "ray " << r;
      EXPECT_EQ(hits[r].normal.z, h.normal.z) << "ray " << r;
      EXPECT_EQ(occ[r] != 0, q.occluded(rays[r], o)) << "ray " << r;
      EXPECT_EQ(vis[r], q.visibility(rays[r], o)) << "ray " << r;
      EXPECT_GE(vis[r], 0.0f);
      EXPECT_LE(vis[r], 1.0f);
      if (mode == Reconstruction::kNearest) {
        EXPECT_EQ(vis[r], h.hit ? 0.0f : 1.0f);
      }
      if (::testing::Test::HasFailure()) return hitCount;
      hitCount += h.hit;
    }
    // Small batches too (an Embree callback's: one ray, or a packet of up to 16), whose paths
    // differ from a large batch's.
    for (const size_t size : {size_t(1), size_t(2), size_t(16), size_t(17)}) {
      for (size_t first = 0; first + size <= std::min(rays.size(), size_t(340)); first += size) {
        const std::span<const Ray> part = std::span<const Ray>(rays).subspan(first, size);
        std::vector<QueryHit> h(size);
        std::vector<uint8_t> oc(size);
        std::vector<float> v(size);
        q.intersect(part, h, o);
        q.occluded(part, oc, o);
        q.visibility(part, v, o);
        for (size_t k = 0; k < size; ++k) {
          const QueryHit one = q.intersect(part[k], o);
          EXPECT_EQ(h[k].hit, one.hit) << "batch of " << size << ", ray " << first + k;
          EXPECT_EQ(h[k].t, one.t) << "batch of " << size << ", ray " << first + k;
          EXPECT_EQ(h[k].point.y, one.point.y) << "batch of " << size << ", ray " << first + k;
          EXPECT_EQ(h[k].normal.z, one.normal.z) << "batch of " << size << ", ray " << first + k;
          EXPECT_EQ(oc[k] != 0, q.occluded(part[k], o)) << "batch of " << size << ", ray " << first + k;
          EXPECT_EQ(v[k], q.visibility(part[k], o)) << "batch of " << size << ", ray " << first + k;
        }
        if (::testing::Test::HasFailure()) return hitCount;
      }
    }
  }
  return hitCount;
}

TEST(Query, InstanceBatchesEqualSingleRays) {
  auto b = bakeShape("torus-knot", 8, 32, true);
  const Instance inst{&b->query, RigidTransform::fromAxisAngle({1, 2, 3}, 0.7f, {5, -2, 1}, 2.5f)};
  const Sphere ws = inst.worldSphere();
  const Vec3 wc{ws.center[0], ws.center[1], ws.center[2]};
  Rng rng(8);
  std::vector<Ray> rays(1000);  // more than one chunk of the object-space transform
  for (Ray& r : rays) {
    r.origin = add(wc, mul(rng.direction(), ws.radius * 2 * rng.uniform()));  // inside and outside
    r.direction = mul(rng.direction(), 0.37f);
    r.tmax = ws.radius * 3 * rng.uniform() / 0.37f;
  }
  EXPECT_GT(expectBatchesEqualSingleRays(inst, rays), 200);
  // No field: every ray misses.
  const Instance empty;
  std::vector<uint8_t> occ(3, 7);
  empty.occluded(std::span<const Ray>(rays).first(3), occ);
  EXPECT_EQ(occ, std::vector<uint8_t>(3, 0));
}

TEST(Query, BatchesEqualSingleRays) {
  auto b = bakeShape("bowl", 8, 16);
  const FieldDesc& f = b->field.field;
  const Vec3 c = centerOf(f);
  Rng rng(11);
  std::vector<Ray> rays(5000);
  for (Ray& r : rays) {
    r.origin = add(c, mul(rng.direction(), f.sphere.radius * 2 * rng.uniform()));  // inside and outside
    r.direction = rng.direction();
    r.tmax = f.sphere.radius * 3 * rng.uniform();
  }
  EXPECT_GT(expectBatchesEqualSingleRays(b->query, rays), 500);
}

TEST(Query, FilesAnswerLikeTheirMaps) {
  auto b = bakeShape("torus-knot", 6, 16, true);
  const auto dir = std::filesystem::path(testing::TempDir());
  Rng rng(13);
  std::vector<Ray> rays(3000);
  const Vec3 c = centerOf(b->field.field);
  const float R = b->field.field.sphere.radius;
  for (Ray& r : rays) r = Ray{add(c, mul(rng.direction(), 1.5f * R)), rng.direction()};
  // One block (the maps back to back) and a block per 7 maps (compressed: maps in separate buffers).
  for (Codec codec : {Codec::kStored, Codec::kZstd}) for (uint32_t perBlock : {0u, 7u}) {
    WriteOptions w;
    w.codec = codec;
    w.mapsPerBlock = perBlock;
    const std::string path = (dir / (std::string("query-") + (codec == Codec::kZstd ? "zstd" : "stored") +
                                     std::to_string(perBlock) + ".vff")).string();
    ASSERT_TRUE(writeFile(path, b->field.field, b->field.distance, b->field.normals, w).ok());
    auto file = File::open(path);
    ASSERT_TRUE(file.ok());
    auto q = FieldQuery::fromFile(*file);
    ASSERT_TRUE(q.ok()) << q.error().toString();
    EXPECT_EQ(q->payloadBytes(), b->query.payloadBytes());
    for (const Ray& r : rays) {
      const QueryHit a = q->intersect(r), e = b->query.intersect(r);
      ASSERT_EQ(a.hit, e.hit);
      ASSERT_EQ(a.t, e.t);
      ASSERT_EQ(a.normal.x, e.normal.x);
    }
    EXPECT_GT(expectBatchesEqualSingleRays(*q, rays), 300);
  }
}

TEST(Query, HugePagesLeaveTheMapsAsTheyWere) {
  // 1090 maps of 64 x 64 (4.5 MiB) in caller memory: making the query may move their whole 2 MiB
  // pages to huge pages (Linux 6.1+), which must change no byte of them and no answer.
  auto b = bakeShape("torus-knot", 16, 64);
  const std::vector<uint8_t> before = b->field.distance;
  auto q = FieldQuery::fromMaps(b->field.field, b->field.distance);
  ASSERT_TRUE(q.ok()) << q.error().toString();
  std::printf("maps on huge pages: %llu of %llu bytes\n", static_cast<unsigned long long>(q->hugePageBytes()),
              static_cast<unsigned long long>(q->payloadBytes()));
  EXPECT_EQ(q->hugePageBytes() % (uint64_t(2) << 20), 0u);
  EXPECT_LE(q->hugePageBytes(), q->payloadBytes());
  EXPECT_TRUE(b->field.distance == before);
  auto copy = FieldQuery::fromMaps(b->field.field, before);
  ASSERT_TRUE(copy.ok());
  Rng rng(29);
  const Vec3 c = centerOf(b->field.field);
  const float R = b->field.field.sphere.radius;
  std::vector<Ray> rays(20000);
  for (Ray& r : rays) r = Ray{add(c, mul(rng.direction(), 1.5f * R)), rng.direction()};
  std::vector<uint8_t> x(rays.size()), y(rays.size());
  q->occluded(rays, x);
  copy->occluded(rays, y);
  EXPECT_TRUE(x == y);
  EXPECT_GT(std::count(x.begin(), x.end(), 1), 1000);
  // Nothing to move in a range without a whole 2 MiB page.
  EXPECT_EQ(detail::adviseHugePages(before.data(), 4096), 0u);
}

TEST(Query, DegenerateRaysMissAndBadPlanesAreErrors) {
  auto b = bakeShape("sphere", 4, 8);
  const FieldDesc& f = b->field.field;
  const Vec3 c = centerOf(f);
  const float R = f.sphere.radius;
  const Vec3 out = add(c, Vec3{3 * R, 0, 0});
  EXPECT_FALSE(b->query.intersect(Ray{out, {0, 0, 0}}).hit);                 // zero direction
  EXPECT_FALSE(b->query.intersect(Ray{out, {NAN, 0, 0}}).hit);               // NaN
  EXPECT_FALSE(b->query.intersect(Ray{out, {1, 0, 0}}).hit);                 // pointing away
  EXPECT_FALSE(b->query.intersect(Ray{out, {0, 1, 0}}).hit);                 // passing by
  EXPECT_TRUE(b->query.intersect(Ray{out, {-1, 0, 0}}).hit);                 // straight at it
  EXPECT_FALSE(b->query.occluded(Ray{out, {-1, 0, 0}, 0.0f, 1.0f * R}));     // tmax before the sphere
  EXPECT_EQ(b->query.visibility(Ray{out, {-1, 0, 0}}), 0.0f);
  EXPECT_FALSE(FieldQuery{}.intersect(Ray{out, {-1, 0, 0}}).hit);            // empty query
  // Wrong plane sizes.
  auto bad = FieldQuery::fromMaps(f, std::span<const uint8_t>(b->field.distance).first(10));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kInvalidArgument);
  auto badNormals = FieldQuery::fromMaps(f, b->field.distance, std::span<const uint8_t>(b->field.distance).first(4));
  ASSERT_FALSE(badNormals.ok());
  EXPECT_EQ(badNormals.error().code, Code::kInvalidArgument);
}

TEST(Query, Bit1FieldsAnswerHitOrMissOnly) {
  auto b = bakeShape("torus-knot", 32, 32, false, DistanceEncoding::kBit1);
  const FieldDesc& f = b->field.field;
  const Vec3 c = centerOf(f);
  const float R = f.sphere.radius;
  Reference ref(b->mesh);
  Rng rng(17);
  int agree = 0, total = 0;
  for (int r = 0; r < 3000; ++r) {
    const Vec3 from = add(c, mul(rng.direction(), 2 * R));
    const Vec3 d = unit(sub(add(c, mul(rng.direction(), 0.7f * R)), from));
    const QueryHit h = b->query.intersect(Ray{from, d});
    ++total;
    agree += h.hit == (ref.cast(from, d) >= 0);
    if (h.hit) {
      EXPECT_NEAR(h.t, dot3(sub(h.point, from), d), 1e-3f);
    }
  }
  EXPECT_GE(double(agree) / total, 0.9);
  // From inside there is no distance to compare: never occluded, and no lookup.
  EXPECT_FALSE(b->query.occluded(Ray{c, {1, 0, 0}}));
  std::vector<Ray> rays(1000);
  for (Ray& ray : rays) ray = Ray{add(c, mul(rng.direction(), 2 * R * rng.uniform())), rng.direction()};
  EXPECT_GT(expectBatchesEqualSingleRays(b->query, rays), 50);
  EXPECT_FALSE(b->query.site(Ray{c, {1, 0, 0}}).valid);
}

TEST(Query, DefaultIntraBiasFollowsTheDocumentedFormula) {
  FieldDesc f;
  f.sphere = {{0, 0, 0}, 3.0f};
  f.mapCount = 4226;
  f.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  EXPECT_NEAR(defaultIntraBias(f), 2 * 2.0f / 254 + std::sqrt(4 * 3.14159265f / 4226), 1e-6f);
  f.distanceEncoding = DistanceEncoding::kUnorm16Diameter;
  EXPECT_NEAR(defaultIntraBias(f), 2 * 2.0f / 65534 + std::sqrt(4 * 3.14159265f / 4226), 1e-6f);
}

}  // namespace
}  // namespace vff
