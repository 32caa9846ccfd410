// Refined fields (vff/refine.h, spec/format.md section 14, spec/geometry.md section 7.5): the REFN
// section written, read and checked; the exact step against Embree; kRefined's answers against
// Embree and kNearest's; batches against the one-ray functions; the marking's determinism.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/baked_shape.h"
#include "common/rng.h"
#include "common/vec3.h"
#include "vff/bake/embree_reference.h"
#include "vff/refine.h"
#include "vff/vff.h"

namespace vff {
namespace {

using test::BakedShape;
using test::Rng;
using test::add;
using test::centerOf;
using test::mul;
using test::sub;

const BakedShape& shape(const std::string& name) {
  static std::map<std::string, std::unique_ptr<BakedShape>> baked;
  std::unique_ptr<BakedShape>& b = baked[name];
  if (!b) b = test::bakeShape(name, 8, 16);
  return *b;
}

Refinement refinementOf(const BakedShape& b, RefineOptions o = {}) {
  auto r = makeRefinement(b.field.field, b.field.distance, b.mesh.positions, b.mesh.indices, o);
  EXPECT_TRUE(r.ok()) << r.error().toString();
  return r.ok() ? std::move(*r) : Refinement{};
}

// Rays from outside the sphere aimed at points inside it (bench's aimed set).
std::vector<Ray> aimedRays(const FieldDesc& f, uint32_t n, uint64_t seed) {
  Rng rng(seed);
  const Vec3 c = centerOf(f);
  const float R = f.sphere.radius;
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    const Vec3 from = add(c, mul(rng.direction(), R * rng.uniform(1.05f, 3.0f)));
    const Vec3 to = add(c, mul(rng.direction(), R * std::cbrt(rng.uniform())));
    r = {from, sub(to, from), 0.0f, INFINITY};
  }
  return rays;
}

QueryOptions refinedOptions() {
  QueryOptions o;
  o.reconstruction = Reconstruction::kRefined;
  o.origin = RayOrigin::kOffObject;
  return o;
}

TEST(Refine, SectionRoundTripsAndSetsVersion13) {
  const BakedShape& b = shape("torus-knot");
  const Refinement r = refinementOf(b);
  ASSERT_GT(r.unsureTexels, 0u);
  WriteOptions wo;
  wo.refinement = r.view();
  auto bytes = writeMemory(b.field.field, b.field.distance, {}, wo);
  ASSERT_TRUE(bytes.ok()) << bytes.error().toString();
  auto file = File::openMemory(*bytes);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_EQ(file->info().versionMinor, 3);
  const RefinementView& v = file->refinement();
  ASSERT_FALSE(v.empty());
  EXPECT_EQ(v.margin, r.margin);
  EXPECT_EQ(v.unsureTexels, r.unsureTexels);
  EXPECT_TRUE(std::equal(v.unsure.begin(), v.unsure.end(), r.unsure.begin(), r.unsure.end()));
  EXPECT_TRUE(std::equal(v.positions.begin(), v.positions.end(), r.positions.begin(), r.positions.end()));
  EXPECT_TRUE(std::equal(v.indices.begin(), v.indices.end(), r.indices.begin(), r.indices.end()));
  auto q = FieldQuery::fromFile(*file);
  ASSERT_TRUE(q.ok());
  EXPECT_TRUE(q->refined());
  EXPECT_GT(q->refinementBytes(), r.positions.size() * 4);
  EXPECT_TRUE(validate(*bytes).valid());
  // Without a refinement: the same bytes as before REFN existed (no section, version 1.0).
  auto plain = writeMemory(b.field.field, b.field.distance);
  ASSERT_TRUE(plain.ok());
  auto pf = File::openMemory(*plain);
  ASSERT_TRUE(pf.ok());
  EXPECT_EQ(pf->info().versionMinor, 0);
  EXPECT_TRUE(pf->refinement().empty());
  EXPECT_EQ(pf->info().sections.size() + 1, file->info().sections.size());
}

// Each mutant of the REFN section fails to open with the rule the spec gives it.
TEST(Refine, BrokenSectionsFailWithTheirRule) {
  const BakedShape& b = shape("box");
  const Refinement good = refinementOf(b);
  struct Case {
    const char* what;
    Code code;
    void (*mutate)(Refinement*);
  };
  const Case cases[] = {
      {"index out of range", Code::kRefineMesh, [](Refinement* r) { r->indices[4] = uint32_t(r->positions.size()); }},
      {"vertex outside the sphere", Code::kRefineMesh, [](Refinement* r) { r->positions[0] = 1e6f; }},
      {"unsureTexels wrong", Code::kRefineUnsure, [](Refinement* r) { r->unsureTexels += 1; }},
      {"negative margin", Code::kRefineHeader, [](Refinement* r) { r->margin = -1.0f; }},
  };
  for (const Case& c : cases) {
    Refinement r = good;
    c.mutate(&r);
    // The writer refuses it as an argument...
    WriteOptions wo;
    wo.refinement = r.view();
    auto refused = writeMemory(b.field.field, b.field.distance, {}, wo);
    ASSERT_FALSE(refused.ok()) << c.what;
    EXPECT_EQ(refused.error().code, Code::kInvalidArgument) << c.what;
    // ... and a file that holds it anyway fails with the rule: written good, patched in place.
    wo.refinement = good.view();
    auto bytes = writeMemory(b.field.field, b.field.distance, {}, wo);
    ASSERT_TRUE(bytes.ok());
    auto file = File::openMemory(*bytes);
    ASSERT_TRUE(file.ok());
    const SectionInfo* s = nullptr;
    for (const SectionInfo& x : file->info().sections)
      if (x.tag == kTagRefinement) s = &x;
    ASSERT_NE(s, nullptr);
    ASSERT_EQ(s->codec, Codec::kStored);
    std::vector<uint8_t> patched = *bytes;
    uint8_t* sec = patched.data() + s->offset;
    const uint64_t bits = (uint64_t(b.field.field.mapCount) * 16 * 16 + 7) / 8;
    const uint64_t posAt = 64 + ((bits + 3) & ~uint64_t(3)), idxAt = posAt + 4 * r.positions.size();
    std::memcpy(sec + 12, &r.margin, 4);
    std::memcpy(sec + 16, &r.unsureTexels, 4);
    std::memcpy(sec + posAt, r.positions.data(), 4 * r.positions.size());
    std::memcpy(sec + idxAt, r.indices.data(), 4 * r.indices.size());
    ReadOptions ro;
    ro.checksums = ChecksumPolicy::kNone;
    auto broken = File::openMemory(patched, ro);
    ASSERT_FALSE(broken.ok()) << c.what;
    EXPECT_EQ(broken.error().code, c.code) << c.what << ": " << broken.error().toString();
    EXPECT_EQ(broken.error().section, kTagRefinement) << c.what;
  }
}

TEST(Refine, MakeRefinementRefusesBadInput) {
  const BakedShape& b = shape("box");
  std::vector<uint32_t> bad = b.mesh.indices;
  bad[0] = 1u << 30;
  auto r = makeRefinement(b.field.field, b.field.distance, b.mesh.positions, bad);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, Code::kInvalidArgument);
  auto shortMaps = makeRefinement(b.field.field, std::span(b.field.distance).first(10), b.mesh.positions, b.mesh.indices);
  ASSERT_FALSE(shortMaps.ok());
  EXPECT_EQ(shortMaps.error().code, Code::kInvalidArgument);
}

