// ao.cpp - inter-object ambient occlusion on the ground plane (the paper's Fig. 3).
//
// Every plane pixel casts `rays` cosine-weighted rays (default 256) up to range * R for each range
// of --ao-ranges (default: --ao-distance, 2 R) and is shaded with the unoccluded fraction. The
// exact image tests them with rtcOccluded1; the field images with Scene::visibilityFrom, one batch
// call per pixel: 0 or 1 per ray for kNearest (the paper's answer), a fraction for kInterpolated.
// Object pixels get a constant colour, so only plane AO is compared, over the whole plane and
// apart over the contact region (plane points inside the bounding sphere, whose rays start inside
// it) and the rest. The rays carry their source, none (spec/geometry.md 7.4).
// The distance field's images trace the same rays (hit or miss), or take the cone estimate with
// one cone of the hemisphere's 1/rays solid angle per ray.
#include "common.h"

#include <memory>

#include "vff/scene.h"

namespace vffx {

const Vec3 kObjectFlat{0.55f, 0.60f, 0.70f};

int runAo(const Options& o) {
  ImageExperiment e;
  e.name = "ao";
  e.defaultRays = 256;
  e.defaultConfigs = {"4226x64x64", "4226x32x32", "16642x32x32"};
  e.comparePlane = true;
  e.contactRegion = true;
  e.ranges = o.aoRanges.empty() ? std::vector<float>{o.aoDistance} : o.aoRanges;
  e.makeShader = [](const World& w, const ExactTracer& exact, const BakedQuery* field, const SdfField* sdf,
                    vff::Reconstruction r, int rays, float range) -> std::function<Vec3(const GSample&, Rng&)> {
    const float tmax = range * w.radius, eps = 1e-4f * w.radius;
    // The field answers through a vff::Scene, as a renderer's would, and every ray says where it
    // starts: on no instance (the ground). Inside the sphere that is section 7.4's test, which keeps
    // the contact shadow at any range.
    std::shared_ptr<vff::Scene> scene;
    if (field) {
      scene = std::make_shared<vff::Scene>();
      if (!scene->add(&field->query, field->instance.transform) || !scene->commit()) scene.reset();
    }
    const vff::QueryOptions qo{.reconstruction = r};
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
      if (scene) {
        thread_local std::vector<uint32_t> sources;
        thread_local std::vector<float> shares;
        sources.assign(batch.size(), vff::kNoInstance);
        shares.resize(batch.size());
        (void)scene->visibilityFrom(batch, sources, shares, qo);  // (committed, sizes equal: cannot fail)
        for (float share : shares) open += share;
      } else {
        for (float share : sdf ? openShares(*sdf, so, batch) : openShares(exact, nullptr, qo, batch)) open += share;
      }
      const float v = open / float(rays);
      return {v, v, v};
    };
  };
  return runImageExperiment(o, e);
}

}  // namespace vffx
