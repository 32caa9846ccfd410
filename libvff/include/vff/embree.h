// vff/embree.h - field instances as Embree 3 user geometry: the optional component vff::embree
// (find_package(vff CONFIG REQUIRED COMPONENTS embree), link vff::embree). Experimental as a whole
// (VFF_EMBREE_EXPERIMENTAL, vff/export.h): the interface may change between minor versions.
//
// A renderer that already traces its static environment with Embree attaches its moving objects
// as fields to the same RTCScene: one rtcIntersect*/rtcOccluded* call then answers exact
// triangles and field objects together, and Embree's own hierarchy, rebuilt by rtcCommitScene,
// is the top level over both.
//
//   vff::Result<vff::embree::FieldGeometry> g =
//       vff::embree::FieldGeometry::attach(device, scene, &bunnyField, transform);
//   rtcCommitScene(scene);
//   ... every frame: g->setTransform(next); rtcCommitScene(scene); rtcIntersect16(...);
//
// What Embree sees. One user primitive whose bounds are the instance's world bounding sphere's
// box. Its intersect callback answers the rays of the packet Embree hands it (1, 4, 8 or 16) with
// Instance::intersect's batch path, with each ray's [tnear, tfar] as [tmin, tmax]: a hit sets
// tfar = t, Ng = the field's world normal (or, for a field without normals, the reversed ray
// direction), u = v = 0, primID = 0, geomID and the instance ids of the context. The occluded
// callback answers with Instance::occluded and sets tfar = -inf. Streams (rtcIntersect1M,
// rtcOccluded1M and the other stream calls) reach the callbacks as packets too. With
// Reconstruction::kNearest a ray's hit does not depend on tfar beyond the test t <= tfar, so the
// nearest hit over fields and triangles is what vff::Scene and an exact trace each give; with
// kInterpolated the blend sees the tfar Embree holds when it calls.
//
// Where each ray starts (vff/scene.h, "Rays that start on an object"). With RaySources::kOptions
// every ray is answered as options.origin says, as Instance does. With RaySources::kRayId each
// ray's id (RTCRay::id, which Embree hands through untouched) names the FieldGeometry the ray
// starts on, by its geomID, or RTC_INVALID_GEOMETRY_ID for none: that geometry answers the ray by
// section 7.3 (RayOrigin::kOnObject, options.intraBias), every other by section 7.4, as vff::Scene's
// *From calls do. A renderer sets the id of each secondary ray to the geomID its primary ray hit.
//
// Filter functions. Set them with setIntersectFilter() and setOccludedFilter() (not on the
// RTCGeometry directly: the callbacks must know that the geometry has one). The callbacks invoke
// the geometry's filter and the context's (RTCIntersectContext::filter) for every hit they find
// (rtcFilterIntersection, rtcFilterOcclusion), with the hit as described above; a hit the filter
// rejects (valid set to 0) is dropped and the ray's tfar kept. With a filter present the occluded
// callback answers through Instance::intersect, so that the filter sees the hit's distance and
// normal.
//
// Speed. The callbacks answer a packet's lanes that reach the instance's sphere through the batch
// path (vff/query.h: the group kernel's SIMD lanes); the lanes that miss it are answered before
// any is taken to object space (Embree hands a packet's callback every active lane). Embree calls
// them per packet and per primitive: with single rays and streams of incoherent rays one active ray
// at a time, which waits for its own texel read as a single-ray traversal of triangles waits for
// its nodes; packets of 16 (rtcOccluded16) give the callback 16. vff-experiments scene-bench measures Embree's triangles, this
// hybrid and vff::Scene side by side, for single rays, packets of 16 and streams, on random rays
// and on coherent ones (4 x 4 pixel tiles). For rays that only field objects and a static
// environment can stop, the two-pass calls below answer the fields in vff::Scene's batches and
// the environment in Embree packets.
//
// The two-pass hybrid. occluded() and intersect() below answer a batch of rays against moving
// field objects (a vff::Scene) and a static environment (an RTCScene of triangles or anything
// else), without attaching the fields to Embree:
//
//   vff::Scene objects;            // the moving instances, committed each frame
//   RTCScene room = ...;           // the static environment, committed once
//   std::vector<uint32_t> sources; // per ray: the instance it starts on, or vff::kNoInstance
//   vff::Status s = vff::embree::occluded(room, objects, rays, sources, blocked);
//
// occluded: vff::Scene::occludedFrom first (the cheap part), then rtcOccluded16 over the rays the
// fields did not stop, 16 at a time (for incoherent rays Embree's streams go one ray at a time).
// intersect: vff::Scene::intersectFrom first, then rtcIntersect16 with each ray's tfar cut to the
// field's hit, so that Embree answers only what lies nearer.
//
// Threads. The callbacks are const and run on Embree's threads. setTransform() must not run
// while the scene is traced. The two-pass calls run on the calling thread (and Embree's packets on
// it); call them from many threads at once on separate batches.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <span>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/query.h"
#include "vff/scene.h"

