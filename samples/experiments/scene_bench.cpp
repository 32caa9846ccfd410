// scene_bench.cpp - the scene scaling benchmark: N moving instances of one object, exact Embree
// instancing against field scenes, time per frame.
//
// For each instance count (--instances, default 1, 10, 100, 1000, 10000), N copies of the object
// (one baked field, shared) stand at random in a cube whose volume grows with N (a constant
// density: neighbours within a few R). Each of --frames frames gives every instance a new random
// rotation and position, then casts the same number of AO rays (--scene-rays), as a renderer's
// AO pass does: each from a random point of a random instance's surface (area-weighted, lifted
// 1e-3 R along the face normal), cosine-weighted around that normal, range
// aoDistance * R; every side answers occluded for each. Per frame and side, the rebuild (new
// transforms and commit) and the rays are timed separately:
//   (a) exact: Embree 3 instancing, the mesh's scene under N instance geometries; rtcOccluded1
//   (b) vff::Scene, kNearest: setTransform + commit; occluded batches of 32768 rays
//   (c) hybrid: Embree's top level over N vff::embree::FieldGeometry; rtcOccluded1
// Rays run on --threads workers (timedParallelFor); commits on the calling thread (Embree's own
// threads for (a) and (c)); a first frame, untimed, warms every side up. Each frame's rays are
// cast --repeat times by each side in turn and the best pass counts. The counts take turns too:
// every count's scenes are built first, and each frame then moves and measures every count in
// turn, so that the ratios between counts compare measurements from the same stretch of the run.
// The table gives the mean per frame, the frame speed-up of (b) and (c) over (a), and the share
// of rays on which (b) agrees with (a) and (c) with (b). Its last columns give (b)'s floor: the
// field's batch path answering exactly (b)'s (ray, instance) pairs, found beforehand (one ray at a
// time with Scene::candidates) and taken into object space as (b) takes them, timed beside the
// rest; (b)'s rays time beyond it is what finding and preparing the pairs costs.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>

#include <embree3/rtcore.h>

#include "cli.h"
#include "embree_instances.h"
#include "scene_bench.h"

namespace vffx {

namespace {

constexpr uint64_t kChunk = 4096;
// (b)'s rays per call: vff::Scene gives each instance the rays of a call that reach it, so larger
// calls fill its vectors better.
constexpr uint64_t kSceneChunk = 32768;

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

vff::RigidTransform randomPlacement(std::mt19937_64& g, float side) {
  std::uniform_real_distribution<float> u(0, 1);
  const Vec3 axis = uniformSphere(u(g), u(g));
  const float angle = 2 * kPi * u(g);
  return vff::RigidTransform::fromAxisAngle(axis, angle, {side * u(g), side * u(g), side * u(g)});
}

namespace {

// The object's mesh centred on its field's sphere s, alone in an Embree scene (what every
// instance of (a) instances), so that a placement's translation is its sphere's centre.
RTCScene centredMeshScene(RTCDevice device, const vff::bake::Mesh& m, const vff::Sphere& s) {
  RTCScene mesh = rtcNewScene(device);
  rtcSetSceneBuildQuality(mesh, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertexCount()));
  for (size_t i = 0; i < m.vertexCount(); ++i)
    for (int a = 0; a < 3; ++a) v[3 * i + size_t(a)] = m.positions[3 * i + size_t(a)] - s.center[a];
  auto* ix = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(uint32_t), m.triangleCount()));
  std::memcpy(ix, m.indices.data(), m.indices.size() * sizeof(uint32_t));
  rtcCommitGeometry(g);
  rtcAttachGeometry(mesh, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(mesh);
  return mesh;
}

}  // namespace

vff::RigidTransform fieldPlacement(const vff::RigidTransform& x, const vff::Sphere& s) {
  vff::RigidTransform f = x;
  f.translation = x.translation - x.toWorldVector(toVec(s.center));
  return f;
}

std::unique_ptr<Count> makeCount(const Bench& b, uint32_t n, RTCDevice device, RTCScene mesh) {
  auto count = std::make_unique<Count>();
  Count& k = *count;
  k.n = n;
  k.g.seed(n);
  k.side = 4.0f * b.R * std::cbrt(float(n));
  k.exact = rtcNewScene(device);
  k.hybrid = rtcNewScene(device);
  k.inst.resize(n);
  k.fields.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    k.inst[i] = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(k.inst[i], mesh);
    rtcAttachGeometryByID(k.exact, k.inst[i], i);
    const vff::RigidTransform x = fieldPlacement(randomPlacement(k.g, k.side), b.s);
    k.fields[i] = std::move(vff::embree::FieldGeometry::attach(device, k.hybrid, &b.q, x, b.qo, i).value());
    (void)k.scene.add(&b.q, x);
  }
  return count;
}

