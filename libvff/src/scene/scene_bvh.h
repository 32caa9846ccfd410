// scene_bvh.h - the top-level hierarchy of a vff::Scene (vff/scene.h): boxes around the instances'
// world spheres, built with a binned surface-area heuristic and stored four children to a node,
// so that a ray tests the four child boxes of a node at once in SSE2 lanes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define VFF_SCENE_SSE2 1
#endif

#include "vff/query.h"

namespace vff::detail {

struct Box {
  float lo[3], hi[3];
};

// A node of four children. Child c is an inner node when count[c] == 0 (child[c] indexes nodes),
// a leaf when count[c] > 0 (the primitives prims[child[c]] .. prims[child[c] + count[c] - 1]), and
// absent when bit c of valid is clear.
struct alignas(16) Node4 {
  float lo[3][4], hi[3][4];
  uint32_t child[4];
  uint32_t count[4];
  unsigned valid;  // bit c: child c exists
};

// A ray prepared for the box tests: eight floats, so that a vector kernel loads a ray in one go.
struct alignas(32) BoxRay {
  float origin[3], inv[3];
  float tmax;
  float unused = 0;
};

BoxRay boxRay(const Ray& ray) noexcept;

// A batch's rays for Bvh4::collect, each as boxRay makes it.
struct BoxRays {
  std::vector<BoxRay> data;
  void assign(std::span<const Ray> rays);
};

// One node's step of Bvh4::collect: the rays in[0, m) (indices into `rays`, a BoxRays' data as
// eight floats a ray) tested against the node's four boxes as hitNode4 tests them, each with its
// own tmax; those that reach child c are appended, in their order, to list + c * stride from
// count[c] on (count[c] grows by their number). A kernel may write up to 15 entries past a list's
// new end: stride is at least m + 16. Plain pointers: a kernel compiled for wider instructions
// instantiates no inline function of the baseline's.
using CollectNodeFn = void (*)(const Node4& node, const float* rays, const uint32_t* in, uint32_t m, uint32_t* list,
                               size_t stride, uint32_t* count);
void collectNodeScalar(const Node4& node, const float* rays, const uint32_t* in, uint32_t m, uint32_t* list,
                       size_t stride, uint32_t* count) noexcept;
// The same in AVX-512 lanes, sixteen rays at a time (scene_bvh_avx512.cpp), where this CPU and build
// have AVX-512 and forceGroupKernel (query_group.h) asks for no narrower kernel; else null.
CollectNodeFn collectNodeAvx512Fn() noexcept;

// What Bvh4::collect finds for a batch of rays: call c says that the rays
// rays[first[c], first[c] + count[c]) (indices into the batch, ascending) reach primitive prim[c];
// each primitive reached by any ray has one call. The rest is working space kept between batches.
struct RayLists {
  std::vector<uint32_t> prim, first, count, rays;
  struct Item {
    uint32_t node, begin, end;  // a node and its rays: arena[begin, end)
  };
  std::vector<uint32_t> arena;
  std::vector<Item> stack;
};

// A node of the binary hierarchy Bvh4::build makes first (and then collapses to four children a
// node): inner with children left and right, or a leaf of primitives prims[start, start + count).
struct BinaryNode {
  Box box;
  uint32_t left = 0, right = 0;
  uint32_t start = 0, count = 0;  // count > 0: a leaf
};

// A primitive's box as Bvh4::build moves it while splitting: two rows of four floats (the fourth
// zero), so that the builder grows its boxes a row at a time.
struct alignas(16) PrimRef {
  float lo[4], hi[4];
  float centre(int axis) const noexcept { return (lo[axis] + hi[axis]) * 0.5f; }
};

class Bvh4 {
 public:
  static constexpr int kMaxDepth = 96;
  // Rebuilds over `boxes` (primitive i is boxes[i]). Deterministic: the same boxes give the same
  // hierarchy.
  void build(const std::vector<Box>& boxes);
  bool empty() const noexcept { return nodes_.empty(); }
  const std::vector<Node4>& nodes() const noexcept { return nodes_; }
  const std::vector<uint32_t>& prims() const noexcept { return prims_; }

