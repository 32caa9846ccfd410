// Fuzz target: everything an application reads from a file that opened: every block (zstd
// decompression included), every map, every packed slice, and the CPU query on a few rays. The
// checksums are not verified (ChecksumPolicy::kNone), so the fuzzer reaches the decoders with
// arbitrary payloads.
#include <cstdint>
#include <span>
#include <vector>

#include "vff/vff.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vff::ReadOptions o;
  o.checksums = vff::ChecksumPolicy::kNone;
  o.maxPayloadBytes = uint64_t{64} << 20;  // keep single inputs cheap
  vff::Result<vff::File> f = vff::File::openMemory(std::span<const uint8_t>(data, size), o);
  if (!f.ok()) return 0;
  for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal}) {
    const vff::PlaneInfo& pi = f->plane(p);
    if (!pi.present) continue;
    for (uint32_t b = 0; b < pi.blocks.size(); ++b) (void)f->blockData(p, b);
    for (uint32_t m = 0; m < f->field().mapCount; ++m) (void)f->mapData(p, m);
    const uint64_t slice = f->sliceBytes(p);
    if (slice > 0 && slice <= (uint64_t{16} << 20)) {
      std::vector<uint8_t> out(slice);
      for (uint32_t s = 0; s < f->layout().sliceCount && s < 4; ++s) (void)f->readSlice(p, s, out);
    }
  }
  vff::Result<vff::FieldQuery> q = vff::FieldQuery::fromFile(*f);
  if (q.ok()) {
    const vff::Sphere& s = q->field().sphere;
    const vff::Vec3 c{s.center[0], s.center[1], s.center[2]};
    const vff::Vec3 dirs[4] = {{1, 0, 0}, {0, -1, 0}, {0.3f, 0.4f, -0.866f}, {-0.6f, 0.0f, 0.8f}};
    for (const vff::Vec3& d : dirs) {
      const vff::Vec3 o2{c.x - 2 * s.radius * d.x, c.y - 2 * s.radius * d.y, c.z - 2 * s.radius * d.z};
      for (auto r : {vff::Reconstruction::kNearest, vff::Reconstruction::kInterpolated}) {
        vff::QueryOptions qo;
        qo.reconstruction = r;
        (void)q->intersect(vff::Ray{o2, d}, qo);
        (void)q->visibility(vff::Ray{c, d}, qo);
      }
    }
    // The batches (the SIMD group kernel) must answer exactly as the one-ray calls: 13 rays, a
    // partial group, from outside, from the centre and from beside the sphere.
    std::vector<vff::Ray> rays;
    for (const vff::Vec3& d : dirs) {
      rays.push_back({{c.x - 2 * s.radius * d.x, c.y - 2 * s.radius * d.y, c.z - 2 * s.radius * d.z}, d});
      rays.push_back({c, d, 0.0f, s.radius * 0.5f});
      rays.push_back({{c.x + 0.9f * s.radius * d.y, c.y - 0.9f * s.radius * d.x, c.z}, d});
    }
    rays.push_back({c, {0, 0, 0}});
    for (auto r : {vff::Reconstruction::kNearest, vff::Reconstruction::kInterpolated}) {
      vff::QueryOptions qo;
      qo.reconstruction = r;
      std::vector<vff::QueryHit> hits(rays.size());
      std::vector<uint8_t> occ(rays.size());
      std::vector<float> vis(rays.size());
      q->intersect(rays, hits, qo);
      q->occluded(rays, occ, qo);
      q->visibility(rays, vis, qo);
      for (size_t i = 0; i < rays.size(); ++i) {
        const vff::QueryHit h = q->intersect(rays[i], qo);
        const float v = q->visibility(rays[i], qo);
        if (h.hit != hits[i].hit || (h.hit && !(h.t == hits[i].t)) || (occ[i] != 0) != h.hit ||
            !(v == vis[i] || (v != v && vis[i] != vis[i])))
          __builtin_trap();
      }
    }
  }
  return 0;
}
