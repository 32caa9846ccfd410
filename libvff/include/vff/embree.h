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
// box. Its intersect callback answers the rays of the packet Embree hands it (1, 4, 8 or 16, or
// streams) with Instance::intersect's batch path, with each ray's [tnear, tfar] as [tmin, tmax]:
// a hit sets tfar = t, Ng = the field's world normal (or, for a field without normals, the
// reversed ray direction), u = v = 0, primID = 0, geomID and the instance ids of the context.
// The occluded callback answers with Instance::occluded and sets tfar = -inf. With
// Reconstruction::kNearest a ray's hit does not depend on tfar beyond the test t <= tfar, so the
// nearest hit over fields and triangles is what vff::Scene and an exact trace each give; with
// kInterpolated the blend sees the tfar Embree holds when it calls. Filter functions are not
// invoked.
//
// Speed, and why vff::Scene does not use this. vff::Scene's batches hand each instance all the
// rays of the batch that reach it, in one call: full SIMD groups, whose texel reads overlap.
// Embree calls the callback per packet and per primitive, with few active rays (one, for
// rtcIntersect1 and rtcOccluded1), and such a ray waits for its own texel read, as a single-ray
// traversal of triangles waits for its nodes. vff-experiments scene-bench measures Embree's
// instancing of the triangles, vff::Scene and this hybrid side by side: for the bunny there, the
// hybrid answers single AO rays more slowly than Embree's own triangles, and vff::Scene's batches
// many times faster than either. A field's cost does not grow with its object's triangles while
// Embree's does (vff-experiments triangle-bench), so the hybrid should compare better for heavier
// objects (scene-bench measures one mesh only). Use this where one traversal must meet fields and
// triangles together (rays that can also hit the static environment); cast the rays that only the
// field objects can stop (their own ambient occlusion, say) in batches through vff::Scene.
//
// Threads. The callbacks are const and run on Embree's threads. setTransform() must not run
// while the scene is traced.
#pragma once

#include <embree3/rtcore.h>

#include <memory>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/query.h"

namespace vff::embree {

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
  static Result<FieldGeometry> attach(RTCDevice device, RTCScene scene, const FieldQuery* field,
                                      const RigidTransform& transform, const QueryOptions& options = {},
                                      unsigned geomID = RTC_INVALID_GEOMETRY_ID);

  // Moves the instance and recommits its geometry (its bounds); the caller then commits the scene.
  // Errors: those of vff::checkTransform; kBadState when not attached.
  Status setTransform(const RigidTransform& transform);
  // Detaches now; the destructor then does nothing.
  void detach() noexcept;

  unsigned geomID() const noexcept;
  const Instance& instance() const noexcept;

  struct State;  // opaque

 private:
  std::unique_ptr<State> state_;
};

}  // namespace vff::embree
