// ao.cpp - inter-object ambient occlusion on the ground plane (the paper's Fig. 3).
//
// Every plane pixel casts `rays` cosine-weighted rays (default 256) up to aoDistance * R (default
// 2 R, see Options) and is shaded with the unoccluded fraction. The exact image tests them with rtcOccluded1;
// the field images with Instance::visibility, one batch call per pixel: 0 or 1 per ray for kNearest
// (the paper's answer, !occluded()), a fraction for kInterpolated. Object pixels get a constant colour, so
// only plane AO is compared. Plane points close to the object lie inside its bounding sphere and
// are answered by the intra-object test (spec/geometry.md 7.3), as a renderer using the field would.
// The distance field's images trace the same rays (hit or miss), or take the cone estimate with
// one cone of the hemisphere's 1/rays solid angle per ray.
#include "common.h"

namespace vffx {

const Vec3 kObjectFlat{0.55f, 0.60f, 0.70f};

int runAo(const Options& o) {
  ImageExperiment e;
  e.name = "ao";
  e.defaultRays = 256;
  e.defaultConfigs = {"4226x64x64", "4226x32x32", "16642x32x32"};
  e.comparePlane = true;
  const float range = o.aoDistance;
  e.makeShader = [range](const World& w, const ExactTracer& exact, const BakedQuery* field, const SdfField* sdf,
                         vff::Reconstruction r, int rays) -> std::function<Vec3(const GSample&, Rng&)> {
    const float tmax = range * w.radius, eps = 1e-4f * w.radius;
    // Plane points are not on the object: no surface of their own to skip from inside the sphere.
    const vff::QueryOptions qo{.reconstruction = r, .intraBias = 0.0f};
    const SdfTraceOptions so = sdfOptions(r == vff::Reconstruction::kInterpolated, false, hemisphereConeTan(rays));
    return [=, &exact](const GSample& s, Rng& rng) -> Vec3 {
      if (s.kind == PixelKind::kObject) return kObjectFlat;
      if (s.kind != PixelKind::kPlane) return {};
      const Vec3 origin = s.point + s.normal * eps;
      const std::span<vff::Ray> batch = rayBuffer(size_t(rays));
      for (vff::Ray& ray : batch) {
        const float u1 = rng.next01(), u2 = rng.next01();
        ray = {origin, cosineDirection(s.normal, u1, u2), 0.0f, tmax};
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
