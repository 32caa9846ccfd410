// triangle_bvh.cpp - the refined query's exact step: building the triangle BVH and casting rays
// through it (triangle_bvh.h).
#include "refine/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace vff::detail {
namespace {

constexpr uint32_t kBins = 16;
// A triangle test's cost against a node visit's (two box tests), in the surface-area heuristic:
// below 1, leaves stay fuller, so the BVH has fewer nodes (memory the refined field's budget
// pays for) at a few more triangle tests a ray.
constexpr double kTriangleCost = 0.5;
// Below this depth the builder splits by the surface-area heuristic; from it on at the median,
// so that no path is longer than the casts' stack (kMaxDepth) whatever the triangles.
constexpr uint32_t kMedianDepth = 40;

struct Box {
  float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                 std::numeric_limits<float>::infinity()};
  float hi[3] = {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                 -std::numeric_limits<float>::infinity()};
  void add(const float* p) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  void add(const Box& b) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b.lo[a]), hi[a] = std::max(hi[a], b.hi[a]);
  }
  double area() const {
    if (!(hi[0] >= lo[0])) return 0;
    const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
    return 2 * (x * y + y * z + z * x);
  }
};

struct Prim {
  Box box;
  float c[3];  // centroid
  uint32_t tri;
};

struct Task {
  uint32_t begin, end, node, depth;
  uint32_t parent;  // for a second child, made when popped: the inner node that names it
};

inline Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

}  // namespace

TriangleBvh::TriangleBvh(std::span<const float> positions, std::span<const uint32_t> indices) : pos_(positions) {
  const uint32_t n = uint32_t(indices.size() / 3);
  if (n == 0) return;
  std::vector<Prim> prims(n);
  for (uint32_t t = 0; t < n; ++t) {
    Prim& p = prims[t];
    for (int v = 0; v < 3; ++v) p.box.add(&positions[size_t(indices[3 * t + v]) * 3]);
    for (int a = 0; a < 3; ++a) p.c[a] = 0.5f * (p.box.lo[a] + p.box.hi[a]);
    p.tri = t;
  }
  nodes_.reserve(size_t(n) * 2 / kMaxLeaf * 2 + 1);
  nodes_.push_back({});
  std::vector<Task> stack{{0, n, 0, 0, UINT32_MAX}};
  std::vector<Prim> ordered;
  ordered.reserve(n);
  while (!stack.empty()) {
    Task task = stack.back();
    stack.pop_back();
    if (task.node == UINT32_MAX) {  // a second child: numbered after its sibling's subtree
      task.node = uint32_t(nodes_.size());
      nodes_.push_back({});
      nodes_[task.parent].first = task.node;
    }
    Box bounds, centroids;
    for (uint32_t i = task.begin; i < task.end; ++i) {
      bounds.add(prims[i].box);
      centroids.add(prims[i].c);
    }
    for (int a = 0; a < 3; ++a) nodes_[task.node].lo[a] = bounds.lo[a], nodes_[task.node].hi[a] = bounds.hi[a];
    const uint32_t count = task.end - task.begin;
    // The split: the best of kBins - 1 planes per axis by the surface-area heuristic.
    int bestAxis = -1;
    uint32_t bestPlane = 0;
    double bestCost = kTriangleCost * double(count);  // a leaf's cost, in node visits
    if (count > 1 && task.depth < kMedianDepth) {
      for (int a = 0; a < 3; ++a) {
        const float extent = centroids.hi[a] - centroids.lo[a];
        if (!(extent > 0)) continue;
        Box bin[kBins];
        uint32_t binCount[kBins] = {};
        const float scale = float(kBins) / extent;
        for (uint32_t i = task.begin; i < task.end; ++i) {
          const uint32_t b = std::min(kBins - 1, uint32_t((prims[i].c[a] - centroids.lo[a]) * scale));
          bin[b].add(prims[i].box);
          ++binCount[b];
        }
        double rightArea[kBins];
        uint32_t rightCount[kBins];
        Box acc;
        uint32_t cnt = 0;
        for (uint32_t b = kBins - 1; b > 0; --b) {
          acc.add(bin[b]);
          cnt += binCount[b];
          rightArea[b] = acc.area();
          rightCount[b] = cnt;
        }
        Box left;
        uint32_t leftCount = 0;
        const double parent = bounds.area() > 0 ? bounds.area() : 1.0;
        for (uint32_t b = 1; b < kBins; ++b) {
          left.add(bin[b - 1]);
          leftCount += binCount[b - 1];
          if (leftCount == 0 || rightCount[b] == 0) continue;
          const double cost = 1.0 + kTriangleCost * (left.area() * leftCount + rightArea[b] * rightCount[b]) / parent;
          if (cost < bestCost) bestCost = cost, bestAxis = a, bestPlane = b;
        }
      }
    }
    uint32_t mid = 0;
    if (bestAxis >= 0) {
      const int a = bestAxis;
      const float scale = float(kBins) / (centroids.hi[a] - centroids.lo[a]);
      auto inLeft = [&](const Prim& p) {
        return std::min(kBins - 1, uint32_t((p.c[a] - centroids.lo[a]) * scale)) < bestPlane;
      };
      mid = uint32_t(std::stable_partition(prims.begin() + task.begin, prims.begin() + task.end, inLeft) - prims.begin());
    } else if (count > kMaxLeaf) {
      // No plane pays (or the depth is spent) but the leaf would be too large: split at the median
      // of the widest centroid axis.
      int a = 0;
      for (int b = 1; b < 3; ++b)
        if (centroids.hi[b] - centroids.lo[b] > centroids.hi[a] - centroids.lo[a]) a = b;
      mid = task.begin + count / 2;
      std::nth_element(prims.begin() + task.begin, prims.begin() + mid, prims.begin() + task.end,
                       [a](const Prim& x, const Prim& y) { return x.c[a] < y.c[a] || (x.c[a] == y.c[a] && x.tri < y.tri); });
    }
    if (mid == 0) {
      nodes_[task.node].first = uint32_t(ordered.size());
      nodes_[task.node].count = count;
      for (uint32_t i = task.begin; i < task.end; ++i) ordered.push_back(prims[i]);
      continue;
    }
    // Depth-first: the first child right after its parent, the second after the first's subtree.
    // The stack takes the second child first so the first is built (and numbered) next.
    const uint32_t first = uint32_t(nodes_.size());
    nodes_.push_back({});
    nodes_[task.node].count = 0;
    stack.push_back({mid, task.end, UINT32_MAX, task.depth + 1, task.node});
    stack.push_back({task.begin, mid, first, task.depth + 1, UINT32_MAX});
  }
  tris_.resize(size_t(n) * 3);
  for (uint32_t t = 0; t < n; ++t)
    for (int v = 0; v < 3; ++v) tris_[3 * t + v] = indices[3 * size_t(ordered[t].tri) + v];
}

