// scene_experiment.cpp - the paper's Fig. 6 setting: a room traced exactly and several moving
// objects, each through its own field, against the fully exact render.
//
// The room (a floor and two walls, 5 high, open to the right) is made here. The objects are the --mesh
// (the bunny by default) and every --object mesh or, without --object, four procedural shapes
// (torus-knot, bowl, box, rod); each is scaled to a bounding radius of 1 and moves along a scripted
// path around the room's centre (turning about y; even ones rest on the floor, odd ones float and
// tumble). Per frame (--frames), ambient occlusion (--rays per pixel, range 1.5) at the exact
// primary hits:
//   exact   Embree: the room's triangles and each object as an instance of its mesh's scene, the
//           top level recommitted every frame;
//   fields  the two-pass hybrid (vff::embree::occluded): the objects through a vff::Scene
//           (kNearest), committed every frame, then the room in Embree (exact); each ray's source
//           is the pixel's object (its intra-object test, spec/geometry.md 7.3) or none (a room
//           point: every object by 7.4).
//   distance fields  the room exact, each object through its distance field (sdf_field.h) at its
//           field's memory, sphere traced (rows "F, distance fields"; --no-sdf: none).
// Writes OUT/scene-fF-exact.png, -fields.png, -comparison.png (the two side by side),
// -error.png (|difference| x 4), -sdf.png and -sdf-error.png, and OUT/scene-table.md: RMS and
// max error (8-bit scale) and the time of each frame, rebuild included.
#include <embree3/rtcore.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli.h"
#include "common.h"
#include "embree_instances.h"
#include "vff/bake/procedural.h"
#include "vff/bake/sphere.h"
#include "vff/embree.h"
#include "vff/scene.h"

namespace vffx {

namespace {

struct Object {
  std::string name;
  vff::bake::Mesh mesh;
  vff::Sphere sphere;
  vff::bake::BakedField baked;
  vff::FieldQuery query;
  RTCScene scene = nullptr;  // the mesh alone, for Embree instancing
};

RTCScene meshScene(RTCDevice device, const vff::bake::Mesh& m) {
  RTCScene s = rtcNewScene(device);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertexCount()));
  std::copy(m.positions.begin(), m.positions.end(), v);
  auto* ix = static_cast<uint32_t*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangleCount()));
  std::copy(m.indices.begin(), m.indices.end(), ix);
  rtcCommitGeometry(g);
  rtcAttachGeometry(s, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(s);
  return s;
}

// The room: floor y = 0, back wall z = -5, left wall x = -5. Open to the right, where the floor and
// the back wall run on past the camera's view, so that no pixel sees outside the room.
constexpr float kRoomRight = 12.0f;

vff::bake::Mesh roomMesh() {
  vff::bake::Mesh m;
  auto quad = [&](Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    const uint32_t base = uint32_t(m.vertexCount());
    for (Vec3 p : {a, b, c, d}) m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  };
  quad({-5, 0, -5}, {-5, 0, 5}, {kRoomRight, 0, 5}, {kRoomRight, 0, -5});
  quad({-5, 0, -5}, {kRoomRight, 0, -5}, {kRoomRight, 5, -5}, {-5, 5, -5});
  quad({-5, 0, -5}, {-5, 5, -5}, {-5, 5, 5}, {-5, 0, 5});
  return m;
}

// Object k of K at frame f: radius 1, on a circle of radius 2.3 around the centre.
vff::RigidTransform placement(const Object& ob, uint32_t k, uint32_t count, int frame) {
  const float phase = 2 * kPi * float(k) / float(count) + 0.35f * float(frame);
  const float scale = 1.0f / ob.sphere.radius;
  const bool floats = k % 2 == 1;
  Vec3 axis{0, 1, 0};
  float angle = float(k) + 0.6f * float(frame);
  if (floats) axis = normalize({0.3f, 1.0f, 0.5f}), angle *= 1.7f;
  vff::RigidTransform x = vff::RigidTransform::fromAxisAngle(axis, angle, {}, scale);
  const Vec3 centre{2.3f * std::cos(phase), floats ? 1.6f + 0.3f * std::sin(float(frame)) : 1.0f, 2.3f * std::sin(phase)};
  x.translation = centre - x.toWorldVector(toVec(ob.sphere.center));
  return x;
}

