#include "vff/bake/baker.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "platform/parallel.h"
#include "vff/bake/sphere.h"
#include "vff/bc4.h"
#include "vff/direction.h"
#include "vff/encoding.h"
#include "vff/positions.h"

namespace vff::bake {

struct Scene::Impl {
  Mesh mesh;
  std::atomic<int64_t> embreeBytes{0};
  std::atomic<int64_t> embreePeak{0};
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;
const Mesh& Scene::mesh() const noexcept { return impl_->mesh; }
uint64_t Scene::embreeBytes() const noexcept { return uint64_t(std::max<int64_t>(0, impl_->embreePeak.load())); }

Result<Scene> Scene::create(const Mesh& mesh, unsigned threads) {
  if (mesh.triangleCount() == 0) return makeError(Code::kMeshEmpty, "the mesh has no triangles");
  auto impl = std::make_unique<Impl>();
  impl->mesh = mesh;
  const std::string config = threads ? "threads=" + std::to_string(threads) : std::string();
  impl->device = rtcNewDevice(config.c_str());
  if (!impl->device) return makeError(Code::kUnsupported, "Embree: cannot create a device (unsupported CPU?)");
  rtcSetDeviceMemoryMonitorFunction(
      impl->device,
      [](void* user, ssize_t bytes, bool) {
        auto* i = static_cast<Impl*>(user);
        const int64_t now = i->embreeBytes.fetch_add(bytes) + bytes;
        int64_t peak = i->embreePeak.load();
        while (now > peak && !i->embreePeak.compare_exchange_weak(peak, now)) {
        }
        return true;
      },
      impl.get());
  impl->scene = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->scene, RTC_BUILD_QUALITY_HIGH);
  // Robust mode: watertight triangle tests, so rays through shared edges and vertices never slip
  // between triangles.
  rtcSetSceneFlags(impl->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertexCount()));
  auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), mesh.triangleCount()));
  if (!v || !ix) {
    rtcReleaseGeometry(g);
    return makeError(Code::kOutOfMemory, "Embree: cannot allocate geometry buffers");
  }
  std::copy(mesh.positions.begin(), mesh.positions.end(), v);
  std::copy(mesh.indices.begin(), mesh.indices.end(), ix);
  rtcCommitGeometry(g);
  rtcAttachGeometry(impl->scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(impl->scene);
  if (rtcGetDeviceError(impl->device) != RTC_ERROR_NONE)
    return makeError(Code::kOutOfMemory, "Embree: building the scene failed");
  return Scene(std::move(impl));
}

Result<FieldDesc> describeBake(const Mesh& mesh, const BakeOptions& o) {
  FieldDesc f;
  if (o.sphere) {
    f.sphere = *o.sphere;
  } else {
    // The sphere of the vertices the triangles use (unreferenced vertices do not occlude).
    std::vector<uint8_t> used(mesh.vertexCount(), 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    std::vector<float> pts;
    pts.reserve(mesh.positions.size());
    for (size_t i = 0; i < used.size(); ++i)
      if (used[i]) pts.insert(pts.end(), {mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]});
    if (pts.empty()) return makeError(Code::kMeshEmpty, "the mesh has no triangles");
    f.sphere = minimalEnclosingSphere(pts);
  }
  auto count = positionCount(o.positionScheme, o.positionParam);
  if (!count) return std::move(count).error();
  f.positionScheme = o.positionScheme;
  f.positionParam = o.positionParam;
  f.mapCount = *count;
  f.directionScheme = o.directionScheme;
  f.mapResolution = o.mapResolution;
  f.distanceEncoding = o.encoding;
  f.normalEncoding = o.normals ? NormalEncoding::kOctSnorm16 : NormalEncoding::kNone;
  Status st = checkFieldDesc(f);
  if (!st) return std::move(st).error();
  if (o.mapResolution > 4096) return makeError(Code::kMapResolution, "mapResolution above 4096 is not supported by the baker");
  return f;
}

