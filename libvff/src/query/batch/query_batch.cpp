// query_batch.cpp - the batch calls of FieldQuery (vff/query.h) and the world-space batches of
// Instance: each picks the nearest path (query_batch_nearest.h) or the interpolated one
// (query_batch_interpolated.h) and writes the answers where the caller asked.
#include <algorithm>

#include "query/batch/query_batch_interpolated.h"
#include "query/batch/query_batch_nearest.h"
#include "query/query_impl.h"

namespace vff {
namespace {

// For every byte value b, the 8 bytes (bit l of b) for l = 0 .. 7, little-endian.
struct BitBytes {
  uint64_t word[256];
  constexpr BitBytes() : word() {
    for (unsigned b = 0; b < 256; ++b)
      for (unsigned l = 0; l < 8; ++l) word[b] |= uint64_t((b >> l) & 1u) << (8 * l);
  }
};
constexpr BitBytes kBitBytes{};

// out[r] = bit r of hits (0 or 1), for r < n <= 64.
void writeHitBytes(uint64_t hits, size_t n, uint8_t* out) {
  size_t r = 0;
  for (; r + 8 <= n; r += 8) {
    const uint64_t w = kBitBytes.word[(hits >> r) & 0xFFu];
    for (unsigned l = 0; l < 8; ++l) out[r + l] = uint8_t(w >> (8 * l));  // one 8-byte store
  }
  for (; r < n; ++r) out[r] = uint8_t((hits >> r) & 1u);
}


// Calls batch(objectRays, first) for the rays of `rays` taken to object space by `to`, kChunk at a
// time.
template <size_t kChunk, class Batch>
void inChunks(const detail::ToObject& to, std::span<const Ray> rays, Batch&& batch) {
  Ray local[kChunk];
  for (size_t first = 0; first < rays.size(); first += kChunk) {
    const size_t n = std::min(kChunk, rays.size() - first);
    for (size_t r = 0; r < n; ++r) local[r] = to.ray(rays[first + r]);
    batch(std::span<const Ray>(local, n), first);
  }
}

// Calls batch(objectRays, first) for rays in chunks, taken to object space by x (none: the rays
// are in object space, one call). A small batch (an Embree callback's) gets a small chunk, which
// costs less to set up.
template <class Batch>
void inObjectSpace(const RigidTransform* x, std::span<const Ray> rays, Batch&& batch) {
  if (!x) {
    batch(rays, size_t(0));
    return;
  }
  const detail::ToObject to(*x);
  if (rays.size() <= 16) {
    inChunks<16>(to, rays, batch);
  } else {
    inChunks<256>(to, rays, batch);
  }
}

// fn(to) with x taken apart (null for none).
template <class Fn>
void withToObject(const RigidTransform* x, Fn&& fn) {
  if (x) {
    const detail::ToObject to(*x);
    fn(&to);
  } else {
    fn(static_cast<const detail::ToObject*>(nullptr));
  }
}

}  // namespace

void FieldQuery::Impl::intersectBatch(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& o,
                                      const RigidTransform* x) const noexcept {
  if (o.reconstruction != Reconstruction::kInterpolated) {
    withToObject(x, [&](const detail::ToObject* to) {
      batchNearest<false>(rays, o, to, [&](size_t r, const QueryHit& h, float) {
        out[r] = h;
        if (x) detail::toWorld(*x, rays[r], &out[r]);
      });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit& h, float) {
      out[first + r] = h;
      if (x) detail::toWorld(*x, rays[first + r], &out[first + r]);
    });
  });
}

void FieldQuery::Impl::occludedBatch(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& o,
                                     const RigidTransform* x) const noexcept {
  if (o.reconstruction != Reconstruction::kInterpolated) {  // (kRefined: batchNearest's refined steps)
    withToObject(x, [&](const detail::ToObject* to) {
      batchNearest<true>(rays, o, to,
                         [&](size_t base, size_t count, uint64_t hits) { writeHitBytes(hits, count, &out[base]); });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit& h, float) { out[first + r] = h.hit ? 1 : 0; });
  });
}

void FieldQuery::Impl::visibilityBatch(std::span<const Ray> rays, std::span<float> out, const QueryOptions& o,
                                       const RigidTransform* x) const noexcept {
  if (o.reconstruction != Reconstruction::kInterpolated) {
    withToObject(x, [&](const detail::ToObject* to) {
      batchNearest<true>(rays, o, to, [&](size_t base, size_t count, uint64_t hits) {
        for (size_t r = 0; r < count; ++r) out[base + r] = (hits >> r) & 1u ? 0.0f : 1.0f;
      });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit&, float v) { out[first + r] = v; });
  });
}

void FieldQuery::intersect(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->intersectBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, QueryHit{});
  }
}

void FieldQuery::occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->occludedBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, uint8_t(0));
  }
}

void FieldQuery::visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->visibilityBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, 1.0f);
  }
}

}  // namespace vff