double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

using Objects = std::vector<std::unique_ptr<Object>>;

// Bakes `mesh` (named `name` in errors and the header) at the configuration's field, in its minimal
// enclosing sphere, and appends it to the objects.
int addObject(Objects& objects, const std::string& name, vff::bake::Mesh mesh, const FieldConfig& config,
              unsigned threads) {
  auto ob = std::make_unique<Object>();
  ob->name = name;
  ob->mesh = std::move(mesh);
  ob->sphere = vff::bake::minimalEnclosingSphere(ob->mesh.positions);
  auto scene = vff::bake::Scene::create(ob->mesh);
  if (!scene) return vff::cli::reportError(kProg, name, scene.error());
  vff::bake::BakeOptions bo;
  bo.positionParam = config.n;
  bo.mapResolution = config.mapSize;
  bo.threads = threads;
  bo.sphere = ob->sphere;
  auto baked = vff::bake::bakeField(*scene, bo);
  if (!baked) return vff::cli::reportError(kProg, name, baked.error());
  ob->baked = std::move(*baked);
  auto q = vff::FieldQuery::fromMaps(ob->baked.field, ob->baked.distance);
  if (!q) return vff::cli::reportError(kProg, name, q.error());
  ob->query = std::move(*q);
  objects.push_back(std::move(ob));
  return 0;
}

// The moving objects, each baked: --mesh, every --object and, without --object, the four
// procedural shapes.
int makeObjects(const Options& o, const FieldConfig& config, unsigned threads, Objects& objects) {
  std::vector<std::string> meshes{o.mesh};
  meshes.insert(meshes.end(), o.objects.begin(), o.objects.end());
  for (const std::string& path : meshes) {
    auto mesh = vff::bake::loadMesh(path);
    if (!mesh) return vff::cli::reportError(kProg, path, mesh.error());
    if (int rc = addObject(objects, path, std::move(*mesh), config, threads)) return rc;
  }
  if (o.objects.empty())
    for (const char* shape : {"torus-knot", "bowl", "box", "rod"})
      if (int rc = addObject(objects, shape, vff::bake::makeShape(shape), config, threads)) return rc;
  return 0;
}

// What the renders trace: the room and the objects in Embree (exact), and the objects' fields.
struct Scenes {
  RTCDevice device = nullptr;
  RTCScene roomOnly = nullptr;    // the room alone, traced exactly beside the fields
  RTCScene exact = nullptr;       // object k as instance k, the room as instance `count`
  std::vector<RTCGeometry> inst;  // object k's instance in `exact`, placed every frame
  vff::Scene fields;              // object k's field as instance k, placed every frame
};

void buildScenes(Objects& objects, Scenes& s) {
  const uint32_t count = uint32_t(objects.size());
  s.device = rtcNewDevice(nullptr);
  const vff::bake::Mesh room = roomMesh();
  s.roomOnly = meshScene(s.device, room);
  s.exact = rtcNewScene(s.device);
  {
    RTCScene roomCopy = meshScene(s.device, room);
    RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, roomCopy);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR,
                            std::array<float, 12>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}.data());
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(s.exact, g, count);  // the room is instance `count`
    rtcReleaseGeometry(g);
    rtcReleaseScene(roomCopy);
  }
  s.inst.resize(count);
  for (uint32_t k = 0; k < count; ++k) {
    objects[k]->scene = meshScene(s.device, objects[k]->mesh);
    s.inst[k] = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(s.inst[k], objects[k]->scene);
    rtcAttachGeometryByID(s.exact, s.inst[k], k);
    (void)s.fields.add(&objects[k]->query, {});
  }
}

void releaseScenes(Objects& objects, Scenes& s) {
  for (RTCGeometry gi : s.inst) rtcReleaseGeometry(gi);
  for (auto& ob : objects) rtcReleaseScene(ob->scene);
  rtcReleaseScene(s.exact);
  rtcReleaseScene(s.roomOnly);
  rtcReleaseDevice(s.device);
}