// With every texel unsure, kRefined is the exact step alone: Embree's answers.
TEST(Refine, ExactStepMatchesEmbree) {
  const BakedShape& b = shape("torus-knot");
  Refinement all = refinementOf(b);
  std::fill(all.unsure.begin(), all.unsure.end(), uint8_t(0xFF));
  const uint64_t texels = uint64_t(b.field.field.mapCount) * 16 * 16;
  if (texels % 8) all.unsure.back() = uint8_t((1u << (texels % 8)) - 1);
  all.unsureTexels = uint32_t(texels);
  auto q = FieldQuery::fromMaps(b.field.field, b.field.distance, {}, all.view());
  ASSERT_TRUE(q.ok()) << q.error().toString();
  const bake::EmbreeReference ref(b.mesh);
  const std::vector<Ray> rays = aimedRays(b.field.field, 20000, 7);
  uint32_t differ = 0, hits = 0;
  for (const Ray& r : rays) {
    const QueryHit h = q->intersect(r, refinedOptions());
    Vec3 ng;
    const float t = ref.cast(r.origin, r.direction, &ng);
    if (h.hit != (t >= 0)) {
      ++differ;
      continue;
    }
    if (!h.hit) continue;
    ++hits;
    // (A ray through an edge may pass between its two triangles in one tracer and not the other.)
    if (std::fabs(h.t - t) > 1e-4f * b.field.field.sphere.radius) ++differ;
    EXPECT_EQ(q->occluded(r, refinedOptions()), true);
  }
  EXPECT_GT(hits, 3000u);
  EXPECT_LE(differ, 3u);
}

