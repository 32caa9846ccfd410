// scene_forms.cpp - scene-bench's second and third tables: the forms in which a renderer casts its
// rays, on the instances of each count up to 1000 as the last frame left them.
//
// Two ray sets of --scene-rays AO rays each, every ray with its source (the instance it starts on,
// or none), range aoDistance * R:
//   random  from random points of random instances' surfaces, as the first table's;
//   tiles   a G-buffer pass: a camera's view of the instances over a ground quad, 16 rays a pixel
//           from each visible point, cast tile by tile: the 16 pixels of a 4 x 4 tile for one
//           sample, then the next sample (so that a packet of 16 is a tile).
// For each set, Embree's triangles (instancing) and the hybrid (vff::embree::FieldGeometry with
// RaySources::kRayId) answer in three forms: single rays (rtcOccluded1), packets of 16
// (rtcOccluded16) and streams of 256 (rtcOccluded1M); vff::Scene answers with occludedFrom; the
// two-pass hybrid (vff::embree::occluded) answers the instances and the ground together, against
// Embree's instancing with the ground in its scene. The mean number of active rays an Embree
// callback gets in each form is counted by a geometry that only counts (the same boxes, never
// occluding). Each side's time is its best of --repeat passes on --threads workers, so that a busy
// moment of the machine does not fall on one side alone.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "cli.h"
#include "embree_instances.h"
#include "scene_bench.h"