namespace {

// A frame's rays and answers, reused by every count and frame.
struct FrameRays {
  std::vector<vff::Ray> rays;
  std::vector<uint8_t> ra, rb, rc, rd;  // the answers of (a), (b), (c), and (b)'s floor per pair
  std::vector<vff::Ray> pairs;          // (b)'s pairs in object space, and each pair's ray
  std::vector<uint32_t> pairRay;
  std::vector<vff::RigidTransform> placed;
  std::vector<uint8_t> any;  // the floor's answers, combined per ray
};

// The frame's AO rays: each from a random point of a random instance's surface (area-weighted,
// lifted 1e-3 R along the face normal), cosine-weighted around that normal.
void sampleAoRays(const Bench& b, Count& k, const std::vector<vff::RigidTransform>& placement,
                  std::vector<vff::Ray>& rays) {
  const uint32_t n = k.n;
  std::uniform_real_distribution<float> u(0, 1);
  for (auto& r : rays) {
    const vff::RigidTransform& x = placement[std::min(n - 1, uint32_t(u(k.g) * float(n)))];
    const float u0 = u(k.g), u1 = u(k.g), u2 = u(k.g);
    const auto [point, normal] = b.surface.sample(u0, u1, u2);
    const Vec3 wn = x.toWorldVector(normal);
    r.origin = x.toWorldPoint(point) + wn * (1e-3f * b.R);
    const float u3 = u(k.g), u4 = u(k.g);
    r.direction = cosineDirection(wn, u3, u4);
    r.tmin = 0;
    r.tmax = b.o.aoDistance * b.R;
  }
}

// Every side's rebuild: the new transforms and the commit, timed (weight w).
int moveInstances(const Bench& b, Count& k, const std::vector<vff::RigidTransform>& placement, double w) {
  const uint32_t n = k.n;
  double t0 = now();
  for (uint32_t i = 0; i < n; ++i) setEmbreeTransform(k.inst[i], placement[i]);
  rtcCommitScene(k.exact);
  k.a.commit += w * (now() - t0);
  t0 = now();
  for (uint32_t i = 0; i < n; ++i) (void)k.scene.setTransform(i, fieldPlacement(placement[i], b.s));
  if (vff::Status st = k.scene.commit(); !st) return vff::cli::reportError(kProg, b.o.mesh, st.error());
  k.b.commit += w * (now() - t0);
  t0 = now();
  for (uint32_t i = 0; i < n; ++i) (void)k.fields[i].setTransform(fieldPlacement(placement[i], b.s));
  rtcCommitScene(k.hybrid);
  k.c.commit += w * (now() - t0);
  return 0;
}

// (b)'s (ray, instance) pairs, found one ray at a time with Scene::candidates and taken into object
// space as (b) takes them: the work of (b)'s floor.
int findPairs(const Bench& b, Count& k, const std::vector<vff::RigidTransform>& placement, FrameRays& f) {
  const uint32_t n = k.n;
  f.pairs.clear();
  f.pairRay.clear();
  f.placed.resize(n);  // each instance as the scene holds it
  for (uint32_t i = 0; i < n; ++i) f.placed[i] = fieldPlacement(placement[i], b.s);
  for (uint32_t i = 0; i < f.rays.size(); ++i) {
    auto ids = k.scene.candidates(f.rays[i]);
    if (!ids) return vff::cli::reportError(kProg, b.o.mesh, ids.error());
    for (uint32_t id : *ids) {
      const vff::RigidTransform& x = f.placed[id];
      f.pairs.push_back(vff::Ray{x.toObjectPoint(f.rays[i].origin), x.toObjectVector(f.rays[i].direction),
                                 f.rays[i].tmin, f.rays[i].tmax});
      f.pairRay.push_back(i);
    }
  }
  f.rd.resize(f.pairs.size());
  return 0;
}

// Each side's rays, best of --repeat passes taken in turn (a, b, c, a, b, c, ...), so that a
// busy moment of the machine falls on no side alone; added to the sums with weight w.
void timeRays(const Bench& b, Count& k, FrameRays& f, double w) {
  const unsigned threads = b.threads;
  const std::vector<vff::Ray>& rays = f.rays;
  double ta = 1e30, tb = 1e30, tc = 1e30, td = 1e30;
  for (int rep = 0; rep < b.o.repeat; ++rep) {
    ta = std::min(ta, timedParallelFor(rays.size(), kChunk, threads, [&](uint64_t lo, uint64_t hi) {
      for (uint64_t i = lo; i < hi; ++i) f.ra[i] = occluded1(k.exact, rays[i]);
    }));
    tb = std::min(tb, timedParallelFor(rays.size(), kSceneChunk, threads, [&](uint64_t lo, uint64_t hi) {
      (void)k.scene.occluded(std::span<const vff::Ray>(rays).subspan(lo, hi - lo),
                             std::span<uint8_t>(f.rb).subspan(lo, hi - lo), b.qo);
    }));
    tc = std::min(tc, timedParallelFor(rays.size(), kChunk, threads, [&](uint64_t lo, uint64_t hi) {
      for (uint64_t i = lo; i < hi; ++i) f.rc[i] = occluded1(k.hybrid, rays[i]);
    }));
    td = std::min(td, timedParallelFor(f.pairs.size(), kSceneChunk, threads, [&](uint64_t lo, uint64_t hi) {
      b.q.occluded(std::span<const vff::Ray>(f.pairs).subspan(lo, hi - lo), std::span<uint8_t>(f.rd).subspan(lo, hi - lo),
                   b.qo);
    }));
  }
  k.a.rays += w * ta, k.b.rays += w * tb, k.c.rays += w * tc, k.answers += w * td;
}

// How often the sides agree: (b) with (a), (c) with (b), and (b) with its floor.
void countAgreement(Count& k, FrameRays& f) {
  const size_t count = f.rays.size();
  f.any.assign(count, 0);
  for (size_t p = 0; p < f.pairs.size(); ++p) f.any[f.pairRay[p]] |= f.rd[p];
  for (size_t i = 0; i < count; ++i) {
    k.agreeAB += f.ra[i] == f.rb[i];
    k.agreeBC += f.rb[i] == f.rc[i];
    k.agreeBD += f.rb[i] == f.any[i];
  }
  k.total += count;
  k.pairs += f.pairs.size();
}

// One frame of one count: new random placements and rays, every side's rebuild and rays timed; the
// warm-up frame (frame < 0) counts nothing.
int measureFrame(const Bench& b, Count& k, int frame, FrameRays& f) {
  const double w = frame < 0 ? 0.0 : 1.0;
  std::vector<vff::RigidTransform> placement(k.n);
  for (auto& x : placement) x = randomPlacement(k.g, k.side);
  sampleAoRays(b, k, placement, f.rays);
  if (int rc = moveInstances(b, k, placement, w)) return rc;
  if (int rc = findPairs(b, k, placement, f)) return rc;
  timeRays(b, k, f, w);
  if (frame < 0) return 0;
  countAgreement(k, f);
  return 0;
}

void printHeader(const Options& o, const World& world, const FieldConfig& config, unsigned threads) {
  std::printf("Scene benchmark: %s (%zu triangles), field %s, %u AO rays per frame (range %.1f R), %d frames "
              "(rays best of %d), %u threads, %s\n\n",
              o.mesh.c_str(), world.objectMesh.triangleCount(), config.name().c_str(), o.sceneRays,
              double(o.aoDistance), o.frames, o.repeat, threads, cpuName().c_str());
  std::printf("| instances | (a) Embree rebuild ms | (a) rays ms | (b) vff::Scene rebuild ms | (b) rays ms | (c) hybrid "
              "rebuild ms | (c) rays ms | frame (a)/(b) | frame (a)/(c) | (b) = (a) | (c) = (b) | (b)'s pairs a ray | "
              "(b) field answers alone ms | = (b) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

struct Summary {
  uint32_t n;
  double speedup;        // frame (a)/(b)
  double rays, answers;  // (b)'s rays and its floor, ms a frame
};

// The table's row of every count, means per frame.
std::vector<Summary> printCounts(const std::vector<std::unique_ptr<Count>>& counts, int frames) {
  std::vector<Summary> summary;
  const double f = 1000.0 / frames;
  for (auto& count : counts) {
    Count& k = *count;
    const Side &a = k.a, &b = k.b, &c = k.c;
    std::printf("| %u | %.3f | %.2f | %.3f | %.2f | %.3f | %.2f | %.2f | %.2f | %.4f | %.4f | %.3f | %.2f | %.4f |\n",
                k.n, a.commit * f, a.rays * f, b.commit * f, b.rays * f, c.commit * f, c.rays * f,
                (a.commit + a.rays) / (b.commit + b.rays), (a.commit + a.rays) / (c.commit + c.rays),
                double(k.agreeAB) / double(k.total), double(k.agreeBC) / double(k.total),
                double(k.pairs) / double(k.total), k.answers * f, double(k.agreeBD) / double(k.total));
    summary.push_back({k.n, (a.commit + a.rays) / (b.commit + b.rays), b.rays * f, k.answers * f});
  }
  return summary;
}

// The summary: where the field scene overtakes Embree, what the scene keeps of the single object's
// speed-up, and where (b)'s time goes beyond the field's own answers.
void printSummary(const std::vector<Summary>& summary) {
  std::string faster;
  for (const Summary& r : summary)
    if (r.speedup > 1) faster += (faster.empty() ? "" : ", ") + std::to_string(r.n);
  std::printf("\nvff::Scene is faster than Embree instancing at %s instances", faster.empty() ? "no count of" : faster.c_str());
  double single = 0;
  for (const Summary& r : summary)
    if (r.n == 1) single = r.speedup;
  for (const Summary& r : summary)
    if (r.n == 1000 && single > 0)
      std::printf("; at 1000 instances its speed-up is %.2fx, %.2f of the single object's %.2fx (target 0.8)",
                  r.speedup, r.speedup / single, single);
  std::printf("\n");
  for (const Summary& r : summary)
    if (r.n == 1 || r.n == 1000)
      std::printf("%u instance%s: finding and preparing the pairs takes %.2f of (b)'s %.2f ms of rays a frame; the "
                  "field's answers alone, %.2f\n",
                  r.n, r.n == 1 ? "" : "s", r.rays - r.answers, r.rays, r.answers);
}

}  // namespace

int runSceneBench(const Options& o) {
  FieldConfig config;
  if (auto rc = singleConfig(o, "4226x64x64", &config)) return *rc;
  const unsigned threads = resolveThreads(o.threads);
  auto setup = makeSetup(o, threads);
  if (!setup) return vff::cli::reportError(kProg, o.mesh, setup.error());
  const World& world = (*setup)->world;
  auto field = bakeQuery(world, *(*setup)->scene, config, false, threads);
  if (!field) return vff::cli::reportError(kProg, o.mesh, field.error());
  const vff::FieldQuery& q = (*field)->query;
  // The object centred on its sphere, so that a placement's translation is its sphere's centre.
  const vff::Sphere& s = q.field().sphere;
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene mesh = centredMeshScene(device, world.objectMesh, s);
  const SurfaceSampler surface(world.objectMesh, s.center);
  const Bench b{o, threads, q, s, world.radius, {.reconstruction = vff::Reconstruction::kNearest}, surface};

  printHeader(o, world, config, threads);
  std::vector<std::unique_ptr<Count>> counts;
  for (uint32_t n : o.instanceCounts) counts.push_back(makeCount(b, n, device, mesh));
  FrameRays f;
  f.rays.resize(o.sceneRays);
  f.ra.resize(f.rays.size()), f.rb.resize(f.rays.size()), f.rc.resize(f.rays.size());
  // Frame by frame, every count in turn: the ratios between counts (what the scene keeps of the
  // single object's speed-up) then compare measurements taken in the same moments of the machine,
  // whose speed drifts (and not alike for every side) over a run.
  for (int frame = -1; frame < o.frames; ++frame)  // frame -1 warms up (page faults, caches)
    for (auto& count : counts)
      if (int rc = measureFrame(b, *count, frame, f)) return rc;
  const std::vector<Summary> summary = printCounts(counts, o.frames);
  printSummary(summary);
  std::fflush(stdout);
  const int rc = runRayForms(b, counts, device, mesh);
  counts.clear();
  rtcReleaseScene(mesh);
  rtcReleaseDevice(device);
  return rc;
}

}  // namespace vffx
