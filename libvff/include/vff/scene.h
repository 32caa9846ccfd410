// vff/scene.h - a scene of field instances: many rigid objects, moved by the caller between frames.
//
// A Scene holds instances (vff::Instance: a FieldQuery and a RigidTransform). Fields are borrowed
// and shared: a thousand bunnies hold one FieldQuery, which must outlive the Scene. The caller
// moves instances with setTransform() between frames and calls commit(), which rebuilds the
// top-level structure: a bounding volume hierarchy over the instances' world bounding spheres
// (binned surface-area heuristic, O(n log n), four children per node, tested four at once in SSE2
// lanes). Queries run on a committed scene only.
//
//   vff::Scene scene;
//   for (int i = 0; i < 1000; ++i) (void)scene.add(&bunny, placement(i, 0));   // ids 0, 1, 2...
//   for (int frame = 0; frame < frames; ++frame) {
//     for (uint32_t i = 0; i < scene.size(); ++i) (void)scene.setTransform(i, placement(i, frame));
//     if (vff::Status s = scene.commit(); !s) return s;
//     vff::Status s = scene.intersect(rays, hits);            // hits[r].instance, .t, .point...
//   }
//
// What a query answers: exactly what looping over the instances in id order answers, bit for bit.
// * intersect: the nearest of the instances' hits (Instance::intersect); of hits at the same t, the
//   one of the lowest id. SceneHit::instance says which; kNoInstance for a miss.
// * occluded: whether any instance reports the ray occluded (Instance::occluded).
// * visibility: the product, in id order, of the instances' visibility (Instance::visibility);
//   the instances a ray never comes near contribute exactly 1.
// The hierarchy only skips instances whose (slightly enlarged) world sphere the ray's [tmin, tmax]
// segment never reaches: those answer a miss and a visibility of 1 anyway, so culling changes no
// answer.
//
// Rays that start on an object. A ray whose origin lies inside an instance's bounding sphere
// starts either on that object's surface or somewhere else inside its sphere (the ground under
// it, another object touching it), and the field answers the two differently (vff/query.h,
// RayOrigin; spec/geometry.md sections 7.3 and 7.4). The *From functions take each ray's source:
// the id of the instance the ray starts on, or kNoInstance. That instance answers the ray by
// section 7.3 with options.intraBias; every other instance by section 7.4, which finds the first
// surface ahead, so contact shadows stay at any ray range. This is what a renderer wants: the
// source is the object its G-buffer pixel or its path vertex lies on.
//
//   std::vector<uint32_t> sources(rays.size());   // per ray: the instance it starts on, or
//   ...                                           // vff::kNoInstance (the ground)
//   vff::Status s = scene.occludedFrom(rays, sources, blocked);
//
// The functions without sources apply options.origin to every instance: by default
// (RayOrigin::kOnObject) every instance whose sphere holds the origin answers by section 7.3, as if
// the ray started on each of them. For a ray from the ground under an object, or from one object
// into the sphere of another it touches, that reports the LAST surface of the other object before
// the ray leaves its sphere, and loses the contact shadow at ranges below 2R: pass sources.
//
// Speed. The batch functions send a chunk of rays down the hierarchy together (each node tested
// once against the rays that reached it), take each (ray, instance) pair into the instance's
// object space as the one-ray functions do, and let each field answer the rays of all its
// instances in one call of its batch path (vff/query.h); then they combine the answers per ray in
// id order. A thousand instances of one field thus cost one large batch, not a thousand small
// ones. The one-ray functions walk the hierarchy nearest first and stop early (intersect: at the
// nearest hit; occluded: at the first).
//
// Why the batches are built beside Embree and not on it: an Embree renderer can hand the top level
// to Embree instead (vff/embree.h: each instance a user geometry), and that is the way to mix
// fields with exact triangles in one traversal. But Embree calls a user geometry back with the
// rays of one traversal step, mostly one ray at a time for incoherent rays, so the field's batch
// path never gets a batch; vff-experiments scene-bench measures Scene's batches, the Embree top
// level over fields and Embree instancing of the triangles side by side in one run, and Scene's
// batches are the fastest of the three there. A GPU walks the same hierarchy, exported by
// hierarchy(): gpu/glsl/vff_scene.glsl, vff/gl/scene_loader.h.
//
// Threads. The query functions are const and may run on many threads at once; add(),
// setTransform() and commit() must not run while any query does. A batch call's working memory
// is the scene's, kept for the next calls (one per call running at once), so threads made for
// each call do not fault it in again.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/query.h"
#include "vff/scene_hierarchy.h"