namespace vffx {

namespace {

constexpr uint32_t kSpp = 16;          // AO rays a pixel of the tiles set
constexpr uint64_t kFormChunk = 4096;  // rays a worker's chunk (a multiple of 16)
constexpr uint32_t kStreamRays = 256;      // rays a stream call
constexpr uint64_t kSceneChunk = 32768;

struct FormRays {
  const char* name;
  std::vector<vff::Ray> rays;
  std::vector<uint32_t> sources;
  std::vector<unsigned> ids;  // the sources as RTCRay::id (RTC_INVALID_GEOMETRY_ID for none)
  void makeIds() {
    ids.resize(sources.size());
    for (size_t i = 0; i < ids.size(); ++i) ids[i] = sources[i] == vff::kNoInstance ? RTC_INVALID_GEOMETRY_ID : sources[i];
  }
};

enum class Form { kSingle, kPacket16, kStream };
const char* formName(Form f) { return f == Form::kSingle ? "single" : f == Form::kPacket16 ? "packets of 16" : "stream"; }

RTCRay rtcRayOf(const vff::Ray& r, unsigned id) {
  RTCRay e{};
  e.org_x = r.origin.x, e.org_y = r.origin.y, e.org_z = r.origin.z;
  e.dir_x = r.direction.x, e.dir_y = r.direction.y, e.dir_z = r.direction.z;
  e.tnear = r.tmin, e.tfar = r.tmax, e.mask = ~0u;
  e.id = id;
  return e;
}

// Rays [lo, hi) of the set in form f against scene; out[i] = 1 where occluded. (The context stays
// incoherent for the tiles too: Embree 3.13's rtcOccluded16 with RTC_INTERSECT_CONTEXT_FLAG_COHERENT
// never returned on an instanced scene here.)
void castForm(Form f, RTCScene scene, const FormRays& set, uint64_t lo, uint64_t hi, uint8_t* out) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (f == Form::kSingle) {
    for (uint64_t i = lo; i < hi; ++i) {
      RTCRay r = rtcRayOf(set.rays[i], set.ids[i]);
      rtcOccluded1(scene, &ctx, &r);
      out[i] = r.tfar < 0;
    }
  } else if (f == Form::kPacket16) {
    occluded16(scene, set.rays.data(), set.ids.data(), lo, hi, out);
  } else {
    RTCRay stream[kStreamRays];
    for (uint64_t b = lo; b < hi; b += kStreamRays) {
      const unsigned n = unsigned(std::min<uint64_t>(kStreamRays, hi - b));
      for (unsigned k = 0; k < n; ++k) stream[k] = rtcRayOf(set.rays[b + k], set.ids[b + k]);
      rtcOccluded1M(scene, &ctx, stream, n, sizeof(RTCRay));
      for (unsigned k = 0; k < n; ++k) out[b + k] = stream[k].tfar < 0;
    }
  }
}

// The counting geometry: one user primitive per instance on its sphere's box; the occluded
// callback counts its calls and their active rays, and occludes nothing.
struct Counter {
  std::atomic<uint64_t> calls{0}, lanes{0};
  std::vector<vff::Sphere> spheres;
};

void countBounds(const RTCBoundsFunctionArguments* a) {
  const auto* c = static_cast<const Counter*>(a->geometryUserPtr);
  const vff::Sphere& s = c->spheres[a->primID];
  RTCBounds* b = a->bounds_o;
  b->lower_x = s.center[0] - s.radius, b->lower_y = s.center[1] - s.radius, b->lower_z = s.center[2] - s.radius;
  b->upper_x = s.center[0] + s.radius, b->upper_y = s.center[1] + s.radius, b->upper_z = s.center[2] + s.radius;
}

void countOccluded(const RTCOccludedFunctionNArguments* a) {
  auto* c = static_cast<Counter*>(a->geometryUserPtr);
  uint64_t n = 0;
  for (unsigned i = 0; i < a->N; ++i) n += a->valid[i] == -1;
  c->calls.fetch_add(1, std::memory_order_relaxed);
  c->lanes.fetch_add(n, std::memory_order_relaxed);
}

void countIntersect(const RTCIntersectFunctionNArguments*) {}

// The mean active rays a callback of form f gets, for the set's rays over the instances' boxes.
double raysPerCallback(RTCDevice device, const vff::Scene& scene, Form f, const FormRays& set, unsigned threads) {
  Counter c;
  for (uint32_t i = 0; i < scene.size(); ++i) c.spheres.push_back(scene.instance(i)->worldSphere());
  RTCScene s = rtcNewScene(device);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(g, unsigned(c.spheres.size()));
  rtcSetGeometryUserData(g, &c);
  rtcSetGeometryBoundsFunction(g, countBounds, nullptr);
  rtcSetGeometryIntersectFunction(g, countIntersect);
  rtcSetGeometryOccludedFunction(g, countOccluded);
  rtcCommitGeometry(g);
  rtcAttachGeometry(s, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(s);
  std::vector<uint8_t> out(set.rays.size());
  parallelFor(set.rays.size(), kFormChunk, threads,
              [&](uint64_t lo, uint64_t hi) { castForm(f, s, set, lo, hi, out.data()); });
  rtcReleaseScene(s);
  return c.calls ? double(c.lanes) / double(c.calls) : 0.0;
}

// A ground quad at height y, far wider than the instances' cube, attached at `id`.
void addGround(RTCDevice device, RTCScene scene, float y, float extent, unsigned id) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 4));
  const float q[12] = {-extent, y, -extent, extent, y, -extent, extent, y, extent, -extent, y, extent};
  std::memcpy(v, q, sizeof q);
  auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 2));
  const unsigned t[6] = {0, 2, 1, 0, 3, 2};
  std::memcpy(ix, t, sizeof t);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, id);
  rtcReleaseGeometry(g);
}

// What one count's forms need beside the Count: the hybrid with ray sources, Embree's instancing
// with the ground, the ground alone.
struct FormScenes {
  RTCScene hybrid = nullptr, exactGround = nullptr, ground = nullptr;
  unsigned groundId = 0;  // in exactGround: after the instances' ids
  std::vector<vff::embree::FieldGeometry> fields;
  std::vector<RTCGeometry> inst;
  ~FormScenes() {
    fields.clear();
    for (RTCGeometry g : inst) rtcReleaseGeometry(g);
    for (RTCScene s : {hybrid, exactGround, ground})
      if (s) rtcReleaseScene(s);
  }
};

