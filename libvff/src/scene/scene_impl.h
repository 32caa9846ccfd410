// scene_impl.h - the state behind vff::Scene (vff/scene.h), shared by scene.cpp and
// scene_batch.cpp.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "query/query_impl.h"
#include "scene/scene_bvh.h"
#include "vff/scene.h"

namespace vff {

namespace detail {

// The (instance, ray) pairs of a chunk of a batch. Instance i's pairs are [first[i], first[i] +
// count[i]), rays ascending; the instances of a field (Scene::Impl::byField) lie back to back, so
// that the pairs of a field form one range.
struct ScenePairs {
  std::vector<uint32_t> first, count;  // per instance
  std::vector<uint32_t> ray;           // per pair: the ray's index in the chunk
  std::vector<Ray> rays;               // per pair: the ray in the instance's object space
};

// What a batch call works in (scene_batch.cpp): megabytes for a large chunk, which fresh memory
// would fault in and zero on every call.
struct SceneScratch {
  ScenePairs pairs;
  BoxRays boxRays;
  RayLists lists;
  std::vector<QueryHit> hits;
  std::vector<uint8_t> blocked;
  std::vector<float> vis;
  // With sources: which pairs start on their own instance, and each half gathered with its answers.
  std::vector<uint8_t> own;
  std::vector<Ray> sourcedRays;
  std::vector<uint32_t> sourcedAt;
  std::vector<QueryHit> partHits;
  std::vector<uint8_t> partBlocked;
  std::vector<float> partVis;
};

}  // namespace detail

struct VFF_HIDDEN Scene::Impl {  // (VFF_HIDDEN: not exported with its class, vff/export.h)
  std::vector<Instance> instances;
  // Each instance's world-to-object step, taken apart at commit (the batches take every pair's ray
  // into its instance's object space with it).
  std::vector<detail::ToObject> toObject;
  detail::Bvh4 bvh;
  std::vector<detail::Box> boxes;  // the commit's, kept for the next
  float maxRadius = 0;  // the largest enlarged world radius
  // The instance ids grouped by field (ascending id within a group), and where each group starts
  // in it (fieldStart.back() == instances.size()): the batches ask each field once for the rays
  // of all its instances.
  std::vector<uint32_t> byField, fieldStart;
  bool committed = true;
  // The working memory of batch calls that ended, for the next ones (ScratchLease in
  // scene_batch.cpp): kept by the scene, not by the calling threads, so that a caller whose
  // threads are new at each call (a thread per call, as Python's batches make) still finds it
  // faulted in. At most one per call running at once.
  mutable std::mutex spareLock;
  mutable std::vector<std::unique_ptr<detail::SceneScratch>> spare;

  static Impl& of(std::unique_ptr<Impl>& p);
  // kBadState unless committed (a scene never touched is committed and empty).
  static Status ready(const Impl* m);
  // How far before the nearest hit so far another instance's hit can still lie, in t.
  float margin(const Ray& ray) const noexcept;
  // The candidate instances of the ray (scene.h), ascending.
  void gather(const Ray& ray, std::vector<uint32_t>* ids) const;
};

}  // namespace vff
