// embree.cpp - vff::embree::FieldGeometry (vff/embree.h): a field instance as Embree 3 user
// geometry, its bounds, intersect and occluded callbacks over Instance's batch path, with ray sources
// and filter functions. (The two-pass hybrid: hybrid.cpp.)
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
  RaySources sources = RaySources::kOptions;
  Sphere sphere;  // the instance's enlarged world sphere (enlargedSphere), kept with the transform
  bool intersectFilter = false, occludedFilter = false;  // the geometry has them (set*Filter)
};

namespace {

constexpr unsigned kMaxPacket = 16;

// The instance's world sphere, enlarged a little, so that no test against it (Embree's box test,
// the callbacks' own) drops a ray the field's sphere test in object space keeps.
Sphere enlargedSphere(const Instance& x) {
  Sphere w = x.worldSphere();
  const float big = std::max({std::abs(w.center[0]), std::abs(w.center[1]), std::abs(w.center[2]), w.radius});
  w.radius = w.radius + 1e-3f * w.radius + 1e-5f * big;
  return w;
}

void bounds(const RTCBoundsFunctionArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  const Sphere w = enlargedSphere(s->instance);
  const float r = w.radius;
  RTCBounds* b = args->bounds_o;
  b->lower_x = w.center[0] - r;
  b->lower_y = w.center[1] - r;
  b->lower_z = w.center[2] - r;
  b->upper_x = w.center[0] + r;
  b->upper_y = w.center[1] + r;
  b->upper_z = w.center[2] + r;
}

// Whether the segment [tmin, tmax] of r reaches the (enlarged) world sphere w. Embree hands a
// packet's callback every active lane of the packet, most of which, for incoherent rays, pass far
// from this instance: they are answered (a miss) here, before any is taken to object space.
float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

bool reaches(const Sphere& w, const Ray& r) {
  const Vec3 d{r.origin.x - w.center[0], r.origin.y - w.center[1], r.origin.z - w.center[2]};
  const float a = dot3(r.direction, r.direction), b = dot3(d, r.direction), c = dot3(d, d) - w.radius * w.radius;
  const float disc = b * b - a * c;
  if (!(disc >= 0) || !(a > 0)) return !(disc < 0);  // (a zero or odd direction: left to the query)
  const float sq = std::sqrt(disc);
  return (-b + sq) >= 0 && (-b - sq) <= r.tmax * a;  // (the sphere not behind; not beyond tmax: as prepare())
}

// The active rays of lanes [base, base + count) of a packet of N that reach the instance's sphere,
// as vff rays; lane[k] is the packet index of rays[k]. Returns how many.
unsigned gather(const Sphere& w, const int* valid, RTCRayN* ray, unsigned N, unsigned base, unsigned count, Ray* rays,
                unsigned* lane) {
  unsigned n = 0;
  for (unsigned i = base; i < base + count; ++i) {
    if (valid[i] != -1) continue;
    rays[n] = Ray{{RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i)},
                  {RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i)},
                  RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i)};
    if (!reaches(w, rays[n])) continue;
    lane[n++] = i;
  }
  return n;
}

// Answers rays[0, n) with answer(rays, out, options): in one call, or, with RaySources::kRayId, in
// two, the rays that start on this geometry (their id) by section 7.3 and the rest by 7.4.
template <class T, class Answer>
void answerPacket(const FieldGeometry::State& s, RTCRayN* ray, unsigned N, const Ray* rays, const unsigned* lane,
                  unsigned n, T* out, Answer&& answer) {
  if (s.sources == RaySources::kOptions) {
    answer(std::span<const Ray>(rays, n), std::span<T>(out, n), s.options);
    return;
  }
  Ray part[kMaxPacket];
  T partOut[kMaxPacket];
  unsigned at[kMaxPacket];
  for (const bool own : {false, true}) {
    unsigned m = 0;
    for (unsigned k = 0; k < n; ++k)
      if ((RTCRayN_id(ray, N, lane[k]) == s.geomID) == own) part[m] = rays[k], at[m++] = k;
    if (m == 0) continue;
    QueryOptions o = s.options;
    o.origin = own ? RayOrigin::kOnObject : RayOrigin::kOffObject;
    answer(std::span<const Ray>(part, m), std::span<T>(partOut, m), o);
    for (unsigned k = 0; k < m; ++k) out[at[k]] = partOut[k];
  }
}