// The distance-field peer (sdf_field.h): each object's at its field's memory (none with --no-sdf).
// An object too small for a distance field leaves the distance-field part out for all of them,
// as --no-sdf does: a frame with some objects missing would compare nothing.
int buildSdfs(const Options& o, const Objects& objects, std::vector<SdfField>& sdfs) {
  const uint32_t count = uint32_t(objects.size());
  bool withSdf = o.sdf;
  for (uint32_t k = 0; withSdf && k < count; ++k)
    if (const uint64_t bytes = objects[k]->query.payloadBytes(); bytes < kSdfMinBudget) {
      std::fprintf(stderr, "%s: scene: note: no distance-field rows: %s's field has %llu bytes, under the %llu a distance grid needs\n",
                   kProg, objects[k]->name.c_str(), static_cast<unsigned long long>(bytes),
                   static_cast<unsigned long long>(kSdfMinBudget));
      withSdf = false;
    }
  for (uint32_t k = 0; withSdf && k < count; ++k) {
    auto sdf = SdfField::build(objects[k]->mesh, {.budgetBytes = objects[k]->query.payloadBytes(), .values = o.sdfValues, .bandVoxels = o.sdfBand});
    if (!sdf) return vff::cli::reportError(kProg, objects[k]->name, sdf.error());
    sdfs.push_back(std::move(*sdf));
  }
  return 0;
}

// The view of the room: from in front of it and above, towards its centre; 50 degrees wide.
Camera roomCamera() {
  const Vec3 eye{0.5f, 4.2f, 8.0f}, look{0, 0.9f, 0};
  Camera cam;
  cam.eye = eye;
  cam.forward = normalize(look - eye);
  const float half = std::tan(0.5f * 50.0f * kPi / 180.0f);
  cam.right = normalize(cross(cam.forward, {0, 1, 0})) * half;
  cam.up = normalize(cross(cam.right, cam.forward)) * half;
  return cam;
}

