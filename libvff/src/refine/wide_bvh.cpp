// wide_bvh.cpp - collapsing the binary triangle BVH to four children a node, and casting rays
// through it with four box tests at once (wide_bvh.h).
#include "refine/wide_bvh.h"

#include <bit>
#include <limits>
#include <utility>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define VFF_WIDE_BVH_SSE2 1
#else
#define VFF_WIDE_BVH_SSE2 0
#endif

namespace vff::detail {
namespace {

static_assert(TriangleBvh::kMaxLeaf <= 8, "a leaf's count takes three bits of its reference");

double halfArea(const BvhNode& n) {
  const double x = double(n.hi[0]) - n.lo[0], y = double(n.hi[1]) - n.lo[1], z = double(n.hi[2]) - n.lo[2];
  return x * y + y * z + z * x;
}

// Which of a node's four boxes the ray enters within [tmin, best], as bits; t[c]: child c's entry
// distance. Each lane does what TriangleBvh's scalar box test does, NaN included (an axis-parallel
// ray on a box's face: that axis keeps the other bounds), so both BVHs cull alike.
struct Slabs {
#if VFF_WIDE_BVH_SSE2
  __m128 org[3], inv[3];
  Slabs(Vec3 o, Vec3 d) {
    org[0] = _mm_set1_ps(o.x), org[1] = _mm_set1_ps(o.y), org[2] = _mm_set1_ps(o.z);
    inv[0] = _mm_set1_ps(1.0f / d.x), inv[1] = _mm_set1_ps(1.0f / d.y), inv[2] = _mm_set1_ps(1.0f / d.z);
  }
  unsigned enter(const WideNode& n, float tmin, float best, float* t) const noexcept {
    __m128 t0 = _mm_set1_ps(tmin), t1 = _mm_set1_ps(best);
    for (int a = 0; a < 3; ++a) {
      const __m128 u = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.lo[a]), org[a]), inv[a]);
      const __m128 v = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.hi[a]), org[a]), inv[a]);
      const __m128 swap = _mm_cmpgt_ps(u, v);
      const __m128 near = _mm_or_ps(_mm_and_ps(swap, v), _mm_andnot_ps(swap, u));
      const __m128 far = _mm_or_ps(_mm_and_ps(swap, u), _mm_andnot_ps(swap, v));
      t0 = _mm_max_ps(near, t0);  // near > t0 ? near : t0
      t1 = _mm_min_ps(far, t1);   // far < t1 ? far : t1
    }
    _mm_storeu_ps(t, t0);
    const __m128i none = _mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(n.child)),
                                         _mm_set1_epi32(-1));
    return unsigned(_mm_movemask_ps(_mm_cmple_ps(t0, t1))) & ~unsigned(_mm_movemask_ps(_mm_castsi128_ps(none)));
  }
#else
  float org[3], inv[3];
  Slabs(Vec3 o, Vec3 d) : org{o.x, o.y, o.z}, inv{1.0f / d.x, 1.0f / d.y, 1.0f / d.z} {}
  unsigned enter(const WideNode& n, float tmin, float best, float* t) const noexcept {
    unsigned mask = 0;
    for (int c = 0; c < 4; ++c) {
      float t0 = tmin, t1 = best;
      for (int a = 0; a < 3; ++a) {
        float u = (n.lo[a][c] - org[a]) * inv[a], v = (n.hi[a][c] - org[a]) * inv[a];
        if (u > v) std::swap(u, v);
        t0 = u > t0 ? u : t0;
        t1 = v < t1 ? v : t1;
      }
      t[c] = t0;
      if (t0 <= t1 && n.child[c] != WideBvh::kNone) mask |= 1u << c;
    }
    return mask;
  }
#endif
};

}  // namespace

