// embree.cpp - vff::embree::FieldGeometry (vff/embree.h): a field instance as Embree 3 user
// geometry, its bounds, intersect and occluded callbacks over Instance's batch path.
#include "vff/embree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "vff/scene.h"

namespace vff::embree {

struct VFF_HIDDEN FieldGeometry::State {  // (VFF_HIDDEN: not exported with its class, vff/export.h)
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  unsigned geomID = RTC_INVALID_GEOMETRY_ID;
  Instance instance;
  QueryOptions options;
};

namespace {

constexpr unsigned kMaxPacket = 16;

void bounds(const RTCBoundsFunctionArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  const Sphere w = s->instance.worldSphere();
  // Enlarged a little, so that Embree's box test never drops a ray the field's sphere test keeps.
  const float big = std::max({std::abs(w.center[0]), std::abs(w.center[1]), std::abs(w.center[2]), w.radius});
  const float r = w.radius + 1e-3f * w.radius + 1e-5f * big;
  RTCBounds* b = args->bounds_o;
  b->lower_x = w.center[0] - r;
  b->lower_y = w.center[1] - r;
  b->lower_z = w.center[2] - r;
  b->upper_x = w.center[0] + r;
  b->upper_y = w.center[1] + r;
  b->upper_z = w.center[2] + r;
}

// The active rays of lanes [base, base + count) of a packet of N as vff rays; lane[k] is the
// packet index of rays[k]. Returns how many.
unsigned gather(const int* valid, RTCRayN* ray, unsigned N, unsigned base, unsigned count, Ray* rays, unsigned* lane) {
  unsigned n = 0;
  for (unsigned i = base; i < base + count; ++i) {
    if (valid[i] != -1) continue;
    rays[n] = Ray{{RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i)},
                  {RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i)},
                  RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i)};
    lane[n++] = i;
  }
  return n;
}

void intersect(const RTCIntersectFunctionNArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  const unsigned N = args->N;
  for (unsigned base = 0; base < N; base += kMaxPacket) {  // streams come as N = 1, packets up to 16
    const unsigned n0 = std::min(kMaxPacket, N - base);
    Ray rays[kMaxPacket];
    unsigned lane[kMaxPacket];
    QueryHit hits[kMaxPacket];
    const unsigned n = gather(args->valid, ray, N, base, n0, rays, lane);
    if (n == 0) continue;
    s->instance.intersect(std::span<const Ray>(rays, n), std::span<QueryHit>(hits, n), s->options);
    for (unsigned k = 0; k < n; ++k) {
      const QueryHit& h = hits[k];
      const unsigned i = lane[k];
      if (!h.hit || !(h.t <= RTCRayN_tfar(ray, N, i))) continue;
      RTCRayN_tfar(ray, N, i) = h.t;
      Vec3 ng = h.normal;
      if (!h.hasNormal) ng = {-rays[k].direction.x, -rays[k].direction.y, -rays[k].direction.z};
      RTCHitN_Ng_x(hit, N, i) = ng.x;
      RTCHitN_Ng_y(hit, N, i) = ng.y;
      RTCHitN_Ng_z(hit, N, i) = ng.z;
      RTCHitN_u(hit, N, i) = 0;
      RTCHitN_v(hit, N, i) = 0;
      RTCHitN_primID(hit, N, i) = args->primID;
      RTCHitN_geomID(hit, N, i) = args->geomID;
      for (unsigned l = 0; l < RTC_MAX_INSTANCE_LEVEL_COUNT; ++l) RTCHitN_instID(hit, N, i, l) = args->context->instID[l];
    }
  }
}

void occluded(const RTCOccludedFunctionNArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  const unsigned N = args->N;
  for (unsigned base = 0; base < N; base += kMaxPacket) {
    const unsigned n0 = std::min(kMaxPacket, N - base);
    Ray rays[kMaxPacket];
    unsigned lane[kMaxPacket];
    uint8_t blocked[kMaxPacket];
    const unsigned n = gather(args->valid, args->ray, N, base, n0, rays, lane);
    if (n == 0) continue;
    s->instance.occluded(std::span<const Ray>(rays, n), std::span<uint8_t>(blocked, n), s->options);
    for (unsigned k = 0; k < n; ++k)
      if (blocked[k]) RTCRayN_tfar(args->ray, N, lane[k]) = -std::numeric_limits<float>::infinity();
  }
}

Error embreeError(RTCDevice device, const char* what) {
  return makeError(Code::kBadState, std::string("embree: ") + what + " failed (RTCError " +
                                        std::to_string(int(rtcGetDeviceError(device))) + ")");
}

}  // namespace

FieldGeometry::FieldGeometry() noexcept = default;
FieldGeometry::FieldGeometry(FieldGeometry&&) noexcept = default;
FieldGeometry& FieldGeometry::operator=(FieldGeometry&& o) noexcept {
  if (this != &o) {
    detach();
    state_ = std::move(o.state_);
  }
  return *this;
}
FieldGeometry::~FieldGeometry() { detach(); }

Result<FieldGeometry> FieldGeometry::attach(RTCDevice device, RTCScene scene, const FieldQuery* field,
                                            const RigidTransform& transform, const QueryOptions& options,
                                            unsigned geomID) {
  if (!device || !scene) return makeError(Code::kInvalidArgument, "embree: null device or scene");
  // The instance checks of vff::Scene: a field with a finite sphere, a rigid transform.
  Scene check;
  if (Result<uint32_t> id = check.add(field, transform); !id) return std::move(id).error();
  FieldGeometry g;
  g.state_ = std::make_unique<State>();
  State& s = *g.state_;
  s.instance = Instance{field, transform};
  s.options = options;
  s.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  if (!s.geometry) return embreeError(device, "rtcNewGeometry");
  rtcSetGeometryUserPrimitiveCount(s.geometry, 1);
  rtcSetGeometryUserData(s.geometry, &s);
  rtcSetGeometryBoundsFunction(s.geometry, bounds, nullptr);
  rtcSetGeometryIntersectFunction(s.geometry, intersect);
  rtcSetGeometryOccludedFunction(s.geometry, occluded);
  rtcCommitGeometry(s.geometry);
  if (geomID == RTC_INVALID_GEOMETRY_ID) {
    s.geomID = rtcAttachGeometry(scene, s.geometry);
  } else {
    rtcAttachGeometryByID(scene, s.geometry, geomID);
    s.geomID = geomID;
  }
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    rtcReleaseGeometry(s.geometry);
    s.geometry = nullptr;
    return embreeError(device, "rtcAttachGeometry");
  }
  s.scene = scene;
  return g;
}

Status FieldGeometry::setTransform(const RigidTransform& transform) {
  if (!state_ || !state_->scene) return makeError(Code::kBadState, "embree: the field geometry is not attached");
  if (Status st = checkTransform(transform); !st) return st;
  state_->instance.transform = transform;
  rtcCommitGeometry(state_->geometry);
  return {};
}

void FieldGeometry::detach() noexcept {
  if (!state_ || !state_->scene) return;
  rtcDetachGeometry(state_->scene, state_->geomID);
  rtcReleaseGeometry(state_->geometry);
  state_->scene = nullptr;
  state_->geometry = nullptr;
}

unsigned FieldGeometry::geomID() const noexcept { return state_ ? state_->geomID : RTC_INVALID_GEOMETRY_ID; }

const Instance& FieldGeometry::instance() const noexcept {
  static const Instance none;
  return state_ ? state_->instance : none;
}

}  // namespace vff::embree