void makeFormScenes(const Bench& b, const Count& k, RTCDevice device, RTCScene mesh, FormScenes* f) {
  f->hybrid = rtcNewScene(device);
  f->exactGround = rtcNewScene(device);
  f->ground = rtcNewScene(device);
  const float y = -1.5f * b.R, extent = 10.0f * (k.side + b.R);
  for (uint32_t i = 0; i < k.n; ++i) {
    const vff::RigidTransform x = k.scene.instance(i)->transform;
    f->fields.push_back(vff::embree::FieldGeometry::attach(device, f->hybrid, &b.q, x, b.qo, i,
                                                           vff::embree::RaySources::kRayId)
                            .value());
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, mesh);
    vff::RigidTransform centred = x;  // (the mesh scene is centred on the sphere: back to its centre)
    centred.translation = x.toWorldPoint(toVec(b.s.center));
    setEmbreeTransform(g, centred);
    rtcAttachGeometryByID(f->exactGround, g, i);
    f->inst.push_back(g);
  }
  f->groundId = k.n;
  addGround(device, f->exactGround, y, extent, f->groundId);
  addGround(device, f->ground, y, extent, 0);
  for (RTCScene s : {f->hybrid, f->exactGround, f->ground}) rtcCommitScene(s);
}

// The random set: from random points of random instances' surfaces.
FormRays randomSet(const Bench& b, const Count& k, std::mt19937_64& g) {
  FormRays set{"random", std::vector<vff::Ray>(b.o.sceneRays), std::vector<uint32_t>(b.o.sceneRays), {}};
  std::uniform_real_distribution<float> u(0, 1);
  for (size_t r = 0; r < set.rays.size(); ++r) {
    const uint32_t i = std::min(k.n - 1, uint32_t(u(g) * float(k.n)));
    const vff::RigidTransform x = k.scene.instance(i)->transform;
    const float u0 = u(g), u1 = u(g), u2 = u(g);
    const auto [point, normal] = b.surface.sample(u0, u1, u2);
    const Vec3 wn = normalize(x.toWorldVector(normal));
    const float u3 = u(g), u4 = u(g);
    set.rays[r] = {x.toWorldPoint(point + toVec(b.s.center)) + wn * (1e-3f * b.R), cosineDirection(wn, u3, u4), 0.0f,
                   b.o.aoDistance * b.R};
    set.sources[r] = i;
  }
  set.makeIds();
  return set;
}

