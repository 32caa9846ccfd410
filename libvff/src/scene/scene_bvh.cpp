// scene_bvh.cpp - building and testing the scene's top-level hierarchy (scene_bvh.h).
#include "scene/scene_bvh.h"

#include "platform/cpu_features.h"
#include "query/batch/query_group.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vff::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kBins = 16;
// One instance a leaf: a batch pairs a ray with every instance of a leaf it reaches, so a larger
// leaf pairs rays with neighbours whose own boxes they miss.
constexpr uint32_t kLeafSize = 1;

Box emptyBox() { return Box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}}; }

float area(const Box& b) {
  const float x = b.hi[0] - b.lo[0], y = b.hi[1] - b.lo[1], z = b.hi[2] - b.lo[2];
  if (!(x >= 0) || !(y >= 0) || !(z >= 0)) return 0;
  return x * y + y * z + z * x;
}

// Four floats, of which the builder uses three (the fourth is zero or ignored): a box corner or a
// centre, taken in one SSE2 operation where there is SSE2. min and max are exact, so both forms
// build the same hierarchy.
#if VFF_SCENE_SSE2
struct V4 {
  __m128 v;
};
inline V4 load4(const float* p) { return {_mm_load_ps(p)}; }
inline void store4(float* p, V4 a) { _mm_store_ps(p, a.v); }
inline V4 splat4(float f) { return {_mm_set1_ps(f)}; }
inline V4 min4(V4 a, V4 b) { return {_mm_min_ps(a.v, b.v)}; }
inline V4 max4(V4 a, V4 b) { return {_mm_max_ps(a.v, b.v)}; }
inline V4 mid4(V4 a, V4 b) { return {_mm_mul_ps(_mm_add_ps(a.v, b.v), _mm_set1_ps(0.5f))}; }
#else
struct V4 {
  float v[4];
};
inline V4 load4(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
inline void store4(float* p, V4 a) { std::copy(a.v, a.v + 4, p); }
inline V4 splat4(float f) { return {{f, f, f, f}}; }
inline V4 min4(V4 a, V4 b) {
  for (int i = 0; i < 4; ++i) a.v[i] = std::min(a.v[i], b.v[i]);
  return a;
}
inline V4 max4(V4 a, V4 b) {
  for (int i = 0; i < 4; ++i) a.v[i] = std::max(a.v[i], b.v[i]);
  return a;
}
inline V4 mid4(V4 a, V4 b) {
  V4 m;
  for (int i = 0; i < 4; ++i) m.v[i] = (a.v[i] + b.v[i]) * 0.5f;
  return m;
}
#endif

// A box of the builder: of primitives, or of their centres.
struct Box4 {
  V4 lo = splat4(kInf), hi = splat4(-kInf);
  void grow(V4 l, V4 h) { lo = min4(lo, l), hi = max4(hi, h); }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  Box box() const {
    alignas(16) float l[4], h[4];
    store4(l, lo), store4(h, hi);
    return Box{{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
  }
};

float area(const Box4& b) { return area(b.box()); }

struct Builder {
  std::vector<PrimRef>& refs;        // the primitives' boxes, each beside its id in `ids`
  std::vector<uint32_t>& ids;        // the primitives, reordered as the nodes split them
  std::vector<PrimRef>& refScratch;  // the right side of a partition
  std::vector<uint32_t>& idScratch;
  std::vector<std::pair<float, uint32_t>>& order;  // a middle split's (centre, position) pairs
  std::vector<BinaryNode>& nodes;
  std::vector<uint8_t>& binIds;      // each primitive's bin, by position in the node's range

  static V4 lo(const PrimRef& r) { return load4(r.lo); }
  static V4 hi(const PrimRef& r) { return load4(r.hi); }
  // The boxes around primitives [start, start + count) and around their centres.
  void bounds(uint32_t start, uint32_t count, Box4* box, Box4* cbox) const {
    *box = Box4{}, *cbox = Box4{};
    for (uint32_t i = start; i < start + count; ++i) {
      const V4 l = lo(refs[i]), h = hi(refs[i]), c = mid4(l, h);
      box->grow(l, h);
      cbox->grow(c, c);
    }
  }

  // The node over primitives [start, start + count), whose bounds are `box` and `cbox` (a split
  // hands its children theirs, from the bins: each primitive is visited twice a level, to bin it
  // and to move it).
  uint32_t build(uint32_t start, uint32_t count, int depth, const Box4& box, const Box4& cbox) {
    const uint32_t id = uint32_t(nodes.size());
    nodes.emplace_back();
    nodes[id].box = box.box();
    if (count <= kLeafSize) {
      nodes[id].start = start;
      nodes[id].count = count;
      return id;
    }
    uint32_t mid = 0;
    const Box cb = cbox.box();
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (cb.hi[a] - cb.lo[a] > cb.hi[axis] - cb.lo[axis]) axis = a;
    const float extent = cb.hi[axis] - cb.lo[axis];
    PrimRef* p = refs.data() + start;
    uint32_t* pid = ids.data() + start;
    Box4 side[2][2];  // [left, right][box, centre box] of the chosen split
    // (Two primitives: the split binning would find, when it finds one, is the middle split's.)
    if (extent > 0 && depth < 48 && count > 2) {
      // Binned SAH on the widest centroid axis, with fewer bins for fewer primitives (a node's
      // sweeps cost as much per bin as its binning costs per primitive).
      const int bins = count < uint32_t(kBins) ? std::max(4, int(count)) : kBins;
      Box4 binBox[kBins], binCentres[kBins];
      uint32_t binCount[kBins] = {};
      const float scale = float(bins) / extent;
      binIds.resize(count);
      for (uint32_t i = 0; i < count; ++i) {
        // Written so that a huge or NaN product (a tiny extent) never reaches the conversion.
        const float f = (p[i].centre(axis) - cb.lo[axis]) * scale;
        const int bin = f >= float(bins - 1) ? bins - 1 : (f > 0 ? int(f) : 0);
        binIds[i] = uint8_t(bin);
        ++binCount[bin];
        const V4 l = lo(p[i]), h = hi(p[i]), c = mid4(l, h);
        binBox[bin].grow(l, h);
        binCentres[bin].grow(c, c);
      }
      uint32_t rightCount[kBins];
      Box4 rightBox[kBins], rightCentres[kBins];
      Box4 acc, accCentres;
      uint32_t n = 0;
      for (int b = bins - 1; b > 0; --b) {
        acc.grow(binBox[b]);
        accCentres.grow(binCentres[b]);
        n += binCount[b];
        rightCount[b] = n;
        rightBox[b] = acc, rightCentres[b] = accCentres;
      }
      acc = Box4{}, accCentres = Box4{};
      n = 0;
      float best = kInf;
      int bestSplit = -1;
      for (int b = 1; b < bins; ++b) {
        acc.grow(binBox[b - 1]);
        accCentres.grow(binCentres[b - 1]);
        n += binCount[b - 1];
        if (n == 0 || rightCount[b] == 0) continue;
        const float cost = area(acc) * float(n) + area(rightBox[b]) * float(rightCount[b]);
        if (cost < best) {
          best = cost;
          bestSplit = b;
          side[0][0] = acc, side[0][1] = accCentres, side[1][0] = rightBox[b], side[1][1] = rightCentres[b];
        }
      }
      if (bestSplit > 0) {
        // A stable partition through the builder's scratch, without a branch: each primitive is
        // written to both sides and only its own side's end moves (the sides are random bits,
        // which a branch mispredicts half the time).
        refScratch.resize(count);
        idScratch.resize(count);
        uint32_t nLeft = 0, nRight = 0;
        for (uint32_t i = 0; i < count; ++i) {
          const PrimRef r = p[i];
          const uint32_t prim = pid[i], right = binIds[i] >= bestSplit ? 1u : 0u;
          p[nLeft] = r, pid[nLeft] = prim;
          refScratch[nRight] = r, idScratch[nRight] = prim;
          nLeft += 1u - right;
          nRight += right;
        }
        std::copy(refScratch.begin(), refScratch.begin() + nRight, p + nLeft);
        std::copy(idScratch.begin(), idScratch.begin() + nRight, pid + nLeft);
        mid = nLeft;
      }
    }
    if (mid == 0 || mid == count) {
      // Coincident centroids or a deep branch: split in the middle, in a fixed order (centre,
      // then id), through the scratch: a partial sort of (centre, position) pairs.
      mid = count / 2;
      order.resize(count);
      for (uint32_t i = 0; i < count; ++i) order[i] = {p[i].centre(axis), i};
      std::nth_element(order.begin(), order.begin() + mid, order.end(), [&](const auto& a, const auto& b) {
        return a.first < b.first || (a.first == b.first && pid[a.second] < pid[b.second]);
      });
      refScratch.resize(count);
      idScratch.resize(count);
      for (uint32_t i = 0; i < count; ++i) refScratch[i] = p[order[i].second], idScratch[i] = pid[order[i].second];
      std::copy(refScratch.begin(), refScratch.begin() + count, p);
      std::copy(idScratch.begin(), idScratch.begin() + count, pid);
      bounds(start, mid, &side[0][0], &side[0][1]);
      bounds(start + mid, count - mid, &side[1][0], &side[1][1]);
    }
    const uint32_t l = build(start, mid, depth + 1, side[0][0], side[0][1]);
    const uint32_t r = build(start + mid, count - mid, depth + 1, side[1][0], side[1][1]);
    nodes[id].left = l;
    nodes[id].right = r;
    return id;
  }
};

}  // namespace

BoxRay boxRay(const Ray& ray) noexcept {
  BoxRay r;
  const float o[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const float d[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  for (int a = 0; a < 3; ++a) {
    r.origin[a] = o[a];
    // A zero component becomes a tiny one: the slab test then never forms 0 * inf.
    const float da = d[a] == 0 ? 1e-30f : d[a];
    r.inv[a] = 1.0f / da;
  }
  r.tmax = ray.tmax;
  return r;
}

void Bvh4::build(const std::vector<Box>& boxes) {
  nodes_.clear();
  prims_.resize(boxes.size());
  for (uint32_t i = 0; i < prims_.size(); ++i) prims_[i] = i;
  if (boxes.empty()) return;
  BuildMemory& mem = memory_;
  mem.refs.resize(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    PrimRef& r = mem.refs[i];
    for (int a = 0; a < 3; ++a) r.lo[a] = boxes[i].lo[a], r.hi[a] = boxes[i].hi[a];
    r.lo[3] = r.hi[3] = 0;
  }
  mem.nodes.clear();
  mem.nodes.reserve(2 * boxes.size());
  Builder b{mem.refs, prims_, mem.refScratch, mem.idScratch, mem.order, mem.nodes, mem.binIds};
  Box4 all, allCentres;
  b.bounds(0, uint32_t(boxes.size()), &all, &allCentres);
  b.build(0, uint32_t(boxes.size()), 0, all, allCentres);
  // Collapse to four children a node: open the child of largest area until there are four.
  using Pending = BuildMemory::Pending;
  std::vector<Pending>& work = mem.work;
  work.assign(1, {0, 0});
  nodes_.reserve(b.nodes.size() / 2 + 1);
  while (!work.empty()) {
    const Pending w = work.back();
    work.pop_back();
    uint32_t kids[4];
    int k = 0;
    const BinaryNode& root = b.nodes[w.binary];
    if (root.count > 0) {
      kids[k++] = w.binary;  // a lone leaf (a scene of one or two instances)
    } else {
      kids[k++] = root.left;
      kids[k++] = root.right;
      while (k < 4) {
        int open = -1;
        float best = -1;
        for (int i = 0; i < k; ++i)
          if (b.nodes[kids[i]].count == 0 && area(b.nodes[kids[i]].box) > best) {
            best = area(b.nodes[kids[i]].box);
            open = i;
          }
        if (open < 0) break;
        const BinaryNode& o = b.nodes[kids[open]];
        kids[open] = o.left;
        kids[k++] = o.right;
      }
    }
    const uint32_t id = uint32_t(nodes_.size());
    nodes_.emplace_back();
    if (w.binary != 0) nodes_[w.slot >> 2].child[w.slot & 3] = id;
    Node4& n = nodes_[id];
    n.valid = (1u << k) - 1;
    for (int c = 0; c < 4; ++c) {
      const Box box = c < k ? b.nodes[kids[c]].box : emptyBox();
      for (int a = 0; a < 3; ++a) {
        n.lo[a][c] = box.lo[a];
        n.hi[a][c] = box.hi[a];
      }
      n.child[c] = 0;
      n.count[c] = 0;
      if (c >= k) continue;
      const BinaryNode& kid = b.nodes[kids[c]];
      if (kid.count > 0) {
        n.child[c] = kid.start;
        n.count[c] = kid.count;
      } else {
        work.push_back({kids[c], (id << 2) | uint32_t(c)});
      }
    }
  }
}

void BoxRays::assign(std::span<const Ray> rays) {
  data.resize(rays.size());
  size_t r = 0;
#if VFF_SCENE_SSE2
  // Four rays at a time, as boxRay makes each (a division rounds the same in any lane): their
  // halves transposed into components, the direction's inverted, and transposed back.
  static_assert(sizeof(Ray) == 8 * sizeof(float) && sizeof(BoxRay) == 8 * sizeof(float));
  const float* in = reinterpret_cast<const float*>(rays.data());
  float* out = reinterpret_cast<float*>(data.data());
  const __m128 zero = _mm_setzero_ps(), tiny = _mm_set1_ps(1e-30f), one = _mm_set1_ps(1.0f);
  auto inverse = [&](__m128 d) {
    const __m128 isZero = _mm_cmpeq_ps(d, zero);
    return _mm_div_ps(one, _mm_or_ps(_mm_and_ps(isZero, tiny), _mm_andnot_ps(isZero, d)));
  };
  for (; r + 4 <= rays.size(); r += 4) {
    const float* p = in + 8 * r;
    __m128 ox = _mm_loadu_ps(p), oy = _mm_loadu_ps(p + 8), oz = _mm_loadu_ps(p + 16), dx = _mm_loadu_ps(p + 24);
    __m128 dy = _mm_loadu_ps(p + 4), dz = _mm_loadu_ps(p + 12), tmin = _mm_loadu_ps(p + 20), tmax = _mm_loadu_ps(p + 28);
    _MM_TRANSPOSE4_PS(ox, oy, oz, dx);
    _MM_TRANSPOSE4_PS(dy, dz, tmin, tmax);
    __m128 ix = inverse(dx), iy = inverse(dy), iz = inverse(dz), unused = zero;
    _MM_TRANSPOSE4_PS(ox, oy, oz, ix);          // each ray's origin and inverse x
    _MM_TRANSPOSE4_PS(iy, iz, tmax, unused);  // each ray's inverse y, z, tmax
    float* q = out + 8 * r;
    _mm_storeu_ps(q, ox), _mm_storeu_ps(q + 4, iy), _mm_storeu_ps(q + 8, oy), _mm_storeu_ps(q + 12, iz);
    _mm_storeu_ps(q + 16, oz), _mm_storeu_ps(q + 20, tmax), _mm_storeu_ps(q + 24, ix), _mm_storeu_ps(q + 28, unused);
  }
#endif
  for (; r < rays.size(); ++r) data[r] = boxRay(rays[r]);
}

void collectNodeScalar(const Node4& node, const float* rays, const uint32_t* in, uint32_t m, uint32_t* list,
                       size_t stride, uint32_t* count) noexcept {
  const BoxRay* boxRays = reinterpret_cast<const BoxRay*>(rays);
  float entry[4];
  for (uint32_t i = 0; i < m; ++i) {
    const uint32_t r = in[i];
    const unsigned mask = hitNode4(node, boxRays[r], boxRays[r].tmax, entry) & node.valid;
    for (uint32_t c = 0; c < 4; ++c) {  // no branch per child: the masks are random bits
      list[c * stride + count[c]] = r;
      count[c] += (mask >> c) & 1u;
    }
  }
}

#if defined(VFF_HAVE_AVX512_COLLECT)
void collectNodeAvx512(const Node4& node, const float* rays, const uint32_t* in, uint32_t m, uint32_t* list,
                       size_t stride, uint32_t* count) noexcept;
CollectNodeFn collectNodeAvx512Fn() noexcept {
  const KernelChoice k = kernelOverride();
  if (k != KernelChoice::kAuto && k != KernelChoice::kAvx512) return nullptr;
  return cpuFeatures().avx512 ? collectNodeAvx512 : nullptr;
}
#else
CollectNodeFn collectNodeAvx512Fn() noexcept { return nullptr; }
#endif

void Bvh4::collect(const BoxRays& rays, RayLists* out, CollectNodeFn step) const {
  out->prim.clear();
  out->first.clear();
  out->count.clear();
  out->rays.clear();
  if (nodes_.empty() || rays.data.empty()) return;
  if (!step) step = collectNodeAvx512Fn();
  if (!step) step = collectNodeScalar;
  std::vector<uint32_t>& arena = out->arena;
  const uint32_t n = uint32_t(rays.data.size());
  if (arena.size() < n) arena.resize(n);
  for (uint32_t r = 0; r < n; ++r) arena[r] = r;
  out->stack.assign(1, {0, 0, n});
  while (!out->stack.empty()) {
    const RayLists::Item it = out->stack.back();
    out->stack.pop_back();
    // Depth first: everything in the arena above this item's rays belongs to items already done.
    const uint32_t m = it.end - it.begin;
    const size_t base = it.end, stride = size_t(m) + 16;
    if (arena.size() < base + 4 * stride) arena.resize(base + 4 * stride);
    const uint32_t* in = arena.data() + it.begin;
    uint32_t* list = arena.data() + base;  // child c's rays at list[c * stride ...]
    const Node4& node = nodes_[it.node];
    uint32_t count[4] = {0, 0, 0, 0};
    step(node, reinterpret_cast<const float*>(rays.data.data()), in, m, list, stride, count);
    for (uint32_t c = 0; c < 4; ++c) {
      if (count[c] == 0) continue;
      const uint32_t begin = uint32_t(base + c * stride);
      if (node.count[c] == 0) {
        out->stack.push_back({node.child[c], begin, begin + count[c]});
        continue;
      }
      const uint32_t at = uint32_t(out->rays.size());
      out->rays.insert(out->rays.end(), list + c * stride, list + c * stride + count[c]);
      for (uint32_t i = 0; i < node.count[c]; ++i) {
        out->prim.push_back(prims_[node.child[c] + i]);
        out->first.push_back(at);
        out->count.push_back(count[c]);
      }
    }
  }
}

}  // namespace vff::detail
