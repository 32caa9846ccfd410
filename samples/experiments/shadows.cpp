// shadows.cpp - soft shadows from three spherical area lights (the paper's Figs. 7-8).
//
// Three coloured spherical lights (radius 0.35 R) above the object; `rays` shadow rays per pixel
// (default 20) split across the lights in turn. Each ray goes from the shaded point (lifted 1e-3 R)
// to a uniform point on the light's sphere, with direction = target - origin and tmax = 1. The
// shading is Lambert toward the light's centre times the unoccluded fraction, on the plane and on
// the object; both are compared. Rays from the object start inside the bounding sphere (the
// field's intra-object path, spec/geometry.md 7.3); most rays from the plane start outside
// (inter-object path), those near the object inside it but off it (section 7.4). The
// distance field traces the same rays (hit or miss), or takes the cone estimate of each: a cone
// from the shaded point that covers the light's disc (distance-field shadows).
#include <algorithm>

#include "common.h"

namespace vffx {

namespace {

struct Light {
  Vec3 offset;  // from the object's centre, in multiples of R
  Vec3 colour;
};
const Light kLights[3] = {{{2.2f, 3.0f, 1.2f}, {0.55f, 0.45f, 0.35f}},
                          {{-2.0f, 3.4f, 1.6f}, {0.30f, 0.38f, 0.55f}},
                          {{0.4f, 2.8f, -2.4f}, {0.35f, 0.45f, 0.30f}}};
constexpr float kLightRadius = 0.35f;
const Vec3 kAmbient{0.06f, 0.06f, 0.07f};

}  // namespace

int runShadows(const Options& o) {
  ImageExperiment e;
  e.name = "shadows";
  e.defaultRays = 20;
  e.defaultConfigs = {"4226x64x64", "16642x32x32"};
  e.comparePlane = true;
  e.compareObject = true;
  e.makeShader = [](const World& w, const ExactTracer& exact, const BakedQuery* field, const SdfField* sdf,
                    vff::Reconstruction r, int rays, float) -> std::function<Vec3(const GSample&, Rng&)> {
    const float eps = 1e-3f * w.radius;
    return [=, &exact](const GSample& s, Rng& rng) -> Vec3 {
      if (s.kind == PixelKind::kBackground) return {};
      // Plane points are on no object (spec/geometry.md 7.4); object points on it (7.3, default bias).
      const vff::QueryOptions qo{.reconstruction = r,
                                 .origin = s.kind == PixelKind::kPlane ? vff::RayOrigin::kOffObject
                                                                       : vff::RayOrigin::kOnObject};
      const SdfTraceOptions so = sdfOptions(r == vff::Reconstruction::kInterpolated, s.kind == PixelKind::kObject, 0.0f,
                                            kLightRadius * w.radius);
      const Vec3 albedo = s.kind == PixelKind::kPlane ? Vec3{0.85f, 0.85f, 0.85f} : Vec3{0.9f, 0.85f, 0.75f};
      const Vec3 origin = s.point + s.normal * eps;
      const std::span<vff::Ray> batch = rayBuffer(size_t(rays));
      for (int i = 0; i < rays; ++i) {
        const Vec3 c = w.center + kLights[i % 3].offset * w.radius;
        const float u1 = rng.next01(), u2 = rng.next01();
        const Vec3 target = c + uniformSphere(u1, u2) * (kLightRadius * w.radius);
        batch[size_t(i)] = {origin, target - origin, 0.0f, 1.0f};
      }
      const std::span<const float> shares = sdf ? openShares(*sdf, so, batch) : openShares(exact, field, qo, batch);
      float open[3] = {0, 0, 0};
      int count[3] = {0, 0, 0};
      for (int i = 0; i < rays; ++i) {
        ++count[i % 3];
        open[i % 3] += shares[size_t(i)];
      }
      Vec3 sum = kAmbient;
      for (int l = 0; l < 3; ++l) {
        if (!count[l]) continue;
        const Vec3 L = normalize(w.center + kLights[l].offset * w.radius - s.point);
        sum = sum + kLights[l].colour * (std::max(0.0f, dot(s.shadingNormal, L)) * open[l] / float(count[l]));
      }
      return mul(albedo, sum);
    };
  };
  return runImageExperiment(o, e);
}

}  // namespace vffx