// A depth-first walk, nearer child first, the triangles tested by triangleHit.
template <bool kAny>
bool TriangleBvh::cast(Vec3 o, Vec3 d, float tmin, float tmax, float* tOut, uint32_t* triOut) const noexcept {
  if (nodes_.empty() || !(tmax >= tmin)) return false;
  const Vec3 inv{1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
  // Entry distance of the ray into a node's box within [tmin, best], or +inf.
  auto enter = [&](const BvhNode& n, float best) {
    float t0 = tmin, t1 = best;
    const float lo[3] = {n.lo[0], n.lo[1], n.lo[2]}, hi[3] = {n.hi[0], n.hi[1], n.hi[2]};
    const float org[3] = {o.x, o.y, o.z}, iv[3] = {inv.x, inv.y, inv.z};
    for (int a = 0; a < 3; ++a) {
      float u = (lo[a] - org[a]) * iv[a], v = (hi[a] - org[a]) * iv[a];
      if (u > v) std::swap(u, v);
      // (NaN from 0 * inf: an axis-parallel ray on a box face; the max/min keep the other bound.)
      t0 = u > t0 ? u : t0;
      t1 = v < t1 ? v : t1;
    }
    return t0 <= t1 ? t0 : std::numeric_limits<float>::infinity();
  };
  float best = tmax;
  bool found = false;
  uint32_t stack[kMaxDepth];
  uint32_t top = 0, node = 0;
  if (enter(nodes_[0], best) == std::numeric_limits<float>::infinity()) return false;
  for (;;) {
    const BvhNode& n = nodes_[node];
    if (n.count == 0) {
      const uint32_t a = node + 1, b = n.first;
      const float ta = enter(nodes_[a], best), tb = enter(nodes_[b], best);
      const bool hitA = ta != std::numeric_limits<float>::infinity(), hitB = tb != std::numeric_limits<float>::infinity();
      if (hitA && hitB) {
        const bool aFirst = ta <= tb;
        node = aFirst ? a : b;
        stack[top++] = aFirst ? b : a;
        continue;
      }
      if (hitA || hitB) {
        node = hitA ? a : b;
        continue;
      }
    } else {
      uint32_t tri = 0;
      if (leafHit<kAny>(o, d, pos_.data(), tris_.data(), n.first, n.count, tmin, &best, &tri)) {
        if constexpr (kAny) return true;
        found = true;
        *triOut = tri;
      }
    }
    // Next: the nearest postponed node that the ray still enters before the best hit.
    for (;;) {
      if (top == 0) {
        if (found) *tOut = best;
        return found;
      }
      node = stack[--top];
      if (kAny || enter(nodes_[node], best) != std::numeric_limits<float>::infinity()) break;
    }
  }
}

Vec3 triangleNormal(Vec3 v0, Vec3 v1, Vec3 v2, Vec3 d) noexcept {
  Vec3 n = cross(sub(v1, v0), sub(v2, v0));
  const float len = std::sqrt(dot3(n, n));
  n = len > 0 ? Vec3{n.x / len, n.y / len, n.z / len} : Vec3{};
  if (dot3(n, d) > 0) n = {-n.x, -n.y, -n.z};
  return n;
}

bool TriangleBvh::occluded(Vec3 o, Vec3 d, float tmin, float tmax) const noexcept {
  return cast<true>(o, d, tmin, tmax, nullptr, nullptr);
}

bool TriangleBvh::intersect(Vec3 o, Vec3 d, float tmin, float tmax, float* t, Vec3* normal) const noexcept {
  uint32_t tri = 0;
  if (!cast<false>(o, d, tmin, tmax, t, &tri)) return false;
  const float* p = pos_.data();
  auto vert = [p](uint32_t v) { return Vec3{p[3 * size_t(v)], p[3 * size_t(v) + 1], p[3 * size_t(v) + 2]}; };
  const uint32_t* v = &tris_[3 * size_t(tri)];
  const Vec3 n = triangleNormal(vert(v[0]), vert(v[1]), vert(v[2]), d);
  *normal = n;
  return true;
}

}  // namespace vff::detail