// kRefined against Embree, where kNearest is wrong on about 1 ray in 20: the refined field is
// wrong far less often, and its batches give the one-ray answers bit for bit.
TEST(Refine, RefinedAnswersAgreeWithEmbree) {
  for (const char* name : {"torus-knot", "bowl", "box"}) {
    const BakedShape& b = shape(name);
    const Refinement r = refinementOf(b);
    auto q = FieldQuery::fromMaps(b.field.field, b.field.distance, {}, r.view());
    ASSERT_TRUE(q.ok());
    const bake::EmbreeReference ref(b.mesh);
    const std::vector<Ray> rays = aimedRays(b.field.field, 20000, 11);
    std::vector<uint8_t> batch(rays.size());
    q->occluded(rays, batch, refinedOptions());
    std::vector<QueryHit> hits(rays.size());
    q->intersect(rays, hits, refinedOptions());
    QueryOptions nearest = refinedOptions();
    nearest.reconstruction = Reconstruction::kNearest;
    uint32_t wrongRefined = 0, wrongNearest = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const bool exact = ref.occluded(rays[i].origin, rays[i].direction, 0, INFINITY);
      const QueryHit one = q->intersect(rays[i], refinedOptions());
      ASSERT_EQ(batch[i] != 0, one.hit) << name << " ray " << i;
      ASSERT_EQ(hits[i].hit, one.hit) << name << " ray " << i;
      if (one.hit) ASSERT_EQ(hits[i].t, one.t) << name << " ray " << i;
      wrongRefined += one.hit != exact;
      wrongNearest += q->occluded(rays[i], nearest) != exact;
    }
    std::printf("%s: wrong answers of 20000 aimed rays: refined %u, nearest %u; unsure texels %u\n", name,
                wrongRefined, wrongNearest, r.unsureTexels);
    EXPECT_GT(wrongNearest, 200u) << name;
    EXPECT_LE(wrongRefined * 20, wrongNearest) << name;
  }
}

// The same bits whatever the thread count, with and without probes; probes mark fewer texels.
TEST(Refine, MarkingIsDeterministic) {
  const BakedShape& b = shape("torus-knot");
  const Refinement one = refinementOf(b, {.threads = 1});
  const Refinement two = refinementOf(b, {.threads = 2});
  EXPECT_EQ(one.unsure, two.unsure);
  const Refinement p1 = refinementOf(b, {.probe = true, .threads = 1});
  const Refinement p2 = refinementOf(b, {.probe = true, .threads = 2});
  EXPECT_EQ(p1.unsure, p2.unsure);
  EXPECT_LT(p1.unsureTexels, one.unsureTexels);
  EXPECT_GT(p1.unsureTexels, 0u);
}

// A field without a refinement answers kRefined as kNearest.
TEST(Refine, UnrefinedFieldAnswersAsNearest) {
  const BakedShape& b = shape("bowl");
  EXPECT_FALSE(b.query.refined());
  EXPECT_EQ(b.query.refinementBytes(), 0u);
  QueryOptions nearest = refinedOptions();
  nearest.reconstruction = Reconstruction::kNearest;
  for (const Ray& r : aimedRays(b.field.field, 2000, 3)) {
    const QueryHit a = b.query.intersect(r, refinedOptions()), n = b.query.intersect(r, nearest);
    ASSERT_EQ(a.hit, n.hit);
    if (a.hit) ASSERT_EQ(a.t, n.t);
  }
}

}  // namespace
}  // namespace vff
