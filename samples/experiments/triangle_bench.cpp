// triangle_bench.cpp - time per ray against the object's triangle count: the paper's claim that a
// field's cost does not depend on the polygon count, with Embree's curve beside it.
//
// The mesh (--mesh) is first decimated (OpenMesh's quadric decimater) to --max-triangles / 4^k
// triangles, the smallest such count of at least --min-triangles, when it has more, and then
// Loop-subdivided (OpenMesh) k times, up to at least --max-triangles: the same object at four
// times the triangles per level. Each level is its own object: stood on the plane as the other experiments do, traced exactly by
// Embree (a BVH built for it) and baked into a field of the --config configuration. Two ray sets of
// --bench-rays rays each, made from the same random numbers at every level:
//   surface  AO rays from the object's own surface (area-weighted points lifted 1e-3 R along the
//            face normal, cosine-weighted around it, range aoDistance * R): the field answers them
//            with its intra-object test;
//   aimed    rays from outside the sphere (1.05 R to 3 R from its centre), each aimed at a uniform
//            point inside it, unbounded: the inter-object lookup.
// Per level and set, best of --repeat: (a) Embree rtcOccluded1, (b) Instance::occluded batches of
// --batch rays (kNearest), on the same --threads; the time per ray is the wall time over the rays.
// A third set, tiles, is what a G-buffer pass casts: the camera's view of the object on its plane
// (--bench-rays / 16 pixels), 16 AO rays a pixel from each visible point, tile by tile (4 x 4
// pixels, one sample of each per packet), each ray's source the object or none (the plane); they
// are cast in packets of 16 (rtcOccluded16) by (a16) Embree's triangles and (c16) the hybrid, the
// field as a vff::embree::FieldGeometry with RaySources::kRayId.
// The summary says how much each side's time per ray varies over the levels (largest / smallest)
// and at which levels the field is faster than Embree.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "cli.h"
#include "common.h"
#include "embree_instances.h"
#include "subdivide.h"
#include "surface_sampler.h"
#include "vff/embree.h"