void intersectPacket(const FieldGeometry::State& s, const Ray* rays, unsigned n, std::span<QueryHit> hits,
                     RTCRayN* ray, unsigned N, const unsigned* lane) {
  answerPacket(s, ray, N, rays, lane, n, hits.data(),
               [&](std::span<const Ray> r, std::span<QueryHit> h, const QueryOptions& o) { s.instance.intersect(r, h, o); });
}

// Hit packets of N lanes (RTCHitN's layout: 7 + RTC_MAX_INSTANCE_LEVEL_COUNT words a lane).
constexpr unsigned kHitWords = 7 + RTC_MAX_INSTANCE_LEVEL_COUNT;

void writeHit(RTCHitN* hit, unsigned N, unsigned i, const QueryHit& h, const Ray& r, unsigned primID, unsigned geomID,
              const RTCIntersectContext* context) {
  const Vec3 ng = h.hasNormal ? h.normal : Vec3{-r.direction.x, -r.direction.y, -r.direction.z};
  RTCHitN_Ng_x(hit, N, i) = ng.x;
  RTCHitN_Ng_y(hit, N, i) = ng.y;
  RTCHitN_Ng_z(hit, N, i) = ng.z;
  RTCHitN_u(hit, N, i) = 0;
  RTCHitN_v(hit, N, i) = 0;
  RTCHitN_primID(hit, N, i) = primID;
  RTCHitN_geomID(hit, N, i) = geomID;
  for (unsigned l = 0; l < RTC_MAX_INSTANCE_LEVEL_COUNT; ++l) RTCHitN_instID(hit, N, i, l) = context->instID[l];
}

// Runs the filters (the geometry's and the context's) over the candidate hits of a packet: each
// candidate lane's tfar holds its hit distance meanwhile, as Embree's own primitives do. Clears
// accept[k] for the hits a filter rejects and puts their tfar back. filter(fargs) invokes them.
template <class Filter>
void filterHits(const void* userPtr, RTCIntersectContext* context, RTCRayN* ray, unsigned N, const Ray* rays,
                const unsigned* lane, const QueryHit* hits, unsigned n, unsigned primID, unsigned geomID,
                bool* accept, Filter&& filter) {
  std::vector<int> valid(N, 0);
  std::vector<unsigned> words(size_t(kHitWords) * N, 0);
  RTCHitN* tmp = reinterpret_cast<RTCHitN*>(words.data());
  std::vector<float> before(n);
  bool any = false;
  for (unsigned k = 0; k < n; ++k) {
    if (!accept[k]) continue;
    const unsigned i = lane[k];
    valid[i] = -1;
    before[k] = RTCRayN_tfar(ray, N, i);
    RTCRayN_tfar(ray, N, i) = hits[k].t;
    writeHit(tmp, N, i, hits[k], rays[k], primID, geomID, context);
    any = true;
  }
  if (!any) return;
  RTCFilterFunctionNArguments fargs;
  fargs.valid = valid.data();
  fargs.geometryUserPtr = const_cast<void*>(userPtr);
  fargs.context = context;
  fargs.ray = ray;
  fargs.hit = tmp;
  fargs.N = N;
  filter(&fargs);
  for (unsigned k = 0; k < n; ++k) {
    if (!accept[k] || valid[lane[k]] == -1) continue;
    accept[k] = false;
    RTCRayN_tfar(ray, N, lane[k]) = before[k];
  }
}

void intersect(const RTCIntersectFunctionNArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  const unsigned N = args->N;
  const bool filters = s->intersectFilter || args->context->filter;
  for (unsigned base = 0; base < N; base += kMaxPacket) {  // (packets come with N <= 16)
    const unsigned n0 = std::min(kMaxPacket, N - base);
    Ray rays[kMaxPacket];
    unsigned lane[kMaxPacket];
    QueryHit hits[kMaxPacket];
    bool accept[kMaxPacket];
    const unsigned n = gather(s->sphere, args->valid, ray, N, base, n0, rays, lane);
    if (n == 0) continue;
    intersectPacket(*s, rays, n, std::span<QueryHit>(hits, n), ray, N, lane);
    for (unsigned k = 0; k < n; ++k) accept[k] = hits[k].hit && hits[k].t <= RTCRayN_tfar(ray, N, lane[k]);
    if (filters)
      filterHits(s, args->context, ray, N, rays, lane, hits, n, args->primID, args->geomID, accept,
                 [&](const RTCFilterFunctionNArguments* f) { rtcFilterIntersection(args, f); });
    for (unsigned k = 0; k < n; ++k) {
      if (!accept[k]) continue;
      RTCRayN_tfar(ray, N, lane[k]) = hits[k].t;
      writeHit(hit, N, lane[k], hits[k], rays[k], args->primID, args->geomID, args->context);
    }
  }
}