  // Calls visit(prim) for every primitive whose box the segment [0, tmax] of the ray reaches,
  // nearest child first. visit returns the new tmax (the caller's best hit so far, or the same
  // value to see everything); a negative value stops the walk.
  template <class Visit>
  void walk(const BoxRay& r, Visit&& visit) const;
  // For a batch of rays, what walk() visits for each with a visit that never lowers tmax, found
  // for all of them at once: the batch goes down the tree as a stream, each node testing the rays
  // that reached it against its four boxes, so that a node is read once for the batch and no ray
  // keeps a stack of its own.
  // `step` steps each node (collectNodeScalar or a vector kernel of the same answers; null: the
  // widest this CPU runs).
  void collect(const BoxRays& rays, RayLists* out, CollectNodeFn step = nullptr) const;

 private:
  std::vector<Node4> nodes_;
  std::vector<uint32_t> prims_;
  // The builder's working memory, kept between builds: a scene rebuilt every frame then finds it
  // already faulted in.
  struct BuildMemory {
    std::vector<PrimRef> refs, refScratch;
    std::vector<uint32_t> idScratch;
    std::vector<std::pair<float, uint32_t>> order;
    std::vector<BinaryNode> nodes;
    std::vector<uint8_t> binIds;
    struct Pending {
      uint32_t binary, slot;
    };
    std::vector<Pending> work;
  } memory_;
};

// The entry distances of the ray into the four boxes of a node, and which it reaches within
// [0, tmax] (bit c of the result).
// Inline: the walks call it for every ray at every node.
inline unsigned hitNode4(const Node4& n, const BoxRay& r, float tmax, float entry[4]) noexcept {
#if VFF_SCENE_SSE2
  __m128 tn = _mm_setzero_ps(), tf = _mm_set1_ps(tmax);
  for (int a = 0; a < 3; ++a) {
    const __m128 o = _mm_set1_ps(r.origin[a]), inv = _mm_set1_ps(r.inv[a]);
    const __m128 t1 = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.lo[a]), o), inv);
    const __m128 t2 = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.hi[a]), o), inv);
    tn = _mm_max_ps(tn, _mm_min_ps(t1, t2));
    tf = _mm_min_ps(tf, _mm_max_ps(t1, t2));
  }
  _mm_storeu_ps(entry, tn);
  return unsigned(_mm_movemask_ps(_mm_cmple_ps(tn, tf)));
#else
  unsigned mask = 0;
  for (int c = 0; c < 4; ++c) {
    float tn = 0, tf = tmax;
    for (int a = 0; a < 3; ++a) {
      const float t1 = (n.lo[a][c] - r.origin[a]) * r.inv[a], t2 = (n.hi[a][c] - r.origin[a]) * r.inv[a];
      tn = std::max(tn, std::min(t1, t2));
      tf = std::min(tf, std::max(t1, t2));
    }
    entry[c] = tn;
    if (tn <= tf) mask |= 1u << c;
  }
  return mask;
#endif
}

template <class Visit>
void Bvh4::walk(const BoxRay& r, Visit&& visit) const {
  if (nodes_.empty()) return;
  // Stack items: an inner node, or (kLeaf | node << 2 | child) for a leaf child of a node.
  constexpr uint32_t kLeaf = 0x80000000u;
  struct Item {
    uint32_t ref;
    float entry;
  };
  // At most three items per level stay behind; build() keeps the depth under kMaxDepth.
  Item stack[3 * kMaxDepth + 4];
  int top = 0;
  stack[top++] = {0, 0.0f};
  float tmax = r.tmax;
  while (top > 0) {
    const Item it = stack[--top];
    if (it.entry > tmax) continue;
    if (it.ref & kLeaf) {
      const Node4& p = nodes_[(it.ref & ~kLeaf) >> 2];
      const uint32_t c = it.ref & 3u;
      for (uint32_t i = 0; i < p.count[c]; ++i) {
        tmax = visit(prims_[p.child[c] + i]);
        if (tmax < 0) return;
      }
      continue;
    }
    const Node4& n = nodes_[it.ref];
    float entry[4];
    const unsigned mask = hitNode4(n, r, tmax, entry) & n.valid;
    uint32_t order[4];
    int k = 0;
    for (uint32_t c = 0; c < 4; ++c)
      if (mask & (1u << c)) order[k++] = c;
    for (int a = 1; a < k; ++a)
      for (int b = a; b > 0 && entry[order[b]] < entry[order[b - 1]]; --b) std::swap(order[b], order[b - 1]);
    for (int a = k - 1; a >= 0; --a) {  // the nearest child ends on top
      const uint32_t c = order[a];
      stack[top++] = {n.count[c] == 0 ? n.child[c] : (kLeaf | (it.ref << 2) | c), entry[c]};
    }
  }
}

}  // namespace vff::detail