namespace {

// Rays start this far (times R) behind the entry point; see traceMap.
constexpr float kBackOff = 1e-4f;

struct Plan {
  FieldDesc field;
  PositionSet positions;
  std::vector<Vec3> local;      // texel-centre directions in the map frame, row-major
  std::vector<float> cosAlpha;  // their z
  uint64_t distBytes = 0, normBytes = 0;
};

Result<Plan> makePlan(const Mesh& mesh, const BakeOptions& o) {
  auto f = describeBake(mesh, o);
  if (!f) return std::move(f).error();
  const uint32_t last = o.mapEnd ? o.mapEnd : f->mapCount;
  if (o.mapBegin >= last || last > f->mapCount)
    return makeError(Code::kInvalidArgument, "map range " + std::to_string(o.mapBegin) + ":" + std::to_string(last) +
                                                 " is not inside the field's " + std::to_string(f->mapCount) + " maps");
  auto ps = PositionSet::fromField(*f);
  if (!ps) return std::move(ps).error();
  Plan p{*f, *ps, {}, {}, 0, 0};
  const uint32_t m = f->mapResolution;
  p.local.resize(size_t(m) * m);
  p.cosAlpha.resize(size_t(m) * m);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) {
      p.local[size_t(j) * m + i] = texelDirection(f->directionScheme, m, i, j);
      p.cosAlpha[size_t(j) * m + i] = p.local[size_t(j) * m + i].z;
    }
  p.distBytes = distanceMapBytes(f->distanceEncoding, m);
  p.normBytes = normalMapBytes(f->normalEncoding, m);
  return p;
}

// Traces one map's rays in packets of 16; with kKeep, encodes them into dist/norm.
template <bool kKeep>
uint64_t traceMap(const Scene::Impl& s, const Plan& plan, uint32_t map, uint8_t* dist, uint8_t* norm) {
  const FieldDesc& f = plan.field;
  const float R = f.sphere.radius;
  const Vec3 u = plan.positions.position(map);
  const float backOff = kBackOff * R;
  const Vec3 origin{f.sphere.center[0] + R * u.x, f.sphere.center[1] + R * u.y, f.sphere.center[2] + R * u.z};
  const Frame frame = frameFromNormal({-u.x, -u.y, -u.z});
  const uint32_t m = f.mapResolution;
  const size_t texels = size_t(m) * m;
  const bool withNormals = kKeep && norm != nullptr;
  const bool smooth = !s.mesh.normals.empty();
  // bc4-diameter: the map's unorm8-diameter codes first, then its BC4 blocks (vff/bc4.h).
  const bool bc4 = kKeep && f.distanceEncoding == DistanceEncoding::kBc4Diameter;
  thread_local std::vector<uint8_t> codes;
  if (bc4) codes.assign(texels, 255);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  uint64_t hits = 0;
  alignas(64) RTCRayHit16 rh;
  alignas(64) int valid[16];
  for (size_t t0 = 0; t0 < texels; t0 += 16) {
    const size_t n = std::min<size_t>(16, texels - t0);
    for (size_t k = 0; k < 16; ++k) {
      valid[k] = k < n ? -1 : 0;
      const Vec3 d = toWorld(frame, plan.local[t0 + std::min(k, n - 1)]);
      // Start kBackOff outside the sphere (only empty space lies there), so that a surface touching
      // the entry point is hit robustly at distance ~0 by every traversal path.
      rh.ray.org_x[k] = origin.x - backOff * d.x;
      rh.ray.org_y[k] = origin.y - backOff * d.y;
      rh.ray.org_z[k] = origin.z - backOff * d.z;
      rh.ray.dir_x[k] = d.x;
      rh.ray.dir_y[k] = d.y;
      rh.ray.dir_z[k] = d.z;
      rh.ray.tnear[k] = 0.0f;
      rh.ray.tfar[k] = INFINITY;
      rh.ray.time[k] = 0.0f;
      rh.ray.mask[k] = 0xFFFFFFFFu;
      rh.ray.id[k] = unsigned(k);
      rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, s.scene, &ctx, &rh);
    for (size_t k = 0; k < n; ++k) {
      const bool hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
      hits += hit;
      if constexpr (kKeep) {
        const size_t t = t0 + k;
        const float d = std::max(0.0f, rh.ray.tfar[k] - backOff);
        const uint32_t code = encodeDistance(f.distanceEncoding, hit, d, R, plan.cosAlpha[t]);
        if (bc4) codes[t] = uint8_t(code);
        else storeCode(f.distanceEncoding, std::span<uint8_t>(dist, plan.distBytes), m, uint32_t(t % m), uint32_t(t / m), code);
        if (withNormals && hit) {
          Vec3 nv{rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]};
          if (smooth) {
            const uint32_t* tri = &s.mesh.indices[3 * size_t(rh.hit.primID[k])];
            const float bu = rh.hit.u[k], bv = rh.hit.v[k], bw = 1.0f - bu - bv;
            const float* N = s.mesh.normals.data();
            Vec3 sn{bw * N[3 * tri[0]] + bu * N[3 * tri[1]] + bv * N[3 * tri[2]],
                    bw * N[3 * tri[0] + 1] + bu * N[3 * tri[1] + 1] + bv * N[3 * tri[2] + 1],
                    bw * N[3 * tri[0] + 2] + bu * N[3 * tri[1] + 2] + bv * N[3 * tri[2] + 2]};
            if (sn.x * sn.x + sn.y * sn.y + sn.z * sn.z > 1e-20f) nv = sn;
          }
          const float len = std::sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
          if (len > 0) encodeNormal({nv.x / len, nv.y / len, nv.z / len}, norm + 4 * t);
        }
      }
    }
  }
  if (bc4) encodeBc4Map(codes, m, std::span<uint8_t>(dist, plan.distBytes));
  return hits;
}