namespace vff {

inline constexpr uint32_t kNoInstance = ~uint32_t{0};

struct SceneHit : QueryHit {
  uint32_t instance = kNoInstance;  // the id of the instance hit; kNoInstance when nothing was
};

class VFF_API Scene {
 public:
  Scene() noexcept;
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  ~Scene();

  // Adds an instance of `field` (borrowed: it must outlive the Scene) placed by `transform`, and
  // returns its id: the number of instances added before it. The scene needs a commit() before
  // its next query. Errors: kInvalidArgument (null field, or a field with no maps), kSphere (the
  // field's bounding sphere is not finite or has radius <= 0), and those of checkTransform().
  Result<uint32_t> add(const FieldQuery* field, const RigidTransform& transform);
  // Moves instance `id`; the scene needs a commit() before its next query. Errors: kOutOfRange
  // (no such instance), those of checkTransform().
  Status setTransform(uint32_t id, const RigidTransform& transform);
  // Instance `id` as it stands (also before a commit). Errors: kOutOfRange.
  Result<Instance> instance(uint32_t id) const;
  uint32_t size() const noexcept;

  // Rebuilds the hierarchy over the instances' world spheres. An empty scene commits (and every
  // ray misses it).
  Status commit();
  // True when no add() or setTransform() happened since the last commit().
  bool committed() const noexcept;

  // World-space queries; the answers are described above. Errors: kBadState when the scene is
  // not committed; for batches, kInvalidArgument when out.size() differs from rays.size().
  Result<SceneHit> intersect(const Ray& ray, const QueryOptions& options = {}) const;
  Result<bool> occluded(const Ray& ray, const QueryOptions& options = {}) const;
  Result<float> visibility(const Ray& ray, const QueryOptions& options = {}) const;
  Status intersect(std::span<const Ray> rays, std::span<SceneHit> out, const QueryOptions& options = {}) const;
  Status occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options = {}) const;
  Status visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options = {}) const;

  // The same queries for rays with sources (see above): sources[r] (or `source`) is the id of the
  // instance ray r starts on, or kNoInstance when it starts on none; options.origin is not used.
  // Errors: those above; kInvalidArgument when sources.size() differs from rays.size();
  // kOutOfRange for a source that is neither an instance's id nor kNoInstance.
  Result<SceneHit> intersectFrom(const Ray& ray, uint32_t source, const QueryOptions& options = {}) const;
  Result<bool> occludedFrom(const Ray& ray, uint32_t source, const QueryOptions& options = {}) const;
  Result<float> visibilityFrom(const Ray& ray, uint32_t source, const QueryOptions& options = {}) const;
  Status intersectFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<SceneHit> out,
                       const QueryOptions& options = {}) const;
  Status occludedFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<uint8_t> out,
                      const QueryOptions& options = {}) const;
  Status visibilityFrom(std::span<const Ray> rays, std::span<const uint32_t> sources, std::span<float> out,
                        const QueryOptions& options = {}) const;

  // The instance ids whose enlarged world spheres the ray's [tmin, tmax] segment reaches, in
  // ascending order (what the queries consider). Errors: kBadState when not committed.
  Result<std::vector<uint32_t>> candidates(const Ray& ray) const;

  // The committed top-level hierarchy, copied into a flat layout (vff/scene_hierarchy.h) for a
  // walker outside libvff, such as the GLSL scene query. Errors: kBadState when not committed.
  // Experimental (vff/export.h): the layout follows the GLSL walker.
  VFF_EXPERIMENTAL Result<SceneHierarchy> hierarchy() const;

  struct Impl;  // opaque

 private:
  std::unique_ptr<Impl> impl_;
};

// Checks that `transform` is rigid: a finite translation, a finite scale > 0, and a rotation whose
// rows are orthonormal to within 1e-3 with determinant +1. Errors: kInvalidArgument naming the
// problem.
VFF_API Status checkTransform(const RigidTransform& transform);

}  // namespace vff