namespace vff::embree {

// Where the rays a FieldGeometry answers start (see "Where each ray starts" above).
enum class RaySources : uint8_t {
  kOptions = 0,  // every ray as the attach options' origin says
  kRayId = 1,    // RTCRay::id holds the geomID of the FieldGeometry the ray starts on, or none
};

class VFF_EMBREE_EXPERIMENTAL FieldGeometry {
 public:
  FieldGeometry() noexcept;
  FieldGeometry(FieldGeometry&&) noexcept;
  FieldGeometry& operator=(FieldGeometry&&) noexcept;
  // Detaches the geometry from its scene (which must still exist; see detach()).
  ~FieldGeometry();

  // Creates the user geometry on `device`, attaches it to `scene` and returns it; the caller
  // commits the scene. `field` is borrowed and must outlive the geometry. geomID: the id to
  // attach at (RTC_INVALID_GEOMETRY_ID: Embree's next free id). Errors: kInvalidArgument (null
  // device, scene or field), kSphere (a field sphere that is not finite), the transform errors of
  // vff::checkTransform (vff/scene.h), kBadState when Embree refuses (its error code in the
  // message).
  // sources: where the rays start (RaySources above).
  static Result<FieldGeometry> attach(RTCDevice device, RTCScene scene, const FieldQuery* field,
                                      const RigidTransform& transform, const QueryOptions& options = {},
                                      unsigned geomID = RTC_INVALID_GEOMETRY_ID,
                                      RaySources sources = RaySources::kOptions);

  // Moves the instance and recommits its geometry (its bounds); the caller then commits the scene.
  // Errors: those of vff::checkTransform; kBadState when not attached.
  Status setTransform(const RigidTransform& transform);
  // Detaches now; the destructor then does nothing.
  void detach() noexcept;
  // The geometry's filter functions (null: none), invoked by the callbacks for every hit they find
  // (see "Filter functions" above); the caller then commits the scene. Errors: kBadState when not
  // attached.
  Status setIntersectFilter(RTCFilterFunctionN filter);
  Status setOccludedFilter(RTCFilterFunctionN filter);
  // The RTCGeometry (for rtcSetGeometryMask and the like; not for its filter functions).
  RTCGeometry geometry() const noexcept;

  unsigned geomID() const noexcept;
  const Instance& instance() const noexcept;

  struct State;  // opaque

 private:
  std::unique_ptr<State> state_;
};

// A hit of the two-pass hybrid: of a field instance (instance != kNoInstance; the Scene's hit) or of
// the environment (geomID != RTC_INVALID_GEOMETRY_ID; Embree's hit, Ng as normal, not normalised).
struct HybridHit : QueryHit {
  uint32_t instance = kNoInstance;
  unsigned geomID = RTC_INVALID_GEOMETRY_ID, primID = RTC_INVALID_GEOMETRY_ID;
  float u = 0, v = 0;
};

// The two-pass hybrid (see above): whether each ray is stopped within [tmin, tmax] by a field
// instance of `fields` or by `environment`; or its nearest hit of either (of equal t, the field's).
// sources: per ray, the instance it starts on or kNoInstance (vff::Scene's *From calls); empty:
// every instance answers as options.origin says. out.size() must equal rays.size(). Errors: those
// of vff::Scene's batch calls (kBadState for an uncommitted scene, kInvalidArgument, kOutOfRange
// for a bad source); kInvalidArgument for a null environment.
VFF_EMBREE_EXPERIMENTAL Status occluded(RTCScene environment, const Scene& fields, std::span<const Ray> rays,
                                        std::span<const uint32_t> sources, std::span<uint8_t> out,
                                        const QueryOptions& options = {});
VFF_EMBREE_EXPERIMENTAL Status intersect(RTCScene environment, const Scene& fields, std::span<const Ray> rays,
                                         std::span<const uint32_t> sources, std::span<HybridHit> out,
                                         const QueryOptions& options = {});

}  // namespace vff::embree
