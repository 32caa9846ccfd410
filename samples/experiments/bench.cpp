// bench.cpp - the query benchmark: Embree against the field on the same incoherent rays.
//
// Two ray sets, each `benchRays` rays (default 2^21), generated once:
//   ao     points uniform in a disc of radius 2 R on the plane around the object's foot, lifted
//          1e-4 R, cosine-weighted directions, tmax = aoDistance * R (the inter-object AO rays);
//   aimed  origins outside the bounding sphere (1.05 R to 3 R from its centre, uniform directions),
//          each aimed at a uniform point inside the sphere, tmax infinite.
// Measured in one run on the same threads (rays handed out in chunks of 4096; each pass timed from
// the moment all its threads run to the moment the last one ends: timedParallelFor), best of
// --repeat (the six take turns in every repetition):
//   (a) Embree rtcOccluded1 against the mesh (world space)
//   (b) FieldQuery::occluded, batch, kNearest (object space: the same rays, transformed beforehand;
//       --batch rays per call, 4096 by default)
//   (c) FieldQuery::occluded, one ray per call, kNearest
//   (d) FieldQuery::visibility, batch, kInterpolated
//   (e) Instance::occluded, batch, kNearest, on the world-space rays (as (a)): the field placed by
//       the object's rigid transform, which the batch applies to each ray (--batch rays per call)
//   (m) no query: one read of a random byte of the field's maps per ray, 64 requested at a time
//       then read (as the batch does): the memory floor of any lookup into a table this size
// and, when more than one thread runs, (a) and (b) again on one thread, (a1) and (b1), in the same
// repetitions: the ratio per core, and how each scales with the threads.
// plus the agreement of (b), (c), (d) > 0.5 and (e) with (a): the fraction of rays with the same answer,
// and each query's throughput as a share of (m) ("of floor"): how far it stands from what this
// machine's memory allows, a figure that carries across CPUs better than the ratio to Embree.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>

#include "cli.h"
#include "common.h"

namespace vffx {

namespace {

constexpr uint64_t kChunk = 4096;

// fn(x, y) for [b, e) cut into runs of at most `batch`.
template <class Fn>
void inBatches(uint64_t b, uint64_t e, uint64_t batch, Fn&& fn) {
  for (uint64_t x = b; x < e; x += batch) fn(x, std::min(e, x + batch));
}

}  // namespace

RaySet makeAoRays(const World& w, uint32_t count, float range) {
  RaySet s;
  s.name = "ao";
  s.world.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    Rng rng(i, 0, 0xb0);
    const float r = 2.0f * w.radius * std::sqrt(rng.next01()), phi = 2 * kPi * rng.next01();
    const Vec3 p{w.center.x + r * std::cos(phi), 1e-4f * w.radius, w.center.z + r * std::sin(phi)};
    const float u1 = rng.next01(), u2 = rng.next01();
    s.world[i] = {p, cosineDirection({0, 1, 0}, u1, u2), 0.0f, range * w.radius};
  }
  return s;
}

RaySet makeAimedRays(const World& w, uint32_t count) {
  RaySet s;
  s.name = "aimed";
  s.world.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    Rng rng(i, 1, 0xb1);
    const float a1 = rng.next01(), a2 = rng.next01(), dist = w.radius * (1.05f + 1.95f * rng.next01());
    const Vec3 origin = w.center + uniformSphere(a1, a2) * dist;
    const float b1 = rng.next01(), b2 = rng.next01(), rr = w.radius * std::cbrt(rng.next01());
    const Vec3 target = w.center + uniformSphere(b1, b2) * rr;
    s.world[i] = {origin, target - origin};
  }
  return s;
}

// The CPU as Linux names it ("model name", family and model from /proc/cpuinfo), or "unknown CPU".
std::string cpuName() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, name, family, model;
  // The value of the first line whose key (the text before the colon, blanks trimmed) is `key`.
  auto value = [&](const char* key, std::string* out) {
    const size_t colon = line.find(':');
    if (!out->empty() || colon == std::string::npos) return;
    const size_t keyEnd = line.find_last_not_of(" \t", colon == 0 ? 0 : colon - 1);
    if (keyEnd == std::string::npos || line.compare(0, keyEnd + 1, key) != 0) return;
    const size_t v = line.find_first_not_of(" \t", colon + 1);
    *out = v == std::string::npos ? std::string() : line.substr(v, line.find_last_not_of(" \t\r") + 1 - v);
  };
  while (std::getline(in, line)) {
    value("model name", &name);
    value("cpu family", &family);
    value("model", &model);
  }
  if (name.empty()) return "unknown CPU";
  return family.empty() ? name : name + " (family " + family + ", model " + model + ")";
}