namespace vffx {

namespace {

constexpr uint64_t kChunk = 4096;

struct Level {
  size_t triangles = 0;
  double buildSeconds = 0, bakeSeconds = 0;
  double exact[2] = {0, 0}, field[2] = {0, 0};  // seconds per ray, per set
  double agree[2] = {0, 0};
  double exact16 = 0, hybrid16 = 0, agree16 = 0;  // the tiles set in packets of 16, seconds per ray
};

// The tiles set (see above): rays and their RTCRay ids (0: the field's geometry; none: the plane).
struct Tiles {
  std::vector<vff::Ray> rays;
  std::vector<unsigned> ids;
};

Tiles tileRays(const World& w, const ExactTracer& exact, uint32_t count, float range, unsigned threads) {
  const int side = std::max(4, int(std::sqrt(double(count) / 16.0)) / 4 * 4);
  const GBuffer g = traceGBuffer(w, exact, side, threads);
  Tiles t;
  for (int ty = 0; ty < side; ty += 4)
    for (int tx = 0; tx < side; tx += 4)
      for (uint32_t s = 0; s < 16; ++s)
        for (int k = 0; k < 16; ++k) {
          const int x = tx + k % 4, y = ty + k / 4;
          const GSample& p = g.pixels[size_t(y) * size_t(side) + size_t(x)];
          if (p.kind != PixelKind::kObject && p.kind != PixelKind::kPlane) continue;
          Rng rng(uint32_t(y * side + x), s, 0x7d);
          const float u1 = rng.next01(), u2 = rng.next01();
          t.rays.push_back({p.point + p.normal * (1e-3f * w.radius), cosineDirection(p.normal, u1, u2), 0.0f,
                            range * w.radius});
          t.ids.push_back(p.kind == PixelKind::kObject ? 0u : RTC_INVALID_GEOMETRY_ID);
        }
  return t;
}

// The tiles set in packets of 16 through Embree's triangles and through the hybrid: seconds per
// ray (best of repeat) into l, with the share of equal answers.
void timeTiles(const Options& o, const ExactTracer& exact, const BakedQuery& field, const Tiles& t, unsigned threads,
               Level* l) {
  RTCScene hybrid = rtcNewScene(exact.device());
  {
    auto g = vff::embree::FieldGeometry::attach(exact.device(), hybrid, &field.query, field.instance.transform, {}, 0,
                                                vff::embree::RaySources::kRayId);
    rtcCommitScene(hybrid);
    std::vector<uint8_t> ra(t.rays.size()), rc(t.rays.size());
    double best[2] = {1e300, 1e300};
    for (int r = 0; r < o.repeat; ++r) {
      best[0] = std::min(best[0], timedParallelFor(t.rays.size(), kChunk, threads, [&](uint64_t lo, uint64_t hi) {
        occluded16(exact.scene(), t.rays.data(), t.ids.data(), lo, hi, ra.data());
      }));
      best[1] = std::min(best[1], timedParallelFor(t.rays.size(), kChunk, threads, [&](uint64_t lo, uint64_t hi) {
        occluded16(hybrid, t.rays.data(), t.ids.data(), lo, hi, rc.data());
      }));
    }
    uint64_t same = 0;
    for (size_t i = 0; i < t.rays.size(); ++i) same += ra[i] == rc[i];
    const double n = double(std::max<size_t>(1, t.rays.size()));
    l->exact16 = best[0] / n, l->hybrid16 = best[1] / n, l->agree16 = double(same) / n;
  }  // (the geometry detaches before its scene goes)
  rtcReleaseScene(hybrid);
}

std::vector<vff::Ray> surfaceRays(const World& w, uint32_t count, float range) {
  const float zero[3] = {0, 0, 0};
  const SurfaceSampler surface(w.worldMesh, zero);
  std::vector<vff::Ray> rays(count);
  for (uint32_t i = 0; i < count; ++i) {
    Rng rng(i, 0, 0x7b);
    const float u0 = rng.next01(), u1 = rng.next01(), u2 = rng.next01();
    const auto [p, n] = surface.sample(u0, u1, u2);
    const float u3 = rng.next01(), u4 = rng.next01();
    rays[i] = {p + n * (1e-3f * w.radius), cosineDirection(n, u3, u4), 0.0f, range * w.radius};
  }
  return rays;
}

std::vector<vff::Ray> aimedRays(const World& w, uint32_t count) {
  std::vector<vff::Ray> rays(count);
  for (uint32_t i = 0; i < count; ++i) {
    Rng rng(i, 0, 0x7c);
    const float a1 = rng.next01(), a2 = rng.next01(), a3 = rng.next01();
    const Vec3 o = w.center + uniformSphere(a1, a2) * (w.radius * (1.05f + 1.95f * a3));
    const float b1 = rng.next01(), b2 = rng.next01(), b3 = rng.next01();
    const Vec3 target = w.center + uniformSphere(b1, b2) * (w.radius * std::cbrt(b3));
    rays[i] = {o, normalize(target - o)};
  }
  return rays;
}

double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int runTriangleBench(const Options& o) {
  FieldConfig config;
  if (auto rc = singleConfig(o, "4226x64x64", &config)) return *rc;
  const unsigned threads = resolveThreads(o.threads);
  auto base = makeWorld(o.mesh);
  if (!base) return vff::cli::reportError(kProg, o.mesh, base.error());
  size_t start = o.maxTriangles;
  while (start / 4 >= o.minTriangles) start /= 4;
  std::vector<vff::bake::Mesh> meshes;
  if (base->objectMesh.triangleCount() > start) {
    uint64_t dropped = 0;
    auto coarse = decimate(base->objectMesh, start + 1, &dropped);  // a collapse removes two
    if (!coarse) return vff::cli::reportError(kProg, o.mesh, coarse.error());
    if (dropped > 0)
      std::fprintf(stderr, "%s: note: decimation left out %llu non-manifold triangles\n", kProg,
                   static_cast<unsigned long long>(dropped));
    meshes.push_back(std::move(*coarse));
  } else {
    meshes.push_back(std::move(base->objectMesh));
  }
  while (meshes.back().triangleCount() < o.maxTriangles) {
    uint64_t dropped = 0;
    auto next = loopSubdivide(meshes.back(), &dropped);
    if (!next) return vff::cli::reportError(kProg, o.mesh, next.error());
    if (dropped > 0)
      std::fprintf(stderr, "%s: note: subdivision level %zu left out %llu non-manifold triangles\n", kProg,
                   meshes.size(), static_cast<unsigned long long>(dropped));
    meshes.push_back(std::move(*next));
  }
  const vff::QueryOptions qo{.reconstruction = vff::Reconstruction::kNearest};
  std::printf("Triangle benchmark: %s at %zu to %zu triangles, field %s, %u rays per set, batches of %u, "
              "%u threads, best of %d, %s\n\n",
              o.mesh.c_str(), meshes.front().triangleCount(), meshes.back().triangleCount(), config.name().c_str(), o.benchRays, o.benchBatch, threads,
              o.repeat, cpuName().c_str());
  std::printf("| triangles | Embree build ms | bake s | surface (a) Embree ns/ray | surface (b) field ns/ray | surface "
              "(a)/(b) | aimed (a) Embree ns/ray | aimed (b) field ns/ray | aimed (a)/(b) | (b) = (a) surface | (b) = "
              "(a) aimed | tiles (a16) Embree packets ns/ray | tiles (c16) hybrid packets ns/ray | tiles (a16)/(c16) | "
              "(c16) = (a16) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<Level> levels;
  for (vff::bake::Mesh& mesh : meshes) {
    Level l;
    l.triangles = mesh.triangleCount();
    const World w = makeWorld(std::move(mesh));
    double t0 = seconds();
    auto exact = ExactTracer::create(w.worldMesh);
    if (!exact) return vff::cli::reportError(kProg, o.mesh, exact.error());
    l.buildSeconds = seconds() - t0;
    auto scene = vff::bake::Scene::create(w.objectMesh, threads);
    if (!scene) return vff::cli::reportError(kProg, o.mesh, scene.error());
    auto field = bakeQuery(w, *scene, config, false, threads);
    if (!field) return vff::cli::reportError(kProg, o.mesh, field.error());
    l.bakeSeconds = (*field)->bakeSeconds;
    const std::vector<vff::Ray> sets[2] = {surfaceRays(w, o.benchRays, o.aoDistance), aimedRays(w, o.benchRays)};
    for (int k = 0; k < 2; ++k) {
      const std::vector<vff::Ray>& rays = sets[k];
      std::vector<uint8_t> ra(rays.size()), rb(rays.size());
      double best[2] = {1e300, 1e300};
      for (int r = 0; r < o.repeat; ++r) {
        best[0] = std::min(best[0], timedParallelFor(rays.size(), kChunk, threads, [&](uint64_t lo, uint64_t hi) {
          for (uint64_t i = lo; i < hi; ++i) ra[i] = exact->occluded(rays[i]);
        }));
        best[1] = std::min(best[1], timedParallelFor(rays.size(), o.benchBatch, threads, [&](uint64_t lo, uint64_t hi) {
          (*field)->instance.occluded(std::span<const vff::Ray>(rays).subspan(lo, hi - lo),
                                      std::span<uint8_t>(rb).subspan(lo, hi - lo), qo);
        }));
      }
      uint64_t same = 0;
      for (size_t i = 0; i < rays.size(); ++i) same += ra[i] == rb[i];
      l.exact[k] = best[0] / double(rays.size());
      l.field[k] = best[1] / double(rays.size());
      l.agree[k] = double(same) / double(rays.size());
    }
    timeTiles(o, *exact, **field, tileRays(w, *exact, o.benchRays, o.aoDistance, threads), threads, &l);
    std::printf("| %zu | %.1f | %.2f | %.1f | %.1f | %.2f | %.1f | %.1f | %.2f | %.4f | %.4f | %.1f | %.1f | %.2f | %.4f |\n",
                l.triangles, l.buildSeconds * 1e3, l.bakeSeconds, l.exact[0] * 1e9, l.field[0] * 1e9,
                l.exact[0] / l.field[0], l.exact[1] * 1e9, l.field[1] * 1e9, l.exact[1] / l.field[1], l.agree[0],
                l.agree[1], l.exact16 * 1e9, l.hybrid16 * 1e9, l.exact16 / l.hybrid16, l.agree16);
    std::fflush(stdout);
    levels.push_back(l);
  }
  std::printf("\n");
  const char* names[2] = {"surface", "aimed"};
  for (int k = 0; k < 2; ++k) {
    double fmin = 1e300, fmax = 0, emin = 1e300, emax = 0;
    std::string faster;
    for (const Level& l : levels) {
      fmin = std::min(fmin, l.field[k]);
      fmax = std::max(fmax, l.field[k]);
      emin = std::min(emin, l.exact[k]);
      emax = std::max(emax, l.exact[k]);
      if (l.exact[k] > l.field[k]) faster += (faster.empty() ? "" : ", ") + std::to_string(l.triangles);
    }
    const Level& last = levels.back();
    std::printf("%s rays: field time per ray varies %.2fx from %zu to %zu triangles (target < 1.5x), Embree's %.2fx; "
                "the field is faster at %s; at %zu triangles it is %.2fx Embree's speed\n",
                names[k], fmax / fmin, levels.front().triangles, last.triangles, emax / emin,
                faster.empty() ? "no level" : (faster + " triangles").c_str(), last.triangles,
                last.exact[k] / last.field[k]);
  }
  std::printf("tiles, packets of 16: the hybrid runs at %.2fx Embree's triangles at %zu triangles and %.2fx at %zu "
              "(targets: 1.0x at the mesh's own count, 3x at 1M)\n",
              levels.front().exact16 / levels.front().hybrid16, levels.front().triangles,
              levels.back().exact16 / levels.back().hybrid16, levels.back().triangles);
  return 0;
}

}  // namespace vffx
