// The WGSL translation of the Vulkan query kernel (gpu/wgsl/kernels/vff_vk_query*.wgsl, generated
// from gpu/vulkan/shaders/vff_vk_query.comp by web/tools/gen-wgsl.mjs) run through WebGPU in
// headless Chromium (wgsl_runner.h), against the CPU query ray by ray.
//
// The cases, rays, comparisons and tolerances are the Vulkan suite's (test_vk_query.cpp; shared in
// field_cases.h and nearest_check.h): kNearest on the baked fields (nearestCases) and the valid
// conformance vectors, normals and kInterpolated on interpolatedCases. A Chromium launch costs
// more than a field's rays, so each test runs every field of one kernel variant (2D array, 3D,
// BC4), or every conformance vector, in one runner call, each field's answers then checked as the
// Vulkan suite checks one case (SCOPED_TRACE names the field). A variant whose kernel is not generated yet, or where
// node, web/node_modules, chromium or a WebGPU adapter is missing (or the adapter does not decode BC4), skips and says
// why.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "baked_fields.h"
#include "field_cases.h"
#include "nearest_check.h"
#include "vff/vff.h"
#include "wgsl_runner.h"

namespace vff {
namespace wgsltest {
// The parameter in test listings (gtest finds PrintTo in the type's namespace).
void PrintTo(Kernel k, std::ostream* os) {
  *os << kernelName(k);
}
}  // namespace wgsltest

namespace {

using gputest::caseName;
using gputest::FieldCase;
using wgsltest::Kernel;
using wgsltest::QueryAnswer;
using wgsltest::QueryRay;

const char* variantName(Kernel k) {
  return k == Kernel::kQuery3D ? "Texture3D" : k == Kernel::kQueryBc4 ? "Bc4" : "Array2D";
}

std::string kernelParamName(const ::testing::TestParamInfo<Kernel>& i) {
  return variantName(i.param);
}

Kernel kernelOf(const FieldCase& c) {
  if (c.encoding == DistanceEncoding::kBc4Diameter) return Kernel::kQueryBc4;
  return c.target == LayoutTarget::kTexture3D ? Kernel::kQuery3D : Kernel::kQuery2D;
}

#define VFF_REQUIRE_WGSL(kernel)                                                                     \
  do {                                                                                               \
    if (std::string why = ::vff::wgsltest::environmentSkip(); !why.empty()) GTEST_SKIP() << why;     \
    if (!std::filesystem::exists(::vff::wgsltest::kernelPath(kernel)))                               \
      GTEST_SKIP() << ::vff::wgsltest::kernelPath(kernel) << " is not generated yet (gen-wgsl.mjs)"; \
  } while (0)

// A field of the job: its file, CPU query, rays and the run that answers them.
struct Entry {
  std::string label;
  File file;
  FieldQuery cpu;
  std::vector<QueryRay> rays;
  size_t run = 0;
};

// Adds the field's run to the job; ADD_FAILUREs and returns false on a setup failure.
bool addEntry(wgsltest::Job& job, std::vector<Entry>& entries, std::string label, Result<File> file,
              std::vector<QueryRay> (*makeRays)(const FieldDesc&, uint32_t, uint64_t), uint32_t count, uint64_t seed) {
  EXPECT_TRUE(file.ok()) << label << ": " << file.error().toString();
  if (!file) return false;
  auto cpu = FieldQuery::fromFile(*file);
  EXPECT_TRUE(cpu.ok()) << label << ": " << cpu.error().toString();
  if (!cpu) return false;
  std::vector<QueryRay> rays = makeRays(file->field(), count, seed);
  auto run = job.addQuery(*file, rays);
  EXPECT_TRUE(run.ok()) << label << ": " << run.error().toString();
  if (!run) return false;
  entries.push_back({std::move(label), std::move(*file), std::move(*cpu), std::move(rays), *run});
  return true;
}

// Runs the job: true when it ran; sets *skip where the runner could not (its reason).
bool runJob(wgsltest::Job& job, std::string* skip) {
  const wgsltest::Outcome o = job.run();
  if (o.skipped) *skip = o.message;
  EXPECT_TRUE(o.ok || o.skipped) << o.message;
  return o.ok;
}

#define VFF_RUN_JOB(job)                         \
  do {                                           \
    std::string skip_;                           \
    if (!runJob(job, &skip_)) {                  \
      if (!skip_.empty()) GTEST_SKIP() << skip_; \
      return;                                    \
    }                                            \
  } while (0)

// ---- Baked fields, kNearest ---------------------------------------------------------------------------

class WgslQuery : public ::testing::TestWithParam<Kernel> {};

TEST_P(WgslQuery, MatchesCpuNearest) {
  VFF_REQUIRE_WGSL(GetParam());
  wgsltest::Job job(std::string("nearest-") + variantName(GetParam()));
  std::vector<Entry> entries;
  for (const FieldCase& c : gputest::nearestCases()) {
    if (kernelOf(c) != GetParam()) continue;
    auto file = gputest::bakeFile(c, false);
    if (file) {
      EXPECT_GT(file->layout().sliceCount, 1u) << caseName(c);
    }
    if (!addEntry(job, entries, caseName(c), std::move(file), gputest::nearestRays<QueryRay>, 8192, 1234)) return;
  }
  ASSERT_FALSE(entries.empty());
  VFF_RUN_JOB(job);
  for (const Entry& e : entries) {
    SCOPED_TRACE(e.label);
    const gputest::Agreement a = gputest::compareNearestAnswers(e.file, e.cpu, e.rays, job.answers<QueryAnswer>(e.run),
                                                                "[ wgsl ] " + e.label + ": kNearest", e.label);
    gputest::expectBakedAgreement(a, e.label);
  }
}

INSTANTIATE_TEST_SUITE_P(Fields, WgslQuery, ::testing::Values(Kernel::kQuery2D, Kernel::kQuery3D, Kernel::kQueryBc4),
                         kernelParamName);

// ---- Conformance vectors, kNearest -------------------------------------------------------------------

// Every vector in one runner call (a few of them need the 3D or BC4 kernel): one Chromium for all.
TEST(WgslConformance, MatchesCpuNearest) {
  for (Kernel k : {Kernel::kQuery2D, Kernel::kQuery3D, Kernel::kQueryBc4}) VFF_REQUIRE_WGSL(k);
  wgsltest::Job job("conformance");
  std::vector<Entry> entries;
  for (const std::string& stem : gputest::validVectors())
    if (!addEntry(job, entries, stem, File::open(gputest::vectorPath(stem)), gputest::nearestRays<QueryRay>, 4096, 99))
      return;
  ASSERT_FALSE(entries.empty());
  VFF_RUN_JOB(job);
  for (const Entry& e : entries) {
    SCOPED_TRACE(e.label);
    gputest::compareNearestAnswers(
        e.file, e.cpu, e.rays, job.answers<QueryAnswer>(e.run),
        "[ wgsl ] " + e.label + " (" + variantName(wgsltest::queryKernel(e.file)) + "): kNearest", e.label);
  }
}

// ---- Normals and kInterpolated ----------------------------------------------------------------------

class WgslField : public ::testing::TestWithParam<Kernel> {};

TEST_P(WgslField, NormalsAndInterpolatedMatchCpu) {
  VFF_REQUIRE_WGSL(GetParam());
  wgsltest::Job job(std::string("interpolated-") + variantName(GetParam()));
  std::vector<Entry> entries;
  for (const FieldCase& c : gputest::interpolatedCases()) {
    if (kernelOf(c) != GetParam()) continue;
    auto file = gputest::bakeFile(c, true);
    if (file) {
      EXPECT_TRUE(file->hasNormals()) << caseName(c);
    }
    if (!addEntry(job, entries, caseName(c), std::move(file), gputest::interpolatedRays<QueryRay>, 8192, 77)) return;
  }
  ASSERT_FALSE(entries.empty());
  VFF_RUN_JOB(job);
  for (const Entry& e : entries) {
    SCOPED_TRACE(e.label);
    const std::vector<QueryAnswer> out = job.answers<QueryAnswer>(e.run);
    ASSERT_EQ(out.size(), e.rays.size());
    gputest::InterpCounts n;
    for (size_t r = 0; r < e.rays.size(); ++r)
      gputest::compareInterpolated(e.cpu, e.rays[r], out[r], e.file.field().sphere.radius, r, n);
    gputest::reportInterpolated(n, "[ wgsl ] " + e.label, e.label);
  }
}

// interpolatedCases has no bc4-diameter field.
INSTANTIATE_TEST_SUITE_P(Fields, WgslField, ::testing::Values(Kernel::kQuery2D, Kernel::kQuery3D), kernelParamName);

}  // namespace
}  // namespace vff