template <bool kKeep>
BakeStats runAll(const Scene::Impl& s, const Plan& plan, const BakeOptions& o, uint8_t* dist, uint8_t* norm) {
  const uint32_t first = o.mapBegin, last = o.mapEnd ? o.mapEnd : plan.field.mapCount;
  const uint32_t maps = last - first;
  std::atomic<uint64_t> hits{0}, done{0};
  const auto t0 = std::chrono::steady_clock::now();
  // One map per chunk (maps differ in cost); each map's codes at its own offset.
  parallel::parallelFor(maps, 1, o.threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      if (o.cancel && o.cancel->load(std::memory_order_relaxed)) return;
      hits.fetch_add(traceMap<kKeep>(s, plan, first + uint32_t(i), kKeep ? dist + i * plan.distBytes : nullptr,
                                     kKeep && norm ? norm + i * plan.normBytes : nullptr),
                     std::memory_order_relaxed);
      const uint64_t d = done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (o.progress) o.progress(d, maps);
    }
  });
  BakeStats st;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.rays = uint64_t(maps) * plan.field.mapResolution * plan.field.mapResolution;
  st.hits = hits;
  return st;
}

}  // namespace

Result<BakedField> bakeField(const Scene& scene, const BakeOptions& o) {
  auto plan = makePlan(scene.mesh(), o);
  if (!plan) return std::move(plan).error();
  BakedField out;
  out.field = plan->field;
  const uint64_t maps = uint64_t(o.mapEnd ? o.mapEnd : plan->field.mapCount) - o.mapBegin;
  try {
    out.distance.assign(plan->distBytes * maps, 0);
    if (o.normals) out.normals.assign(plan->normBytes * maps, 0);
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory,
                     "cannot allocate the field's " + std::to_string((plan->distBytes + plan->normBytes) * maps) + " bytes");
  }
  out.stats = runAll<true>(*scene.impl_, *plan, o, out.distance.data(), o.normals ? out.normals.data() : nullptr);
  if (o.cancel && o.cancel->load()) return makeError(Code::kBadState, "the bake was cancelled");
  return out;
}

Result<BakeStats> traceOnly(const Scene& scene, const BakeOptions& o) {
  auto plan = makePlan(scene.mesh(), o);
  if (!plan) return std::move(plan).error();
  return runAll<false>(*scene.impl_, *plan, o, nullptr, nullptr);
}

}  // namespace vff::bake
