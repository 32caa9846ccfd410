// exact_tracer.cpp - the reference: Embree 3 against the object's real triangles.
#include <embree3/rtcore.h>

#include <atomic>
#include <limits>

#include "common.h"

namespace vffx {

struct ExactTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  const vff::bake::Mesh* mesh = nullptr;
  std::atomic<int64_t> bytes{0}, peak{0};
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

ExactTracer::ExactTracer(ExactTracer&&) noexcept = default;
ExactTracer& ExactTracer::operator=(ExactTracer&&) noexcept = default;
ExactTracer::~ExactTracer() = default;

vff::Result<ExactTracer> ExactTracer::create(const vff::bake::Mesh& mesh) {
  auto impl = std::make_unique<Impl>();
  impl->mesh = &mesh;
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device) return vff::Error{vff::Code::kOutOfMemory, 0, vff::kNoOffset, "cannot create the Embree device"};
  rtcSetDeviceMemoryMonitorFunction(
      impl->device,
      [](void* user, ssize_t bytes, bool) -> bool {
        auto* i = static_cast<Impl*>(user);
        const int64_t now = i->bytes.fetch_add(bytes) + bytes;
        int64_t p = i->peak.load();
        while (now > p && !i->peak.compare_exchange_weak(p, now)) {
        }
        return true;
      },
      impl.get());
  impl->scene = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions.data(), 0,
                             3 * sizeof(float), mesh.vertexCount());
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices.data(), 0,
                             3 * sizeof(uint32_t), mesh.triangleCount());
  rtcCommitGeometry(g);
  rtcAttachGeometry(impl->scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(impl->scene);
  if (rtcGetDeviceError(impl->device) != RTC_ERROR_NONE)
    return vff::Error{vff::Code::kOutOfMemory, 0, vff::kNoOffset, "Embree failed to build the scene"};
  ExactTracer t;
  t.impl_ = std::move(impl);
  return t;
}

namespace {

RTCRay toRtc(const vff::Ray& r) {
  RTCRay ray{};
  ray.org_x = r.origin.x;
  ray.org_y = r.origin.y;
  ray.org_z = r.origin.z;
  ray.dir_x = r.direction.x;
  ray.dir_y = r.direction.y;
  ray.dir_z = r.direction.z;
  ray.tnear = r.tmin;
  ray.tfar = r.tmax;
  ray.mask = 0xffffffffu;
  return ray;
}

}  // namespace

bool ExactTracer::occluded(const vff::Ray& r) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray = toRtc(r);
  rtcOccluded1(impl_->scene, &ctx, &ray);
  return ray.tfar == -std::numeric_limits<float>::infinity();
}

ExactHit ExactTracer::intersect(const vff::Ray& r) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh{};
  rh.ray = toRtc(r);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx, &rh);
  ExactHit h;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
  h.hit = true;
  h.t = rh.ray.tfar;
  const vff::bake::Mesh& m = *impl_->mesh;
  h.geometric = normalize({rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
  h.normal = h.geometric;
  if (!m.normals.empty()) {
    const uint32_t* tri = &m.indices[size_t(rh.hit.primID) * 3];
    const float u = rh.hit.u, v = rh.hit.v;
    h.normal = normalize(toVec(&m.normals[size_t(tri[0]) * 3]) * (1 - u - v) + toVec(&m.normals[size_t(tri[1]) * 3]) * u +
                         toVec(&m.normals[size_t(tri[2]) * 3]) * v);
  }
  return h;
}

uint64_t ExactTracer::memoryBytes() const { return uint64_t(std::max<int64_t>(0, impl_->peak.load())); }

RTCDevice ExactTracer::device() const { return impl_->device; }
RTCScene ExactTracer::scene() const { return impl_->scene; }

}  // namespace vffx