void occluded(const RTCOccludedFunctionNArguments* args) {
  const auto* s = static_cast<const FieldGeometry::State*>(args->geometryUserPtr);
  const unsigned N = args->N;
  const bool filters = s->occludedFilter || args->context->filter;
  for (unsigned base = 0; base < N; base += kMaxPacket) {
    const unsigned n0 = std::min(kMaxPacket, N - base);
    Ray rays[kMaxPacket];
    unsigned lane[kMaxPacket];
    bool accept[kMaxPacket];
    const unsigned n = gather(s->sphere, args->valid, args->ray, N, base, n0, rays, lane);
    if (n == 0) continue;
    if (filters) {  // the filter sees the hit: its distance and normal
      QueryHit hits[kMaxPacket];
      intersectPacket(*s, rays, n, std::span<QueryHit>(hits, n), args->ray, N, lane);
      for (unsigned k = 0; k < n; ++k) accept[k] = hits[k].hit;
      filterHits(s, args->context, args->ray, N, rays, lane, hits, n, args->primID, args->geomID, accept,
                 [&](const RTCFilterFunctionNArguments* f) { rtcFilterOcclusion(args, f); });
    } else {
      uint8_t blocked[kMaxPacket];
      answerPacket(*s, args->ray, N, rays, lane, n, blocked,
                   [&](std::span<const Ray> r, std::span<uint8_t> b, const QueryOptions& o) { s->instance.occluded(r, b, o); });
      for (unsigned k = 0; k < n; ++k) accept[k] = blocked[k] != 0;
    }
    for (unsigned k = 0; k < n; ++k)
      if (accept[k]) RTCRayN_tfar(args->ray, N, lane[k]) = -std::numeric_limits<float>::infinity();
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
                                            unsigned geomID, RaySources sources) {
  if (!device || !scene) return makeError(Code::kInvalidArgument, "embree: null device or scene");
  // The instance checks of vff::Scene: a field with a finite sphere, a rigid transform.
  Scene check;
  if (Result<uint32_t> id = check.add(field, transform); !id) return std::move(id).error();
  FieldGeometry g;
  g.state_ = std::make_unique<State>();
  State& s = *g.state_;
  s.instance = Instance{field, transform};
  s.sphere = enlargedSphere(s.instance);
  s.options = options;
  s.sources = sources;
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
  state_->sphere = enlargedSphere(state_->instance);
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

Status FieldGeometry::setIntersectFilter(RTCFilterFunctionN filter) {
  if (!state_ || !state_->scene) return makeError(Code::kBadState, "embree: the field geometry is not attached");
  rtcSetGeometryIntersectFilterFunction(state_->geometry, filter);
  state_->intersectFilter = filter != nullptr;
  rtcCommitGeometry(state_->geometry);
  return {};
}

Status FieldGeometry::setOccludedFilter(RTCFilterFunctionN filter) {
  if (!state_ || !state_->scene) return makeError(Code::kBadState, "embree: the field geometry is not attached");
  rtcSetGeometryOccludedFilterFunction(state_->geometry, filter);
  state_->occludedFilter = filter != nullptr;
  rtcCommitGeometry(state_->geometry);
  return {};
}

RTCGeometry FieldGeometry::geometry() const noexcept { return state_ ? state_->geometry : nullptr; }

unsigned FieldGeometry::geomID() const noexcept { return state_ ? state_->geomID : RTC_INVALID_GEOMETRY_ID; }

const Instance& FieldGeometry::instance() const noexcept {
  static const Instance none;
  return state_ ? state_->instance : none;
}

}  // namespace vff::embree
