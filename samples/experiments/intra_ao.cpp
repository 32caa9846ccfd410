// intra_ao.cpp - intra-object ambient occlusion on the object's own surface (the paper's Fig. 5).
//
// Every object pixel casts `rays` cosine-weighted rays (default 121) around its geometric normal
// from a point lifted 1e-3 R off the surface, with no range limit (self-occlusion only: the plane
// is not an occluder here). The origins are inside the bounding sphere, so the field answers with
// the intra-object test (the reversed ray from the sphere exit, spec/geometry.md 7.3). Plane pixels
// get a constant colour. The distance field skips two voxels first (sdfOptions: its self-shadow bias).
#include "common.h"

namespace vffx {

const Vec3 kPlaneFlat{0.30f, 0.30f, 0.34f};

int runIntraAo(const Options& o) {
  ImageExperiment e;
  e.name = "intra-ao";
  e.defaultRays = 121;
  e.defaultConfigs = {"16642x64x64", "4226x64x64", "4226x32x32"};
  e.comparePlane = false;
  e.compareObject = true;
  e.makeShader = [](const World& w, const ExactTracer& exact, const BakedQuery* field, const SdfField* sdf,
                    vff::Reconstruction r, int rays, float) -> std::function<Vec3(const GSample&, Rng&)> {
    const float eps = 1e-3f * w.radius;
    const vff::QueryOptions qo{.reconstruction = r};
    const SdfTraceOptions so = sdfOptions(r == vff::Reconstruction::kInterpolated, true, hemisphereConeTan(rays));
    return [=, &exact](const GSample& s, Rng& rng) -> Vec3 {
      if (s.kind == PixelKind::kPlane) return kPlaneFlat;
      if (s.kind != PixelKind::kObject) return {};
      const Vec3 origin = s.point + s.normal * eps;
      const std::span<vff::Ray> batch = rayBuffer(size_t(rays));
      for (vff::Ray& ray : batch) {
        const float u1 = rng.next01(), u2 = rng.next01();
        ray = {origin, cosineDirection(s.normal, u1, u2)};
      }
      float open = 0;
      for (float share : sdf ? openShares(*sdf, so, batch) : openShares(exact, field, qo, batch)) open += share;
      const float v = open / float(rays);
      return {v, v, v};
    };
  };
  return runImageExperiment(o, e);
}

}  // namespace vffx
