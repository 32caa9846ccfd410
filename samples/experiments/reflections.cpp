// reflections.cpp - glossy reflection of the object in the ground plane (the paper's Fig. 9).
//
// The plane is a glossy reflector: `rays` reflection rays per plane pixel (default 4) drawn from a
// Phong lobe (exponent 300) around the mirror direction. A ray that hits the object is shaded with
// Lambert under one directional light using the hit's normal: the exact image with Embree's hit
// and the mesh's (interpolated or geometric) normal, the field images with Instance::intersect and
// QueryHit::normal from the baked normal plane. A miss returns a constant sky colour. The plane
// pixel is 30% its own grey plus 70% the mean reflection. Object pixels get a constant colour. The
// distance field's image shades its sphere-traced hit with the distance's gradient for a normal.
#include <algorithm>
#include <cmath>

#include "common.h"

namespace vffx {

namespace {

constexpr float kGloss = 300.0f;
const Vec3 kSky{0.20f, 0.22f, 0.28f};
const Vec3 kObjectAlbedo{0.95f, 0.75f, 0.45f};
const Vec3 kPlaneGrey{0.5f, 0.5f, 0.5f};
const Vec3 kObjectFlat{0.55f, 0.60f, 0.70f};

Vec3 lambert(Vec3 n, Vec3 dir) {
  const Vec3 light = normalize({0.4f, 1.0f, 0.5f});
  if (dot(n, dir) > 0) n = n * -1.0f;  // two-sided, facing the ray
  return kObjectAlbedo * (0.15f + 0.85f * std::max(0.0f, dot(n, light)));
}

}  // namespace

int runReflections(const Options& o) {
  ImageExperiment e;
  e.name = "reflections";
  e.defaultRays = 4;
  e.defaultConfigs = {"4226x64x64", "4226x32x32"};
  e.normals = true;
  e.comparePlane = true;
  e.sdfRows = {vff::Reconstruction::kNearest};  // no cone for a hit's shading
  e.makeShader = [](const World& w, const ExactTracer& exact, const BakedQuery* field, const SdfField* sdf,
                    vff::Reconstruction r, int rays, float) -> std::function<Vec3(const GSample&, Rng&)> {
    const float eps = 1e-4f * w.radius;
    const vff::QueryOptions qo{.reconstruction = r};
    return [=, &exact](const GSample& s, Rng& rng) -> Vec3 {
      if (s.kind == PixelKind::kObject) return kObjectFlat;
      if (s.kind != PixelKind::kPlane) return {};
      const Vec3 mirror = s.viewDir - s.normal * (2.0f * dot(s.viewDir, s.normal));
      Vec3 b, c;
      orthonormalBasis(mirror, &b, &c);
      Vec3 sum{};
      for (int i = 0; i < rays; ++i) {
        const float u1 = rng.next01(), u2 = rng.next01();
        const float cosT = std::pow(u1, 1.0f / (kGloss + 1.0f)), sinT = std::sqrt(std::max(0.0f, 1 - cosT * cosT));
        Vec3 dir = b * (sinT * std::cos(2 * kPi * u2)) + c * (sinT * std::sin(2 * kPi * u2)) + mirror * cosT;
        if (dir.y <= 0) dir = mirror;
        const vff::Ray ray{s.point + s.normal * eps, dir};
        if (sdf) {
          const SdfHit h = sdf->intersect(ray);
          sum = sum + (h.hit ? lambert(h.normal, dir) : kSky);
        } else if (!field) {
          const ExactHit h = exact.intersect(ray);
          sum = sum + (h.hit ? lambert(h.normal, dir) : kSky);
        } else {
          const vff::QueryHit h = field->instance.intersect(ray, qo);
          sum = sum + (h.hit ? lambert(h.hasNormal ? h.normal : dir * -1.0f, dir) : kSky);
        }
      }
      return kPlaneGrey * 0.3f + sum * (0.7f / float(rays));
    };
  };
  return runImageExperiment(o, e);
}

}  // namespace vffx