WideBvh::WideBvh(const TriangleBvh& b) : pos_(b.positions()), tris_(b.triangles().begin(), b.triangles().end()) {
  const std::span<const BvhNode> bin = b.nodes();
  if (bin.empty()) return;
  auto ref = [&](uint32_t i) { return kLeaf | bin[i].first << 3 | (bin[i].count - 1); };
  // Each wide node takes a binary inner node's two children, then opens the largest inner one
  // among its children until it has four (the surface-area order Embree's BVH4 builders use).
  struct Job {
    uint32_t binary, wide;
  };
  std::vector<Job> jobs{{0, 0}};
  nodes_.reserve(bin.size() / 3 + 1);
  nodes_.push_back({});
  while (!jobs.empty()) {
    const Job job = jobs.back();
    jobs.pop_back();
    uint32_t kids[4];
    int n = 0;
    if (bin[job.binary].count != 0) {
      kids[n++] = job.binary;  // the whole BVH is one leaf
    } else {
      kids[n++] = job.binary + 1;
      kids[n++] = bin[job.binary].first;
      while (n < 4) {
        int open = -1;
        double largest = -1;
        for (int c = 0; c < n; ++c) {
          if (bin[kids[c]].count != 0) continue;
          const double area = halfArea(bin[kids[c]]);
          if (area > largest) largest = area, open = c;
        }
        if (open < 0) break;
        const uint32_t inner = kids[open];
        kids[open] = inner + 1;
        kids[n++] = bin[inner].first;
      }
    }
    WideNode w{};
    for (int c = 0; c < 4; ++c) {
      w.child[c] = kNone;
      if (c >= n) continue;
      const BvhNode& k = bin[kids[c]];
      for (int a = 0; a < 3; ++a) w.lo[a][c] = k.lo[a], w.hi[a][c] = k.hi[a];
      if (k.count != 0) {
        w.child[c] = ref(kids[c]);
      } else {
        w.child[c] = uint32_t(nodes_.size());
        nodes_.push_back({});
        jobs.push_back({kids[c], w.child[c]});
      }
    }
    nodes_[job.wide] = w;
  }
}

// A depth-first walk, nearer children first (for the nearest hit), the triangles tested by
// triangleHit as TriangleBvh tests them.
template <bool kAny>
bool WideBvh::cast(Vec3 o, Vec3 d, float tmin, float tmax, float* tOut, uint32_t* triOut) const noexcept {
  if (nodes_.empty() || !(tmax >= tmin)) return false;
  const Slabs slabs(o, d);
  struct Entry {
    uint32_t ref;
    float t;  // where the ray enters the node's box
  };
  // A node leaves at most three children on the stack, and no path is deeper than the binary one.
  Entry stack[3 * TriangleBvh::kMaxDepth + 1];
  uint32_t top = 0, ref = 0;
  float best = tmax;
  bool found = false;
  for (;;) {
    if (!(ref & kLeaf)) {
      const WideNode& n = nodes_[ref];
      alignas(16) float t[4];
      unsigned mask = slabs.enter(n, tmin, best, t);
      if (mask != 0) {
        Entry e[4];
        int c = 0;
        for (; mask; mask &= mask - 1) {
          const int lane = std::countr_zero(mask);
          e[c++] = {n.child[lane], t[lane]};
        }
        if constexpr (!kAny) {
          for (int i = 1; i < c; ++i)  // nearest first; ties keep the lanes' order
            for (int j = i; j > 0 && e[j].t < e[j - 1].t; --j) std::swap(e[j], e[j - 1]);
        }
        for (int i = c - 1; i >= 1; --i) stack[top++] = e[i];
        ref = e[0].ref;
        continue;
      }
    } else {
      uint32_t tri = 0;
      if (leafHit<kAny>(o, d, pos_.data(), tris_.data(), (ref & ~kLeaf) >> 3, (ref & 7u) + 1, tmin, &best, &tri)) {
        if constexpr (kAny) return true;
        found = true;
        *triOut = tri;
      }
    }
    // Next: the nearest postponed node that the ray enters before the best hit.
    for (;;) {
      if (top == 0) {
        if (found) *tOut = best;
        return found;
      }
      const Entry e = stack[--top];
      if (kAny || e.t <= best) {
        ref = e.ref;
        break;
      }
    }
  }
}

bool WideBvh::occluded(Vec3 o, Vec3 d, float tmin, float tmax) const noexcept {
  return cast<true>(o, d, tmin, tmax, nullptr, nullptr);
}

bool WideBvh::intersect(Vec3 o, Vec3 d, float tmin, float tmax, float* t, Vec3* normal) const noexcept {
  uint32_t tri = 0;
  if (!cast<false>(o, d, tmin, tmax, t, &tri)) return false;
  const float* p = pos_.data();
  auto vert = [p](uint32_t v) { return Vec3{p[3 * size_t(v)], p[3 * size_t(v) + 1], p[3 * size_t(v) + 2]}; };
  const uint32_t* v = &tris_[3 * size_t(tri)];
  *normal = triangleNormal(vert(v[0]), vert(v[1]), vert(v[2]), d);
  return true;
}

}  // namespace vff::detail