// The tiles set: a camera's view of the instances and the ground (traced exactly), 16 AO rays a
// visible pixel, tile by tile and sample by sample.
FormRays tileSet(const Bench& b, const Count& k, const FormScenes& f, std::mt19937_64& g) {
  FormRays set{"tiles", {}, {}, {}};
  const uint32_t side = std::max(4u, uint32_t(std::sqrt(double(b.o.sceneRays) / kSpp)) / 4 * 4);
  const Vec3 centre{0.5f * k.side, 0.5f * k.side, 0.5f * k.side};
  const Vec3 eye = centre + normalize(Vec3{0.35f, 0.55f, 1.0f}) * (1.6f * k.side + 6.0f * b.R);
  const Vec3 fwd = normalize(centre - eye);
  const Vec3 right = normalize(cross(fwd, Vec3{0, 1, 0})) * 0.45f;
  const Vec3 up = cross(right, fwd);
  std::uniform_real_distribution<float> u(0, 1);
  struct Pixel {
    bool hit;
    Vec3 p, n;
    uint32_t source;
  };
  std::vector<Pixel> px(size_t(side) * side);
  for (uint32_t y = 0; y < side; ++y)
    for (uint32_t x = 0; x < side; ++x) {
      const float sx = 2.0f * (float(x) + 0.5f) / float(side) - 1.0f, sy = 1.0f - 2.0f * (float(y) + 0.5f) / float(side);
      const Vec3 d = normalize(fwd + right * sx + up * sy);
      RTCRayHit rh{};
      rh.ray = rtcRayOf({eye, d, 0.0f, 1e30f}, RTC_INVALID_GEOMETRY_ID);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      rtcIntersect1(f.exactGround, &ctx, &rh);
      Pixel& q = px[size_t(y) * side + x];
      q.hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      if (!q.hit) continue;
      q.p = eye + d * rh.ray.tfar;
      const bool ground = rh.hit.geomID == f.groundId;
      q.source = ground ? vff::kNoInstance : rh.hit.instID[0];
      Vec3 n = ground ? Vec3{0, 1, 0} : k.scene.instance(q.source)->transform.toWorldVector({rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
      n = normalize(n);
      if (dot(n, d) > 0) n = n * -1.0f;
      q.n = n;
    }
  for (uint32_t ty = 0; ty < side; ty += 4)
    for (uint32_t tx = 0; tx < side; tx += 4)
      for (uint32_t s = 0; s < kSpp; ++s)
        for (uint32_t k4 = 0; k4 < 16; ++k4) {
          const Pixel& q = px[size_t(ty + k4 / 4) * side + tx + k4 % 4];
          if (!q.hit) continue;
          const float u1 = u(g), u2 = u(g);
          set.rays.push_back({q.p + q.n * (1e-3f * b.R), cosineDirection(q.n, u1, u2), 0.0f, b.o.aoDistance * b.R});
          set.sources.push_back(q.source);
        }
  set.makeIds();
  return set;
}

double bestOf(int repeat, const std::function<double()>& pass) {
  double best = 1e30;
  for (int r = 0; r < std::max(1, repeat); ++r) best = std::min(best, pass());
  return best;
}

double mrays(size_t rays, double seconds) { return seconds > 0 ? double(rays) / seconds * 1e-6 : 0.0; }

struct TwoPassRow {
  uint32_t n;
  const char* set;
  size_t rays;
  double scene, exact, exactGround, twoPass;  // seconds
  double agree;                               // two-pass = Embree + ground
};

// One count and set: the forms table's rows, printed; the two-pass row, returned.
TwoPassRow measureSet(const Bench& b, const Count& k, const FormScenes& f, RTCDevice device, const FormRays& set) {
  const uint64_t n = set.rays.size();
  std::vector<uint8_t> want(n), out(n), ref(n);
  const std::span<const vff::Ray> rays(set.rays);
  const std::span<const uint32_t> sources(set.sources);
  const double scene = bestOf(b.o.repeat, [&] {
    return timedParallelFor(n, kSceneChunk, b.threads, [&](uint64_t lo, uint64_t hi) {
      (void)k.scene.occludedFrom(rays.subspan(lo, hi - lo), sources.subspan(lo, hi - lo),
                                 std::span<uint8_t>(want).subspan(lo, hi - lo), b.qo);
    });
  });
  double exactSingle = 0;
  for (Form form : {Form::kSingle, Form::kPacket16, Form::kStream}) {
    const double te = bestOf(b.o.repeat, [&] {
      return timedParallelFor(n, kFormChunk, b.threads,
                              [&](uint64_t lo, uint64_t hi) { castForm(form, k.exact, set, lo, hi, ref.data()); });
    });
    const double th = bestOf(b.o.repeat, [&] {
      return timedParallelFor(n, kFormChunk, b.threads,
                              [&](uint64_t lo, uint64_t hi) { castForm(form, f.hybrid, set, lo, hi, out.data()); });
    });
    if (form == Form::kSingle) exactSingle = te;
    uint64_t same = 0, exactSame = 0;
    for (uint64_t i = 0; i < n; ++i) same += out[i] == want[i], exactSame += ref[i] == want[i];
    const double perCall = raysPerCallback(device, k.scene, form, set, b.threads);
    std::printf("| %u | %s | %s | %.2f | %.2f | %.2f | %.2f | %.4f | %.4f |\n", k.n, set.name, formName(form),
                mrays(n, te), mrays(n, th), te / th, perCall, double(same) / double(n), double(exactSame) / double(n));
  }
  std::printf("| %u | %s | vff::Scene batches | - | %.2f | %.2f | - | 1 | - |\n", k.n, set.name, mrays(n, scene),
              exactSingle / scene);
  // The two-pass hybrid against Embree's instancing with the ground, single rays.
  const double exactGround = bestOf(b.o.repeat, [&] {
    return timedParallelFor(n, kFormChunk, b.threads, [&](uint64_t lo, uint64_t hi) {
      castForm(Form::kSingle, f.exactGround, set, lo, hi, ref.data());
    });
  });
  const double twoPass = bestOf(b.o.repeat, [&] {
    return timedParallelFor(n, kSceneChunk, b.threads, [&](uint64_t lo, uint64_t hi) {
      (void)vff::embree::occluded(f.ground, k.scene, rays.subspan(lo, hi - lo), sources.subspan(lo, hi - lo),
                                  std::span<uint8_t>(out).subspan(lo, hi - lo), b.qo);
    });
  });
  uint64_t agree = 0;
  for (uint64_t i = 0; i < n; ++i) agree += out[i] == ref[i];
  return {k.n, set.name, size_t(n), scene, exactSingle, exactGround, twoPass, double(agree) / double(n)};
}

}  // namespace

int runRayForms(const Bench& b, const std::vector<std::unique_ptr<Count>>& counts, RTCDevice device, RTCScene mesh) {
  std::printf("\nRay forms: Embree's triangles (instancing) and the hybrid (FieldGeometry, ray sources in RTCRay::id) "
              "as single rays, packets of 16 and streams of %u; %u AO rays a set, range %.1f R; rates in Mrays/s, "
              "best of %d, %u threads\n\n",
              kStreamRays, b.o.sceneRays, double(b.o.aoDistance), b.o.repeat, b.threads);
  std::printf("| instances | rays | form | Embree triangles | hybrid | hybrid / Embree | hybrid rays a callback | "
              "hybrid = vff::Scene | Embree = vff::Scene |\n");
  std::printf("|---:|---|---|---:|---:|---:|---:|---:|---:|\n");
  std::vector<TwoPassRow> twoPass;
  for (const auto& count : counts) {
    const Count& k = *count;
    if (k.n > 1000) continue;
    FormScenes f;
    makeFormScenes(b, k, device, mesh, &f);
    std::mt19937_64 g(1000 + k.n);
    for (const FormRays& set : {randomSet(b, k, g), tileSet(b, k, f, g)}) {
      if (set.rays.empty()) continue;
      twoPass.push_back(measureSet(b, k, f, device, set));
    }
  }
  std::printf("\nTwo-pass hybrid (vff::embree::occluded: vff::Scene, then the ground in Embree packets of 16) against "
              "Embree's instancing with the ground, single rays; vff::Scene against Embree's instancing alone\n\n");
  std::printf("| instances | rays | vff::Scene speed-up | two-pass speed-up | kept (target 0.8) | two-pass = Embree | "
              "Embree + ground ns/ray | two-pass ns/ray | its ground pass ns/ray |\n");
  std::printf("|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const TwoPassRow& r : twoPass) {
    const double scene = r.exact / r.scene, two = r.exactGround / r.twoPass, n = double(r.rays);
    // (The two-pass's first pass is vff::Scene's own batch: the rest is the ground's.)
    std::printf("| %u | %s | %.2f | %.2f | %.2f | %.4f | %.1f | %.1f | %.1f |\n", r.n, r.set, scene, two, two / scene,
                r.agree, r.exactGround / n * 1e9, r.twoPass / n * 1e9, std::max(0.0, r.twoPass - r.scene) / n * 1e9);
  }
  return 0;
}

}  // namespace vffx