int runBench(const Options& o) {
  FieldConfig config;
  if (auto rc = singleConfig(o, "4226x64x64", &config)) return *rc;
  const unsigned threads = resolveThreads(o.threads);
  auto setup = makeSetup(o, threads);
  if (!setup) return vff::cli::reportError(kProg, o.mesh, setup.error());
  World* world = &(*setup)->world;
  ExactTracer* exact = &*(*setup)->exact;
  vff::bake::Scene* scene = &*(*setup)->scene;
  auto field = bakeQuery(*world, *scene, config, false, threads);
  if (!field) return vff::cli::reportError(kProg, o.mesh, field.error());
  const vff::FieldQuery& q = (*field)->query;
  const vff::Instance& instance = (*field)->instance;  // q placed in the world

  std::printf("Query benchmark: %s (%zu triangles), field %s (%.2f MiB payload, %.2f MiB of it on huge pages, baked "
              "in %.2f s), %u rays per set, %u threads, best of %d, batch kernel %s, %u rays per batch call, %s\n\n",
              o.mesh.c_str(), world->worldMesh.triangleCount(), config.name().c_str(), (*field)->payloadMiB(),
              double(q.hugePageBytes()) / 1048576.0, (*field)->bakeSeconds, o.benchRays, threads, o.repeat,
              vff::batchKernelName(), o.benchBatch, cpuName().c_str());
  std::printf("| ray set | query | Mrays/s | x Embree | occluded | agreement with Embree | of floor (m) |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|\n");

  for (RaySet set : {makeAoRays(*world, o.benchRays, o.aoDistance), makeAimedRays(*world, o.benchRays)}) {
    set.object.resize(set.world.size());
    for (size_t i = 0; i < set.world.size(); ++i) {
      const vff::Ray& r = set.world[i];
      set.object[i] = {world->transform.toObjectPoint(r.origin), world->transform.toObjectVector(r.direction), r.tmin,
                       r.tmax};
    }
    const size_t n = set.world.size();
    std::vector<uint8_t> ref(n), nearest(n), single(n);
    std::vector<float> vis(n);
    // Both ray sets start off the object (on the plane, or outside the sphere): spec/geometry.md 7.4.
    const vff::QueryOptions qn{.reconstruction = vff::Reconstruction::kNearest, .origin = vff::RayOrigin::kOffObject};
    const vff::QueryOptions qi{.reconstruction = vff::Reconstruction::kInterpolated,
                               .origin = vff::RayOrigin::kOffObject};
    const std::span<const vff::Ray> rays(set.object);
    // (m): a random byte of the maps per ray.
    const std::span<const uint8_t> maps((*field)->baked.distance);
    std::vector<uint32_t> at(n);
    for (size_t i = 0; i < n; ++i)
      at[i] = uint32_t(std::min(double(Rng(uint32_t(i), 2, 0xb2).next01()) * double(maps.size()), double(maps.size() - 1)));
    std::vector<uint8_t> read(n);  // (stores into memory the threads share: the reads are kept)

    // The measurements take turns within each repetition, so that a slow spell of the machine
    // does not fall on one of them only.
    std::vector<uint8_t> placed(n);
    double ta = 1e30, tb = 1e30, tc = 1e30, td = 1e30, te = 1e30, tm = 1e30, ta1 = 1e30, tb1 = 1e30;
    auto embree = [&](unsigned t) {
      return timedParallelFor(n, kChunk, t, [&](uint64_t b, uint64_t e) {
        for (uint64_t i = b; i < e; ++i) ref[i] = exact->occluded(set.world[i]) ? 1 : 0;
      });
    };
    auto batch = [&](unsigned t) {
      return timedParallelFor(n, kChunk, t, [&](uint64_t b, uint64_t e) {
        inBatches(b, e, o.benchBatch, [&](uint64_t x, uint64_t y) {
          q.occluded(rays.subspan(x, y - x), std::span<uint8_t>(nearest).subspan(x, y - x), qn);
        });
      });
    };
    for (int rep = 0; rep < o.repeat; ++rep) {
      ta = std::min(ta, embree(threads));
      tb = std::min(tb, batch(threads));
      if (threads > 1) {
        ta1 = std::min(ta1, embree(1));
        tb1 = std::min(tb1, batch(1));
      }
      tc = std::min(tc, timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
        for (uint64_t i = b; i < e; ++i) single[i] = q.occluded(set.object[i], qn) ? 1 : 0;
      }));
      td = std::min(td, timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
        inBatches(b, e, o.benchBatch, [&](uint64_t x, uint64_t y) {
          q.visibility(rays.subspan(x, y - x), std::span<float>(vis).subspan(x, y - x), qi);
        });
      }));
      te = std::min(te, timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
        inBatches(b, e, o.benchBatch, [&](uint64_t x, uint64_t y) {
          instance.occluded(std::span<const vff::Ray>(set.world).subspan(x, y - x),
                            std::span<uint8_t>(placed).subspan(x, y - x), qn);
        });
      }));
      tm = std::min(tm, timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
        for (uint64_t g = b; g < e; g += 64) {
          const uint64_t ge = std::min(e, g + 64);
          for (uint64_t i = g; i < ge; ++i) __builtin_prefetch(maps.data() + at[i]);
          for (uint64_t i = g; i < ge; ++i) read[i] = maps[at[i]];
        }
      }));
    }

    uint64_t occA = 0, occB = 0, occC = 0, occD = 0, occE = 0, agreeB = 0, agreeC = 0, agreeD = 0, agreeE = 0;
    for (size_t i = 0; i < n; ++i) {
      const bool a = ref[i] != 0, b = nearest[i] != 0, c = single[i] != 0, d = vis[i] < 0.5f, e = placed[i] != 0;
      occA += a;
      occB += b;
      occC += c;
      occD += d;
      occE += e;
      agreeB += a == b;
      agreeC += a == c;
      agreeD += a == d;
      agreeE += a == e;
    }
    const double mr = double(n) / 1e6;
    auto row = [&](const char* query, double t, uint64_t occ, const std::string& agree) {
      std::printf("| %s | %s | %.2f | %.2f | %.1f%% | %s | %.0f%% |\n", set.name.c_str(), query, mr / t, ta / t,
                  100.0 * double(occ) / double(n), agree.c_str(), 100.0 * tm / t);
    };
    auto pct = [&](uint64_t k) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.2f%%", 100.0 * double(k) / double(n));
      return std::string(buf);
    };
    row("(a) Embree rtcOccluded1", ta, occA, "-");
    row("(b) field occluded, batch, nearest", tb, occB, pct(agreeB));
    row("(c) field occluded, single ray, nearest", tc, occC, pct(agreeC));
    row("(d) field visibility, batch, interpolated", td, occD, pct(agreeD) + " (visibility < 0.5)");
    row("(e) instance occluded, batch, nearest, world rays", te, occE, pct(agreeE));
    std::printf("| %s | (m) no query: one random read of the maps per ray | %.2f | %.2f | - | - | 100%% |\n", set.name.c_str(),
                mr / tm, ta / tm);
    if (threads > 1) {
      // (The same answers as (a) and (b): the queries are deterministic.)
      std::printf("| %s | (a1) Embree rtcOccluded1, 1 thread | %.2f | 1.00 | %.1f%% | - | - |\n", set.name.c_str(), mr / ta1,
                  100.0 * double(occA) / double(n));
      std::printf("| %s | (b1) field occluded, batch, nearest, 1 thread | %.2f | %.2f | %.1f%% | %s | - |\n", set.name.c_str(),
                  mr / tb1, ta1 / tb1, 100.0 * double(occB) / double(n), pct(agreeB).c_str());
    }
  }
  std::printf("\nTarget: (b) >= 10x (a)%s. (m) is the memory floor of any lookup into a table of this size.\n",
              threads > 1 ? " (and (b1) >= 10x (a1): one thread; their x column is against (a1))" : "");
  return vff::cli::kExitSuccess;
}

}  // namespace vffx