// The primary hits (exact, shared by every render) of a size x size image; object k placed at xs[k].
GBuffer primaryHits(RTCScene exact, const Camera& cam, int size, const std::vector<vff::RigidTransform>& xs,
                    unsigned threads) {
  const uint32_t count = uint32_t(xs.size());
  const Vec3 eye = cam.eye;
  GBuffer g;
  g.width = g.height = size;
  g.pixels.resize(size_t(size) * size_t(size));
  parallelFor(uint64_t(size) * uint64_t(size), 256, threads, [&](uint64_t b, uint64_t e) {
    for (uint64_t i = b; i < e; ++i) {
      const int x = int(i % uint64_t(size)), y = int(i / uint64_t(size));
      const Vec3 d = cam.rayDirection(float(x) + 0.5f, float(y) + 0.5f, size, size);
      RTCRayHit rh{};
      rh.ray.org_x = eye.x, rh.ray.org_y = eye.y, rh.ray.org_z = eye.z;
      rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
      rh.ray.tfar = INFINITY, rh.ray.mask = ~0u;
      rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      rtcIntersect1(exact, &ctx, &rh);
      GSample& s = g.pixels[i];
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      const uint32_t id = rh.hit.instID[0];
      s.kind = id < count ? PixelKind::kObject : PixelKind::kPlane;
      s.instance = id < count ? id : vff::kNoInstance;
      Vec3 n{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
      if (id < count) n = xs[id].toWorldVector(n);  // Embree gives an instance's normal in its space
      n = normalize(n);
      if (dot(n, d) > 0) n = n * -1.0f;
      s.point = eye + d * rh.ray.tfar;
      s.normal = s.shadingNormal = n;
      s.viewDir = d;
    }
  });
  return g;
}

// The AO rays of a pixel (range 1.5), in the thread's buffer.
std::span<vff::Ray> aoRays(const GSample& s, Rng& rng, int rays) {
  const float range = 1.5f;
  std::span<vff::Ray> r = rayBuffer(size_t(rays));
  for (auto& ray : r) {
    const float u1 = rng.next01(), u2 = rng.next01();
    ray = {s.point + s.normal * 1e-3f, cosineDirection(s.normal, u1, u2), 0.0f, range};
  }
  return r;
}

// The three renders of a frame's AO: exact (Embree alone), fields (the objects' fields, the room
// exact) and distance fields (each object's, the room exact). Each gives its time through *seconds.
Image renderExact(const GBuffer& g, RTCScene exact, int rays, unsigned threads, int frame, double* seconds) {
  return renderImage(g, threads, uint32_t(frame), [&](const GSample& s, Rng& rng) {
    if (s.kind == PixelKind::kBackground) return Vec3{};
    int open = 0;
    for (const vff::Ray& r : aoRays(s, rng, rays)) open += !occluded1(exact, r);
    const float v = float(open) / float(rays);
    return Vec3{v, v, v};
  }, seconds);
}

Image renderFields(const GBuffer& g, const vff::Scene& fields, RTCScene roomOnly, int rays, unsigned threads,
                   int frame, double* seconds) {
  return renderImage(g, threads, uint32_t(frame), [&](const GSample& s, Rng& rng) {
    if (s.kind == PixelKind::kBackground) return Vec3{};
    const std::span<vff::Ray> r = aoRays(s, rng, rays);
    thread_local std::vector<uint8_t> blocked;
    thread_local std::vector<uint32_t> sources;
    blocked.resize(r.size());
    sources.assign(r.size(), s.instance);  // each ray starts on the pixel's object, or on none (the room)
    // The two-pass hybrid: the objects through vff::Scene, then the room in Embree packets.
    (void)vff::embree::occluded(roomOnly, fields, r, sources, blocked);
    int open = 0;
    for (size_t i = 0; i < r.size(); ++i) open += !blocked[i];
    const float v = float(open) / float(rays);
    return Vec3{v, v, v};
  }, seconds);
}

Image renderSdf(const GBuffer& g, const std::vector<SdfField>& sdfs, RTCScene roomOnly, int rays, unsigned threads,
                int frame, double* seconds) {
  return renderImage(g, threads, uint32_t(frame), [&](const GSample& s, Rng& rng) {
    if (s.kind == PixelKind::kBackground) return Vec3{};
    const std::span<vff::Ray> r = aoRays(s, rng, rays);
    thread_local std::vector<uint8_t> blocked, any;
    blocked.resize(r.size());
    any.assign(r.size(), 0);
    const SdfTraceOptions so = sdfOptions(false, s.kind == PixelKind::kObject);
    for (const SdfField& sdf : sdfs) {
      sdf.occluded(r, blocked, so);
      for (size_t i = 0; i < r.size(); ++i) any[i] |= blocked[i];
    }
    int open = 0;
    for (size_t i = 0; i < r.size(); ++i) open += !any[i] && !occluded1(roomOnly, r[i]);
    const float v = float(open) / float(rays);
    return Vec3{v, v, v};
  }, seconds);
}

// What a frame measured: its images, and the seconds of each side's rebuild and render.
struct Frame {
  std::vector<uint8_t> mask;  // the pixels that see the room or an object
  Image ref, img, sdfImg;     // exact, fields, distance fields (empty without them)
  double exactRebuild = 0, fieldRebuild = 0;
  double exactSeconds = 0, fieldSeconds = 0, sdfSeconds = 0;
};

// Frame `frame`: places the objects in both scenes (and the distance fields), traces the primary
// hits and renders the three images.
int renderFrame(const Options& o, int frame, const Objects& objects, Scenes& s, std::vector<SdfField>& sdfs,
                const Camera& cam, int rays, unsigned threads, Frame& f) {
  const uint32_t count = uint32_t(objects.size());
  double t0 = seconds();
  std::vector<vff::RigidTransform> xs(count);
  for (uint32_t k = 0; k < count; ++k) {
    xs[k] = placement(*objects[k], k, count, frame);
    setEmbreeTransform(s.inst[k], xs[k]);
  }
  rtcCommitScene(s.exact);
  f.exactRebuild = seconds() - t0;
  t0 = seconds();
  for (uint32_t k = 0; k < count; ++k) (void)s.fields.setTransform(k, xs[k]);
  if (vff::Status st = s.fields.commit(); !st) return vff::cli::reportError(kProg, "", st.error());
  f.fieldRebuild = seconds() - t0;
  const GBuffer g = primaryHits(s.exact, cam, o.size, xs, threads);
  f.mask.resize(g.pixels.size());
  for (size_t i = 0; i < f.mask.size(); ++i) f.mask[i] = g.pixels[i].kind != PixelKind::kBackground;
  f.ref = renderExact(g, s.exact, rays, threads, frame, &f.exactSeconds);
  f.img = renderFields(g, s.fields, s.roomOnly, rays, threads, frame, &f.fieldSeconds);
  for (uint32_t k = 0; k < sdfs.size(); ++k) sdfs[k].transform = xs[k];
  if (!sdfs.empty()) f.sdfImg = renderSdf(g, sdfs, s.roomOnly, rays, threads, frame, &f.sdfSeconds);
  return 0;
}

// OUT/scene-fF-*.png of a frame: -sdf and -sdf-error (with distance fields), -exact, -fields,
// -comparison and -error.
int writeFrameImages(const Options& o, int frame, const Frame& f, bool withSdf) {
  const std::string base = o.out + "/scene-f" + std::to_string(frame);
  if (withSdf)
    for (auto st : {writePng(f.sdfImg, base + "-sdf.png"), writeErrorMap(f.ref, f.sdfImg, f.mask, 4.0f, base + "-sdf-error.png")})
      if (!st) return vff::cli::reportError(kProg, base, st.error());
  for (auto st : {writePng(f.ref, base + "-exact.png"), writePng(f.img, base + "-fields.png"),
                  writePng(sideBySide({f.ref, f.img}), base + "-comparison.png"),
                  writeErrorMap(f.ref, f.img, f.mask, 4.0f, base + "-error.png")})
    if (!st) return vff::cli::reportError(kProg, base, st.error());
  return 0;
}

// The frame's table rows: the fields', then (with distance fields) theirs, their time in the last
// column.
std::string frameRows(int frame, const Frame& f, bool withSdf) {
  const ErrorStats e = compareImages(f.ref, f.img, f.mask);
  char row[320];
  std::snprintf(row, sizeof row, "| %d | %.2f | %.0f | %.1f | %.1f |\n", frame, e.rms, e.max,
                1000 * (f.exactRebuild + f.exactSeconds), 1000 * (f.fieldRebuild + f.fieldSeconds));
  if (withSdf) {
    const ErrorStats es = compareImages(f.ref, f.sdfImg, f.mask);
    std::snprintf(row + std::strlen(row), sizeof row - std::strlen(row), "| %d, distance fields | %.2f | %.0f | %.1f | %.1f |\n",
                  frame, es.rms, es.max, 1000 * (f.exactRebuild + f.exactSeconds), 1000 * f.sdfSeconds);
  }
  return row;
}

}  // namespace

