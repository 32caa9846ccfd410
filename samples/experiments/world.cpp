// world.cpp - the scene: the object standing on the ground plane y = 0, the camera looking at it
// from above at an angle, and the primary hits (G-buffer).
#include <algorithm>
#include <chrono>
#include <limits>

#include "common.h"
#include "vff/bake/sphere.h"

namespace vffx {

namespace {

// Camera placement: azimuth and elevation of the eye around the object's centre, its distance in
// multiples of R, and the vertical field of view. From 35 degrees up with a 40 degree field the top
// of the image still looks down at the plane, so there is no horizon.
constexpr float kAzimuthDeg = 35.0f, kElevationDeg = 35.0f, kDistanceR = 4.2f, kFovDeg = 40.0f;

}  // namespace

Vec3 Camera::rayDirection(float px, float py, int width, int height) const {
  const float sx = 2.0f * px / float(width) - 1.0f, sy = 1.0f - 2.0f * py / float(height);
  return normalize(forward + right * sx + up * sy);
}

vff::Result<World> makeWorld(const std::string& meshPath) {
  auto mesh = vff::bake::loadMesh(meshPath);
  if (!mesh) return std::move(mesh).error();
  return makeWorld(std::move(*mesh));
}

World makeWorld(vff::bake::Mesh mesh) {
  World w;
  w.objectMesh = std::move(mesh);
  w.objectSphere = vff::bake::minimalEnclosingSphere(w.objectMesh.positions);
  float minY = std::numeric_limits<float>::infinity();
  for (size_t i = 1; i < w.objectMesh.positions.size(); i += 3) minY = std::min(minY, w.objectMesh.positions[i]);
  // Stand the object on the plane, its sphere centre above the origin.
  w.transform.translation = {-w.objectSphere.center[0], -minY, -w.objectSphere.center[2]};
  w.worldMesh = w.objectMesh;
  for (size_t i = 0; i < w.worldMesh.positions.size(); i += 3) {
    const Vec3 p = w.transform.toWorldPoint(toVec(&w.worldMesh.positions[i]));
    w.worldMesh.positions[i] = p.x;
    w.worldMesh.positions[i + 1] = p.y;
    w.worldMesh.positions[i + 2] = p.z;
  }
  w.center = w.transform.toWorldPoint(toVec(w.objectSphere.center));
  w.radius = w.objectSphere.radius;

  const float az = kAzimuthDeg * kPi / 180, el = kElevationDeg * kPi / 180;
  const Vec3 toEye{std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az)};
  Camera& c = w.camera;
  c.eye = w.center + toEye * (kDistanceR * w.radius);
  c.forward = toEye * -1.0f;
  const float half = std::tan(0.5f * kFovDeg * kPi / 180);
  c.right = normalize(cross(c.forward, {0, 1, 0})) * half;
  c.up = normalize(cross(c.right, c.forward)) * half;
  return w;
}

GBuffer traceGBuffer(const World& world, const ExactTracer& exact, int size, unsigned threads) {
  GBuffer g;
  g.width = g.height = size;
  g.pixels.resize(size_t(size) * size_t(size));
  parallelFor(g.pixels.size(), 256, threads, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i) {
      const int x = int(i % uint64_t(size)), y = int(i / uint64_t(size));
      const Vec3 d = world.camera.rayDirection(float(x) + 0.5f, float(y) + 0.5f, size, size);
      GSample& s = g.pixels[i];
      s.viewDir = d;
      float tPlane = std::numeric_limits<float>::infinity();
      if (d.y < 0) tPlane = -world.camera.eye.y / d.y;
      const ExactHit h = exact.intersect({world.camera.eye, d, 0.0f, tPlane});
      if (h.hit) {
        s.kind = PixelKind::kObject;
        s.point = world.camera.eye + d * h.t;
        s.normal = dot(h.geometric, d) > 0 ? h.geometric * -1.0f : h.geometric;
        s.shadingNormal = dot(h.normal, d) > 0 ? h.normal * -1.0f : h.normal;
      } else if (std::isfinite(tPlane)) {
        s.kind = PixelKind::kPlane;
        s.point = world.camera.eye + d * tPlane;
        s.point.y = 0.0f;
        s.normal = s.shadingNormal = {0, 1, 0};
      }
    }
  });
  return g;
}

Image renderImage(const GBuffer& g, unsigned threads, uint32_t stream,
                  const std::function<Vec3(const GSample&, Rng&)>& shade, double* seconds) {
  constexpr int kTile = 16;
  Image img;
  img.width = g.width;
  img.height = g.height;
  img.rgb.assign(size_t(g.width) * size_t(g.height), Vec3{});
  const int tilesX = (g.width + kTile - 1) / kTile, tilesY = (g.height + kTile - 1) / kTile;
  const auto t0 = std::chrono::steady_clock::now();
  parallelFor(uint64_t(tilesX) * uint64_t(tilesY), 1, threads, [&](uint64_t begin, uint64_t end) {
    for (uint64_t tile = begin; tile < end; ++tile) {
      const int x0 = int(tile % uint64_t(tilesX)) * kTile, y0 = int(tile / uint64_t(tilesX)) * kTile;
      for (int y = y0; y < std::min(y0 + kTile, g.height); ++y)
        for (int x = x0; x < std::min(x0 + kTile, g.width); ++x) {
          Rng rng(uint32_t(x), uint32_t(y), stream);
          img.at(x, y) = shade(g.at(x, y), rng);
        }
    }
  });
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

vff::Result<std::unique_ptr<Setup>> makeSetup(const Options& o, unsigned threads) {
  auto world = makeWorld(o.mesh);
  if (!world) return std::move(world).error();
  auto setup = std::make_unique<Setup>();
  setup->world = std::move(*world);
  auto exact = ExactTracer::create(setup->world.worldMesh);
  if (!exact) return std::move(exact).error();
  setup->exact.emplace(std::move(*exact));
  auto scene = vff::bake::Scene::create(setup->world.objectMesh, threads);
  if (!scene) return std::move(scene).error();
  setup->scene.emplace(std::move(*scene));
  return setup;
}

}  // namespace vffx
