// scene_export.cpp - Scene::hierarchy (vff/scene.h, vff/scene_hierarchy.h): the committed
// hierarchy (scene_bvh.h's Node4 and primitive order) copied into the flat public layout.
#include <algorithm>
#include <utility>

#include "scene/scene_impl.h"

namespace vff {

Result<SceneHierarchy> Scene::hierarchy() const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  SceneHierarchy h;
  if (!impl_ || impl_->bvh.empty()) return h;
  const std::vector<detail::Node4>& nodes = impl_->bvh.nodes();
  h.nodes.resize(nodes.size());
  std::vector<uint32_t> level(nodes.size(), 0);
  level[0] = 1;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const detail::Node4& n = nodes[i];
    SceneNode& o = h.nodes[i];
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 4; ++c) {
        o.lo[a][c] = n.lo[a][c];
        o.hi[a][c] = n.hi[a][c];
      }
    for (int c = 0; c < 4; ++c) {
      o.child[c] = n.child[c];
      o.count[c] = n.count[c];
      // Children are stored after their parent (Bvh4::build), so a parent's level is known here.
      if ((n.valid & (1u << c)) && n.count[c] == 0 && n.child[c] < nodes.size()) level[n.child[c]] = level[i] + 1;
    }
    o.valid = n.valid;
    o.reserved[0] = o.reserved[1] = o.reserved[2] = 0;
    h.depth = std::max(h.depth, level[i]);
  }
  h.order = impl_->bvh.prims();
  h.maxRadius = impl_->maxRadius;
  return h;
}

}  // namespace vff
