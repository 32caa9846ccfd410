// positions_reference.h - what the positional-sample tests (test_positions.cpp,
// test_position_lookup.cpp) check the library against: binary64 vector helpers, the exact nearest
// samples by an accelerated brute force, and the agreement of a lookup with them on random (the
// SplitMix64 sequence of tests/common/rng.h) and adversarial (near-tie) queries.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "common/rng.h"
#include "vff/vff.h"

namespace vff::test {

// Sanitizer and unoptimised builds run an eighth of the random queries.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSlowBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSlowBuild = true;
#else
inline constexpr bool kSlowBuild = false;
#endif
#elif !defined(NDEBUG)
inline constexpr bool kSlowBuild = true;
#else
inline constexpr bool kSlowBuild = false;
#endif
inline uint32_t scaled(uint32_t queries) {
  return kSlowBuild ? queries / 8 : queries;
}

// ---- Helpers -----------------------------------------------------------------------------------

inline D3 toD(Vec3 v) {
  return {v.x, v.y, v.z};
}
inline Vec3 toF(D3 v) {
  return {float(v.x), float(v.y), float(v.z)};
}
inline double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline D3 sub(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline D3 normalized(D3 a) {
  const double l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

// The exact nearest samples (largest dot product with the binary32 positions, ties to the smallest
// index): a uniform 3D grid over [-1, 1]^3, searched in growing shells of cells until no unsearched
// cell can hold a nearer point. Every unsearched point is at least r * cell away after shell r; a
// point that far has a dot product smaller than the current third best by more than 1e-6.
class ExactNearest {
 public:
  explicit ExactNearest(const PositionSet& set) : n_(set.count()) {
    pts_.resize(n_);
    for (uint32_t i = 0; i < n_; ++i) pts_[i] = toD(set.position(i));
    g_ = std::clamp(int(std::lround(2.0 / std::sqrt(38.0 / double(n_)))), 1, 64);
    cell_ = 2.0002 / g_;
    start_.assign(size_t(g_) * g_ * g_ + 1, 0);
    std::vector<uint32_t> cellOf(n_);
    for (uint32_t i = 0; i < n_; ++i) {
      cellOf[i] = cellIndex(coord(pts_[i].x), coord(pts_[i].y), coord(pts_[i].z));
      ++start_[cellOf[i] + 1];
    }
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    ids_.resize(n_);
    std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
    for (uint32_t i = 0; i < n_; ++i) ids_[fill[cellOf[i]]++] = i;
  }

  // The best three (index, dot), best first; fewer if the set is smaller.
  struct Hit {
    uint32_t index = 0;
    double dot = -2.0;
  };
  std::vector<Hit> best3(D3 q) const {
    Hit h[3];
    uint32_t found = 0;
    const int cx = coord(q.x), cy = coord(q.y), cz = coord(q.z);
    for (int r = 0; r <= g_; ++r) {
      for (int z = std::max(0, cz - r); z <= std::min(g_ - 1, cz + r); ++z)
        for (int y = std::max(0, cy - r); y <= std::min(g_ - 1, cy + r); ++y)
          for (int x = std::max(0, cx - r); x <= std::min(g_ - 1, cx + r); ++x) {
            if (std::max({std::abs(x - cx), std::abs(y - cy), std::abs(z - cz)}) != r) continue;
            const uint32_t c = cellIndex(x, y, z);
            for (uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
              const uint32_t i = ids_[k];
              Hit cand{i, dot(pts_[i], q)};
              ++found;
              for (Hit& slot : h)
                if (cand.dot > slot.dot || (cand.dot == slot.dot && cand.index < slot.index)) std::swap(cand, slot);
            }
          }
      if (found >= std::min<uint32_t>(3, n_)) {
        const uint32_t last = std::min<uint32_t>(3, n_) - 1;
        // chord^2 of the last kept point, with |p| = 1 +- 1e-7 absorbed by the 1e-5 slack.
        const double chord2 = 2.0 - 2.0 * h[last].dot;
        const double reach = r * cell_;
        if (reach * reach > chord2 + 1e-5) break;
      }
    }
    return std::vector<Hit>(h, h + std::min<uint32_t>(3, n_));
  }
  double dotWith(uint32_t i, D3 q) const { return dot(pts_[i], q); }
  D3 point(uint32_t i) const { return pts_[i]; }

 private:
  int coord(double v) const { return std::clamp(int((v + 1.0001) / cell_), 0, g_ - 1); }
  uint32_t cellIndex(int x, int y, int z) const { return uint32_t((z * g_ + y) * g_ + x); }

  uint32_t n_;
  int g_ = 1;
  double cell_ = 2.0;
  std::vector<D3> pts_;
  std::vector<uint32_t> start_, ids_;
};

// Agreement of a lookup with the exact nearest: "same" = the same index, "tie" = another index
// whose dot product is within 1e-6 of the best (counted as agreement), "fail" = worse than that;
// "nearTie" counts the failures within 1e-5 (for the binary32 port).
struct Agreement {
  uint64_t total = 0, same = 0, tie = 0, fail = 0, nearTie = 0;
  double worst = 0;
  double rate() const { return total ? double(same + tie) / double(total) : 1.0; }
  std::string summary() const {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "%llu queries, %.6f%% agree (%llu same, %llu ties), %llu fail (%llu within 1e-5), worst %.3g",
                  (unsigned long long)total, 100.0 * rate(), (unsigned long long)same, (unsigned long long)tie,
                  (unsigned long long)fail, (unsigned long long)nearTie, worst);
    return buf;
  }
};

template <class Lookup>
inline void check(const ExactNearest& ref, Lookup&& lookup, D3 q, Agreement* a) {
  const Vec3 qf = toF(q);  // the query as a caller passes it
  const D3 qd = toD(qf);
  const uint32_t got = lookup(qf);
  const auto best = ref.best3(qd);
  ++a->total;
  if (got == best[0].index) {
    ++a->same;
    return;
  }
  const double d = best[0].dot - ref.dotWith(got, qd);
  if (d <= 1e-6) {
    ++a->tie;
    return;
  }
  ++a->fail;
  if (d <= 1e-5) ++a->nearTie;
  a->worst = std::max(a->worst, d);
}

// Uniformly random directions; and for every sixteenth of them, adversarial queries near ties: on the
// bisector of the two nearest samples and at the circumcentre of the three nearest (a Voronoi
// vertex), exactly and nudged by 1e-7 and 1e-5 in random directions (6 queries).
struct Measured {
  Agreement random, adversarial;
};
template <class Lookup>
inline Measured measure(const ExactNearest& ref, Lookup&& lookup, uint32_t queries, uint64_t seed) {
  Measured m;
  SplitMix64 rng{seed};
  for (uint32_t k = 0; k < queries; ++k) {
    const D3 q = rng.direction();
    check(ref, lookup, q, &m.random);
    if (k % 16 != 0) continue;
    const auto b = ref.best3(q);
    if (b.size() < 3) continue;
    const D3 p0 = ref.point(b[0].index), p1 = ref.point(b[1].index), p2 = ref.point(b[2].index);
    std::vector<D3> seeds;
    const D3 e = sub(p0, p1);
    if (dot(e, e) > 1e-20) {
      const double t = dot(q, e) / dot(e, e);
      seeds.push_back(normalized({q.x - t * e.x, q.y - t * e.y, q.z - t * e.z}));
    }
    D3 c = cross(sub(p1, p0), sub(p2, p0));
    if (dot(c, c) > 1e-30) {
      c = normalized(c);
      if (dot(c, q) < 0) c = {-c.x, -c.y, -c.z};
      seeds.push_back(c);
    }
    for (const D3& sd : seeds)
      for (double eps : {0.0, 1e-7, 1e-5}) {
        const D3 r = rng.direction();
        check(ref, lookup, normalized({sd.x + eps * r.x, sd.y + eps * r.y, sd.z + eps * r.z}), &m.adversarial);
      }
  }
  return m;
}

inline PositionSet make(PositionScheme s, uint32_t n) {
  auto set = PositionSet::create(s, n);
  EXPECT_TRUE(set.ok()) << (set.ok() ? "" : set.error().toString());
  return set.ok() ? set.value() : PositionSet();
}

// Index of the canonical copy: octa-hemi2's lower equator vertices map to their upper copy.
inline uint32_t canonical(const PositionSet& set, uint32_t i) {
  if (set.scheme() != PositionScheme::kOctaHemi2) return i;
  const uint32_t n = set.param(), hemi = 2 * n * n + 2 * n + 1;
  if (i < hemi) return i;
  const Vec3 p = set.position(i);
  return p.z == 0.0f ? i - hemi : i;
}

}  // namespace vff::test
