// scene_impl.h - the state behind vff::Scene (vff/scene.h), shared by scene.cpp and
// scene_batch.cpp.
#pragma once

#include <memory>
#include <vector>

#include "scene_bvh.h"
#include "vff/scene.h"

namespace vff {

struct Scene::Impl {
  std::vector<Instance> instances;
  detail::Bvh4 bvh;
  float maxRadius = 0;  // the largest enlarged world radius
  // The instance ids grouped by field (ascending id within a group), and where each group starts
  // in it (fieldStart.back() == instances.size()): the batches ask each field once for the rays
  // of all its instances.
  std::vector<uint32_t> byField, fieldStart;
  bool committed = true;

  static Impl& of(std::unique_ptr<Impl>& p);
  // kBadState unless committed (a scene never touched is committed and empty).
  static Status ready(const Impl* m);
  // How far before the nearest hit so far another instance's hit can still lie, in t.
  float margin(const Ray& ray) const noexcept;
  // The candidate instances of the ray (scene.h), ascending.
  void gather(const Ray& ray, std::vector<uint32_t>* ids) const;
};

}  // namespace vff