int runScene(const Options& o) {
  const unsigned threads = resolveThreads(o.threads);
  FieldConfig config;
  if (auto rc = singleConfig(o, "4226x32x32", &config)) return *rc;
  Objects objects;
  if (int rc = makeObjects(o, config, threads, objects)) return rc;
  const uint32_t count = uint32_t(objects.size());
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) return vff::cli::reportError(kProg, o.out, vff::makeError(vff::Code::kIoWrite, "cannot create the folder: " + ec.message()));

  Scenes scenes;
  buildScenes(objects, scenes);
  std::vector<SdfField> sdfs;
  if (int rc = buildSdfs(o, objects, sdfs)) return rc;
  const int rays = o.rays > 0 ? o.rays : 16;
  const Camera cam = roomCamera();

  std::string table = "| frame | RMS | max | exact ms | fields ms |\n|---:|---:|---:|---:|---:|\n";
  std::printf("Scene: %u objects (%s", count, objects[0]->name.c_str());
  for (uint32_t k = 1; k < count; ++k) std::printf(", %s", objects[k]->name.c_str());
  std::printf("), fields %s, %dx%d, %d AO rays per pixel, %u threads\n\n", config.name().c_str(), o.size, o.size,
              rays, threads);
  std::printf("%s", table.c_str());
  for (int frame = 0; frame < o.frames; ++frame) {
    Frame f;
    if (int rc = renderFrame(o, frame, objects, scenes, sdfs, cam, rays, threads, f)) return rc;
    if (int rc = writeFrameImages(o, frame, f, !sdfs.empty())) return rc;
    const std::string row = frameRows(frame, f, !sdfs.empty());
    table += row;
    std::printf("%s", row.c_str());
    std::fflush(stdout);
  }
  std::ofstream(o.out + "/scene-table.md") << table;
  releaseScenes(objects, scenes);
  return 0;
}

}  // namespace vffx
