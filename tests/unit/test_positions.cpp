// Positional-sample schemes (spec/positions.md): counts, order, positions, and the O(1) nearest
// lookup checked against an exact (accelerated) brute force, plus a binary32 port of the lookup as
// a shader would run it (the GLSL listing of the spec, line for line).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>

#include "vff/vff.h"

namespace vff {
namespace {

// Sanitizer and unoptimised builds run an eighth of the random queries.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSlowBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSlowBuild = true;
#else
constexpr bool kSlowBuild = false;
#endif
#elif !defined(NDEBUG)
constexpr bool kSlowBuild = true;
#else
constexpr bool kSlowBuild = false;
#endif
uint32_t scaled(uint32_t queries) {
  return kSlowBuild ? queries / 8 : queries;
}

// ---- Helpers -----------------------------------------------------------------------------------

struct D3 {
  double x = 0, y = 0, z = 0;
};
D3 toD(Vec3 v) {
  return {v.x, v.y, v.z};
}
Vec3 toF(D3 v) {
  return {float(v.x), float(v.y), float(v.z)};
}
double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
D3 sub(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
D3 normalized(D3 a) {
  const double l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

// SplitMix64: a fixed, portable random sequence.
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * 0x1p-53; }  // [0, 1)
  D3 direction() {                                             // uniform on the sphere
    const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
};

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
void check(const ExactNearest& ref, Lookup&& lookup, D3 q, Agreement* a) {
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
Measured measure(const ExactNearest& ref, Lookup&& lookup, uint32_t queries, uint64_t seed) {
  Measured m;
  Rng rng{seed};
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

PositionSet make(PositionScheme s, uint32_t n) {
  auto set = PositionSet::create(s, n);
  EXPECT_TRUE(set.ok()) << (set.ok() ? "" : set.error().toString());
  return set.ok() ? set.value() : PositionSet();
}

// Index of the canonical copy: octa-hemi2's lower equator vertices map to their upper copy.
uint32_t canonical(const PositionSet& set, uint32_t i) {
  if (set.scheme() != PositionScheme::kOctaHemi2) return i;
  const uint32_t n = set.param(), hemi = 2 * n * n + 2 * n + 1;
  if (i < hemi) return i;
  const Vec3 p = set.position(i);
  return p.z == 0.0f ? i - hemi : i;
}

// ---- binary32 port (the GLSL listing of spec/positions.md, in C++) -----------------------------

namespace f32 {

uint32_t umulHigh(uint32_t a, uint32_t b) {
  return uint32_t((uint64_t(a) * b) >> 32);
}
uint32_t fibTop32(uint32_t k) {
  return k * 0x9E3779B9u + umulHigh(k, 0x7F4A7C15u);
}
constexpr float kTwoPiOver2p32 = 6.28318531f / 4294967296.0f;
constexpr uint32_t kFib[22] = {0,  1,   1,   2,   3,   5,   8,    13,   21,   34,   55,
                               89, 144, 233, 377, 610, 987, 1597, 2584, 4181, 6765, 10946};

struct Best {
  float dot = -2.0f;
  int k = 0;
  void offer(float d, int i) {
    if (d > dot || (d == dot && i < k)) {
      dot = d;
      k = i;
    }
  }
};
float dotf(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 normalize(Vec3 v) {
  const float l = std::sqrt(dotf(v, v));
  return {v.x / l, v.y / l, v.z / l};
}

int octaIndex(int n, int h, int p, int q) {
  const int t = n + q;
  const int start = q <= 0 ? t * t : t * t - 2 * q * (q - 1);
  return h * (2 * n * n + 2 * n + 1) + start + p + n - std::abs(q);
}

int nearestOctaHemi2(Vec3 d, int n) {
  const int h = d.z >= 0.0f ? 0 : 1;
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  const float s = float(n) / (ax + ay + az);
  const int a0 = std::min(int(ax * s), n - 1), b0 = std::min(int(ay * s), n - 1);
  const int sx = d.x < 0.0f ? -1 : 1, sy = d.y < 0.0f ? -1 : 1;
  static constexpr int kOffs[8][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {-1, 1}, {1, -1}, {2, 0}, {0, 2}};
  Best best;
  for (const auto& o : kOffs) {
    const int a = a0 + o[0], b = b0 + o[1];
    const int l1 = std::abs(a) + std::abs(b);
    if (l1 > n) continue;
    const int p = sx * a, q = sy * b, m = n - l1;
    const Vec3 u = normalize({float(p), float(q), float(h == 0 ? m : -m)});
    best.offer(dotf(u, d), octaIndex(n, l1 == n ? 0 : h, p, q));
  }
  return best.k;
}

Vec3 eaPosition(int n, int i, int j) {
  const int P = 2 * i + 1 - n, Q = 2 * j + 1 - n;
  const int ax = std::abs(P), ay = std::abs(Q);
  const bool upper = ax + ay <= n;
  const int a = upper ? ax : n - ay, b = upper ? ay : n - ax;
  const int r = a + b;
  const float s = upper ? 1.0f : -1.0f;
  if (r == 0) return {0.0f, 0.0f, s};
  const float nn = float(n * n);
  const float rho = float(r) * std::sqrt(float(2 * n * n - r * r)) / nn;
  const float x = rho * std::sin(float(a) / float(r) * 1.57079633f);
  const float y = rho * std::sin(float(b) / float(r) * 1.57079633f);
  return {P < 0 ? -x : x, Q < 0 ? -y : y, s * float(n * n - r * r) / nn};
}

int nearestEaOctaGrid(Vec3 d, int n) {
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  const float r = std::sqrt((ax * ax + ay * ay) / (1.0f + az));
  const float b = ax + ay > 0.0f ? r * (std::atan2(ay, ax) * 0.636619772f) : 0.0f;
  float u = r - b, v = b;
  if (d.z < 0.0f) {
    const float t = u;
    u = 1.0f - v;
    v = 1.0f - t;
  }
  if (d.x < 0.0f) u = -u;
  if (d.y < 0.0f) v = -v;
  const int i0 = std::clamp(int(std::floor((u + 1.0f) * (0.5f * float(n)))), 0, n - 1);
  const int j0 = std::clamp(int(std::floor((v + 1.0f) * (0.5f * float(n)))), 0, n - 1);
  Best best;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      int i = i0 + di, j = j0 + dj;
      if (i < 0 || i >= n) {
        i = i < 0 ? 0 : n - 1;
        j = n - 1 - j;
      }
      if (j < 0 || j >= n) {
        j = j < 0 ? 0 : n - 1;
        i = n - 1 - i;
      }
      best.offer(dotf(eaPosition(n, i, j), d), j * n + i);
    }
  return best.k;
}

Vec3 fibPosition(int n, int k) {
  const float phi = float(fibTop32(uint32_t(k))) * kTwoPiOver2p32;
  const float z = float(n - 2 * k - 1) / float(n);
  const float rho = std::sqrt(float(2 * k + 1) * float(2 * n - 2 * k - 1)) / float(n);
  return {rho * std::cos(phi), rho * std::sin(phi), z};
}

int nearestFibonacci(Vec3 d, int n) {
  const float rho2 = d.x * d.x + d.y * d.y;
  const float v = float(n) * 7.02481473f * rho2;
  const int k = v > 1.0f ? std::clamp(int(std::floor(std::log(v) * 1.03904346f)), 2, 20) : 2;
  const uint32_t f0 = kFib[k], f1 = kFib[k + 1];
  const float p0 = float(int32_t(fibTop32(f0))) * kTwoPiOver2p32;
  const float p1 = float(int32_t(fibTop32(f1))) * kTwoPiOver2p32;
  const float z0 = -2.0f * float(f0) / float(n), z1 = -2.0f * float(f1) / float(n);
  const float phi = rho2 > 0.0f ? std::atan2(d.y, d.x) : 0.0f;
  const float dz = d.z - (1.0f - 1.0f / float(n));
  const float det = p0 * z1 - p1 * z0;
  const int c0 = int(std::floor((phi * z1 - p1 * dz) / det));
  const int c1 = int(std::floor((p0 * dz - z0 * phi) / det));
  Best best;
  for (int s = 0; s < 4; ++s) {
    const int i = (c0 + (s & 1)) * int(f0) + (c1 + (s >> 1)) * int(f1);
    if (i < 0 || i >= n) continue;
    best.offer(dotf(fibPosition(n, i), d), i);
  }
  return best.k;
}

int nearest(const PositionSet& set, Vec3 d) {
  const int n = int(set.param());
  switch (set.scheme()) {
    case PositionScheme::kOctaHemi2:
      return nearestOctaHemi2(d, n);
    case PositionScheme::kEqualAreaOctaGrid:
      return nearestEaOctaGrid(d, n);
    case PositionScheme::kSphericalFibonacci:
      return nearestFibonacci(d, n);
    case PositionScheme::kInvalid:
      break;
  }
  return 0;
}

Vec3 position(const PositionSet& set, uint32_t k) {
  const int n = int(set.param());
  switch (set.scheme()) {
    case PositionScheme::kOctaHemi2: {
      const int hemi = 2 * n * n + 2 * n + 1, h = int(k) / hemi;
      // Invert by search: the binary32 port only needs the forward index formula.
      for (int q = -n; q <= n; ++q) {
        const int w = n - std::abs(q);
        const int p = int(k) - octaIndex(n, h, -w, q) - w;
        if (p >= -w && p <= w) {
          const int m = n - std::abs(p) - std::abs(q);
          return normalize({float(p), float(q), float(h == 0 ? m : -m)});
        }
      }
      return {};
    }
    case PositionScheme::kEqualAreaOctaGrid:
      return eaPosition(n, int(k) % n, int(k) / n);
    case PositionScheme::kSphericalFibonacci:
      return fibPosition(n, int(k));
    case PositionScheme::kInvalid:
      break;
  }
  return {};
}

}  // namespace f32

// ---- Construction ------------------------------------------------------------------------------

TEST(PositionSet, CreateChecksSchemeAndParam) {
  struct Bad {
    PositionScheme s;
    uint32_t n;
  };
  for (Bad b : {Bad{PositionScheme::kInvalid, 1}, Bad{PositionScheme(4), 1}, Bad{PositionScheme::kOctaHemi2, 0},
                Bad{PositionScheme::kOctaHemi2, 1025}, Bad{PositionScheme::kEqualAreaOctaGrid, 0},
                Bad{PositionScheme::kEqualAreaOctaGrid, 2049}, Bad{PositionScheme::kSphericalFibonacci, 0},
                Bad{PositionScheme::kSphericalFibonacci, (1u << 24) + 1}}) {
    auto r = PositionSet::create(b.s, b.n);
    ASSERT_FALSE(r.ok()) << uint32_t(b.s) << " " << b.n;
    EXPECT_EQ(r.error().code, Code::kPositionScheme);
  }
  EXPECT_TRUE(PositionSet::create(PositionScheme::kOctaHemi2, 1024).ok());
  EXPECT_TRUE(PositionSet::create(PositionScheme::kEqualAreaOctaGrid, 2048).ok());
  EXPECT_TRUE(PositionSet::create(PositionScheme::kSphericalFibonacci, 1u << 24).ok());
}

TEST(PositionSet, CountsMatchTheFormat) {
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 32).count(), 4226u);
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 64).count(), 16642u);
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 1).count(), 10u);
  EXPECT_EQ(make(PositionScheme::kEqualAreaOctaGrid, 65).count(), 4225u);
  EXPECT_EQ(make(PositionScheme::kEqualAreaOctaGrid, 129).count(), 16641u);
  EXPECT_EQ(make(PositionScheme::kSphericalFibonacci, 4226).count(), 4226u);
  const PositionSet s = make(PositionScheme::kSphericalFibonacci, 16642);
  EXPECT_EQ(s.scheme(), PositionScheme::kSphericalFibonacci);
  EXPECT_EQ(s.param(), 16642u);
  EXPECT_EQ(s.count(), 16642u);
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci})
    for (uint32_t n : {1u, 2u, 7u, 64u}) EXPECT_EQ(make(sc, n).count(), positionCount(sc, n).value());
}

TEST(PositionSet, FromFieldChecksMapCount) {
  FieldDesc f;
  f.positionScheme = PositionScheme::kOctaHemi2;
  f.positionParam = 32;
  f.mapCount = 4226;
  auto ok = PositionSet::fromField(f);
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(ok->count(), 4226u);
  f.mapCount = 4225;
  auto bad = PositionSet::fromField(f);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kMapCount);
  f.positionParam = 0;
  auto badParam = PositionSet::fromField(f);
  ASSERT_FALSE(badParam.ok());
  EXPECT_EQ(badParam.error().code, Code::kPositionScheme);
}

TEST(PositionSet, CandidatesHoldTheNearestSample) {
  // candidates() is what a table-driven lookup (the CPU query, a GPU port) chooses from.
  for (auto [sc, n] : {std::pair{PositionScheme::kOctaHemi2, 32u}, std::pair{PositionScheme::kEqualAreaOctaGrid, 65u},
                       std::pair{PositionScheme::kSphericalFibonacci, 4226u}}) {
    const PositionSet s = make(sc, n);
    Rng rng{42};
    for (int k = 0; k < 20000; ++k) {
      const Vec3 d = toF(rng.direction());
      uint32_t c[PositionSet::kMaxCandidates];
      const uint32_t count = s.candidates(d, c);
      ASSERT_GE(count, 1u);
      ASSERT_LE(count, PositionSet::kMaxCandidates);
      const uint32_t want = s.nearest(d);
      bool found = false;
      for (uint32_t i = 0; i < count; ++i) {
        ASSERT_LT(c[i], s.count());
        found = found || c[i] == want;
      }
      ASSERT_TRUE(found) << positionSchemeName(sc) << " query " << k;
    }
    uint32_t c[PositionSet::kMaxCandidates];
    EXPECT_EQ(s.candidates({0, 0, 0}, c), 1u);
    EXPECT_EQ(c[0], 0u);
  }
  uint32_t c[PositionSet::kMaxCandidates];
  EXPECT_EQ(PositionSet{}.candidates({1, 0, 0}, c), 0u);
}

TEST(PositionSet, EmptyAndInvalidInputsAreSafe) {
  static_assert(std::is_trivially_copyable_v<PositionSet>);
  const PositionSet empty;
  EXPECT_EQ(empty.count(), 0u);
  EXPECT_EQ(empty.nearest({0, 0, 1}), 0u);
  const Vec3 zero = empty.position(0);
  EXPECT_EQ(zero.x, 0.0f);
  const float nan = std::nanf(""), inf = INFINITY;
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci}) {
    const PositionSet s = make(sc, 5);
    EXPECT_EQ(s.nearest({0, 0, 0}), 0u);
    EXPECT_EQ(s.nearest({nan, 0, 1}), 0u);
    EXPECT_EQ(s.nearest({inf, 0, 0}), 0u);
    const Vec3 out = s.position(s.count());
    EXPECT_EQ(out.x + out.y + out.z, 0.0f);
    // Not normalised, tiny or huge: still a valid index, the same as for the unit vector.
    EXPECT_EQ(s.nearest({3e-30f, 1e-30f, -2e-30f}), s.nearest({3, 1, -2}));
    EXPECT_EQ(s.nearest({3e30f, 1e30f, -2e30f}), s.nearest({3, 1, -2}));
    EXPECT_LT(s.nearest({0, 0, -1}), s.count());
    // The map frame looks inward.
    const Frame fr = s.frame(3);
    const Vec3 p = s.position(3);
    EXPECT_NEAR(fr.n.x * p.x + fr.n.y * p.y + fr.n.z * p.z, -1.0f, 1e-6f);
  }
}

// ---- Positions and order -----------------------------------------------------------------------

struct Param {
  PositionScheme scheme;
  uint32_t n;
};
const Param kSmallAndPaper[] = {
    {PositionScheme::kOctaHemi2, 1},
    {PositionScheme::kOctaHemi2, 2},
    {PositionScheme::kOctaHemi2, 3},
    {PositionScheme::kOctaHemi2, 32},
    {PositionScheme::kOctaHemi2, 64},
    {PositionScheme::kEqualAreaOctaGrid, 1},
    {PositionScheme::kEqualAreaOctaGrid, 2},
    {PositionScheme::kEqualAreaOctaGrid, 3},
    {PositionScheme::kEqualAreaOctaGrid, 64},
    {PositionScheme::kEqualAreaOctaGrid, 65},
    {PositionScheme::kEqualAreaOctaGrid, 129},
    {PositionScheme::kSphericalFibonacci, 1},
    {PositionScheme::kSphericalFibonacci, 2},
    {PositionScheme::kSphericalFibonacci, 3},
    {PositionScheme::kSphericalFibonacci, 4226},
    {PositionScheme::kSphericalFibonacci, 16642},
};

TEST(PositionSet, AllPositionsAreUnitVectors) {
  for (const Param& pr : kSmallAndPaper) {
    const PositionSet s = make(pr.scheme, pr.n);
    for (uint32_t i = 0; i < s.count(); ++i) {
      const D3 p = toD(s.position(i));
      ASSERT_NEAR(dot(p, p), 1.0, 4e-7) << positionSchemeName(pr.scheme) << " n=" << pr.n << " i=" << i;
    }
  }
}

TEST(PositionOctaHemi2, OrderMatchesSpec) {
  // n = 1: the octahedron's vertices, row by row.
  const PositionSet one = make(PositionScheme::kOctaHemi2, 1);
  const float expected[10][3] = {{0, -1, 0}, {-1, 0, 0}, {0, 0, 1},  {1, 0, 0}, {0, 1, 0},
                                 {0, -1, 0}, {-1, 0, 0}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}};
  for (uint32_t k = 0; k < 10; ++k) {
    const Vec3 p = one.position(k);
    EXPECT_EQ(p.x, expected[k][0]) << k;
    EXPECT_EQ(p.y, expected[k][1]) << k;
    EXPECT_EQ(p.z, expected[k][2]) << k;
  }
  // Any n: an independent enumeration (h, then q = -n..n, then p) gives the same bits.
  for (uint32_t un : {2u, 3u, 32u, 64u}) {
    const int64_t n = un;
    const PositionSet s = make(PositionScheme::kOctaHemi2, un);
    uint32_t k = 0;
    for (int64_t h = 0; h < 2; ++h)
      for (int64_t q = -n; q <= n; ++q)
        for (int64_t p = -(n - std::abs(q)); p <= n - std::abs(q); ++p, ++k) {
          const int64_t m = (h == 0 ? 1 : -1) * (n - std::abs(p) - std::abs(q));
          const double len = std::sqrt(double(p * p + q * q + m * m));
          const Vec3 got = s.position(k);
          ASSERT_EQ(got.x, float(double(p) / len)) << "n=" << n << " k=" << k;
          ASSERT_EQ(got.y, float(double(q) / len)) << "n=" << n << " k=" << k;
          ASSERT_EQ(got.z, float(double(m) / len)) << "n=" << n << " k=" << k;
        }
    EXPECT_EQ(k, s.count());
  }
}

TEST(PositionOctaHemi2, EquatorDuplicatesAreEqualAndResolveToTheUpperCopy) {
  for (uint32_t n : {1u, 2u, 5u, 32u, 64u}) {
    const PositionSet s = make(PositionScheme::kOctaHemi2, n);
    const uint32_t hemi = s.count() / 2;
    uint32_t equator = 0;
    for (uint32_t i = 0; i < hemi; ++i) {
      const Vec3 a = s.position(i), b = s.position(i + hemi);
      if (a.z == 0.0f) {
        ++equator;
        // Bit-identical copies (z is +0 in both), so their maps are identical too.
        EXPECT_EQ(std::bit_cast<uint32_t>(a.x), std::bit_cast<uint32_t>(b.x));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.y), std::bit_cast<uint32_t>(b.y));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.z), std::bit_cast<uint32_t>(b.z));
        EXPECT_EQ(s.nearest(b), i);
        // Just below the equator, the nearest is still this vertex, and still the upper copy.
        EXPECT_EQ(s.nearest({b.x, b.y, -1e-6f}), i);
      } else {
        EXPECT_EQ(a.z, -b.z);
        EXPECT_GT(a.z, 0.0f);
      }
    }
    EXPECT_EQ(equator, 4 * n);
  }
}

TEST(PositionEaOctaGrid, MatchesClarbergPbrtMap) {
  // pbrt-v4's EqualAreaSquareToSphere, transcribed in binary64 on p in [0,1]^2.
  auto pbrt = [](double px, double py) {
    const double u = 2 * px - 1, v = 2 * py - 1, up = std::fabs(u), vp = std::fabs(v);
    const double sd = 1 - (up + vp), d = std::fabs(sd), r = 1 - d;
    const double phi = (r == 0 ? 1 : (vp - up) / r + 1) * 3.141592653589793 / 4;
    const double z = std::copysign(1 - r * r, sd);
    const double cosPhi = std::copysign(std::cos(phi), u), sinPhi = std::copysign(std::sin(phi), v);
    const double s = r * std::sqrt(std::max(0.0, 2 - r * r));
    return D3{cosPhi * s, sinPhi * s, z};
  };
  for (uint32_t n : {1u, 2u, 3u, 64u, 65u}) {
    const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, n);
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        const D3 want = pbrt((i + 0.5) / n, (j + 0.5) / n);
        const D3 got = toD(s.position(j * n + i));
        ASSERT_NEAR(got.x, want.x, 2e-7) << n << " " << i << " " << j;
        ASSERT_NEAR(got.y, want.y, 2e-7) << n << " " << i << " " << j;
        ASSERT_NEAR(got.z, want.z, 2e-7) << n << " " << i << " " << j;
      }
  }
  // The examples of the spec: centre = north pole, corner cell in the lower hemisphere.
  const PositionSet s3 = make(PositionScheme::kEqualAreaOctaGrid, 3);
  EXPECT_EQ(s3.position(4).z, 1.0f);
  EXPECT_EQ(s3.position(5).x, 0x1.a9b7acp-1f);
  EXPECT_EQ(s3.position(5).y, 0.0f);
  EXPECT_EQ(s3.position(5).z, 0x1.1c71c8p-1f);
  EXPECT_EQ(s3.position(0).x, -0x1.2d0718p-1f);
  EXPECT_EQ(s3.position(0).z, -0x1.1c71c8p-1f);
}

TEST(PositionEaOctaGrid, NearestRegionsHaveNearlyEqualArea) {
  // The cells are equal-area, so the regions that look up each sample (their Voronoi cells) have
  // nearly equal solid angles: with 256 uniform directions per sample, every count is within 2x.
  const uint32_t n = 16;
  const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, n);
  std::vector<uint32_t> hits(s.count(), 0);
  Rng rng{42};
  const uint32_t q = 256 * s.count();
  for (uint32_t k = 0; k < q; ++k) ++hits[s.nearest(toF(rng.direction()))];
  const auto [lo, hi] = std::minmax_element(hits.begin(), hits.end());
  EXPECT_GT(*lo, 256u / 2);
  EXPECT_LT(*hi, 256u * 2);
}

TEST(PositionFibonacci, MatchesKeinertDefinition) {
  // z_i = 1 - (2i+1)/N and phi_i = 2 pi frac(i (Phi - 1)), in long double with the irrational Phi.
  for (uint32_t n : {1u, 2u, 3u, 4226u, 16642u}) {
    const PositionSet s = make(PositionScheme::kSphericalFibonacci, n);
    const long double phiM1 = (std::sqrt(5.0L) - 1.0L) / 2.0L;
    for (uint32_t i = 0; i < n; ++i) {
      const long double z = 1.0L - (2.0L * i + 1.0L) / n;
      const long double t = i * phiM1, ph = 2.0L * 3.14159265358979323846264338327950288L * (t - std::floor(t));
      const long double r = std::sqrt(1.0L - z * z);
      const Vec3 got = s.position(i);
      ASSERT_NEAR(got.x, double(r * std::cos(ph)), 2e-7) << n << " " << i;
      ASSERT_NEAR(got.y, double(r * std::sin(ph)), 2e-7) << n << " " << i;
      ASSERT_EQ(got.z, float(double(n - 2 * int64_t(i) - 1) / double(n))) << n << " " << i;
    }
  }
}

// ---- The binary64 evaluation is the correctly rounded binary32 value ----------------------------

TEST(PositionSet, PositionsAreCorrectlyRounded) {
  // Evaluate every formula again in long double and round to binary32: position() must give the
  // same bits (that is what makes the positions reproducible byte for byte).
  using L = long double;
  const L pi = 3.14159265358979323846264338327950288L;
  uint64_t total = 0, differ = 0;
  auto same = [&](Vec3 got, L x, L y, L z) {
    ++total;
    if (got.x != float(x) || got.y != float(y) || got.z != float(z)) ++differ;
  };
  for (uint32_t un : {32u, 64u}) {
    const PositionSet s = make(PositionScheme::kOctaHemi2, un);
    const int64_t n = un, hemi = s.count() / 2;
    for (int64_t k = 0; k < int64_t(s.count()); ++k) {
      const Vec3 p = s.position(uint32_t(k));
      // Recover (p, q, m) from the float (exact for these sizes), then normalise in long double.
      const int64_t h = k / hemi;
      const L l1 = L(std::fabs(p.x)) + std::fabs(p.y) + std::fabs(p.z);
      const int64_t a = std::llround(L(p.x) / l1 * n), b = std::llround(L(p.y) / l1 * n);
      const int64_t m = (h == 0 ? 1 : -1) * (n - std::abs(a) - std::abs(b));
      const L len = std::sqrt(L(a * a + b * b + m * m));
      same(p, a / len, b / len, m / len);
    }
  }
  for (uint32_t un : {65u, 129u}) {
    const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, un);
    const int64_t n = un;
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const int64_t P = 2 * i + 1 - n, Q = 2 * j + 1 - n, ax = std::abs(P), ay = std::abs(Q);
        const bool upper = ax + ay <= n;
        const int64_t a = upper ? ax : n - ay, b = upper ? ay : n - ax, r = a + b;
        const L sg = upper ? 1 : -1;
        if (r == 0) {
          same(s.position(uint32_t(j * n + i)), 0, 0, sg);
          continue;
        }
        const L rho = L(r) * std::sqrt(L(2 * n * n - r * r)) / L(n * n);
        const L x = rho * std::sin(pi / 2 * a / r), y = rho * std::sin(pi / 2 * b / r);
        same(s.position(uint32_t(j * n + i)), P < 0 ? -x : x, Q < 0 ? -y : y, sg * L(n * n - r * r) / L(n * n));
      }
  }
  for (uint32_t un : {4226u, 16642u}) {
    const PositionSet s = make(PositionScheme::kSphericalFibonacci, un);
    const int64_t n = un;
    for (int64_t i = 0; i < n; ++i) {
      const uint64_t f = uint64_t(i) * 0x9E3779B97F4A7C15ull;
      const L ph = 2 * pi * (L(f) / 18446744073709551616.0L);
      const L rho = std::sqrt(L((2 * i + 1) * (2 * n - 2 * i - 1))) / n;
      same(s.position(uint32_t(i)), rho * std::cos(ph), rho * std::sin(ph), L(n - 2 * i - 1) / n);
    }
  }
  std::printf("[ positions ] %llu of %llu positions differ from the long-double evaluation\n",
              (unsigned long long)differ, (unsigned long long)total);
  RecordProperty("differ", std::to_string(differ));
  // long double is wider than binary64 on x86; elsewhere it may be binary64 and this is trivial.
  EXPECT_LE(differ, total / 100000);
}

// ---- The nearest lookup ------------------------------------------------------------------------

struct Case {
  const char* name;
  PositionScheme scheme;
  uint32_t n;
  uint32_t queries;
};

class PositionLookup : public ::testing::TestWithParam<Case> {};

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
  return info.param.name;
}

TEST_P(PositionLookup, RoundTripsEverySample) {
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  Rng rng{7};
  const double spacing = std::sqrt(4.0 * 3.141592653589793 / s.count());
  for (uint32_t i = 0; i < s.count(); ++i) {
    const Vec3 p = s.position(i);
    ASSERT_EQ(s.nearest(p), canonical(s, i)) << "i=" << i;
    // Nudged by a hundredth of the spacing: still the same sample.
    const D3 r = rng.direction(), pd = toD(p);
    const double e = 0.01 * spacing;
    ASSERT_EQ(s.nearest(toF({pd.x + e * r.x, pd.y + e * r.y, pd.z + e * r.z})), canonical(s, i)) << "i=" << i;
  }
}

TEST_P(PositionLookup, AgreesWithBruteForce) {
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  const ExactNearest ref(s);
  const auto t0 = std::chrono::steady_clock::now();
  const Measured m = measure(
      ref, [&](Vec3 d) { return s.nearest(d); }, scaled(c.queries), 1000 + c.n);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ positions ] %s n=%u (%u samples), random: %s\n", positionSchemeName(c.scheme), c.n, s.count(),
              m.random.summary().c_str());
  std::printf("[ positions ] %s n=%u (%u samples), near ties: %s (%.2f s)\n", positionSchemeName(c.scheme), c.n,
              s.count(), m.adversarial.summary().c_str(), secs);
  RecordProperty("agreement", std::to_string(m.random.rate()));
  RecordProperty("queries", std::to_string(m.random.total));
  RecordProperty("agreement_near_ties", std::to_string(m.adversarial.rate()));
  // The lookup is exact for every scheme (spec/positions.md): no query may fail.
  ASSERT_EQ(m.random.fail, 0u) << m.random.summary();
  ASSERT_EQ(m.adversarial.fail, 0u) << m.adversarial.summary();
}

TEST_P(PositionLookup, Binary32PortAgrees) {
  // The GLSL listing of the spec, run in binary32: positions within a few ulp, and the same nearest
  // sample except within binary32 rounding of a tie (1e-5 in dot is allowed here; reported).
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  double worst = 0;
  for (uint32_t i = 0; i < s.count(); ++i) {
    const D3 d = sub(toD(s.position(i)), toD(f32::position(s, i)));
    worst = std::max(worst, std::sqrt(dot(d, d)));
  }
  EXPECT_LT(worst, 2e-6);
  const ExactNearest ref(s);
  const Measured m = measure(
      ref, [&](Vec3 d) { return uint32_t(f32::nearest(s, d)); }, scaled(100000), 77 + c.n);
  std::printf("[ positions ] binary32 port %s n=%u: max position error %.2g; random: %s; near ties: %s\n",
              positionSchemeName(c.scheme), c.n, worst, m.random.summary().c_str(), m.adversarial.summary().c_str());
  RecordProperty("binary32_agreement", std::to_string(m.random.rate()));
  EXPECT_EQ(m.random.fail - m.random.nearTie, 0u) << m.random.summary();
  EXPECT_EQ(m.adversarial.fail - m.adversarial.nearTie, 0u) << m.adversarial.summary();
}

INSTANTIATE_TEST_SUITE_P(Positions, PositionLookup,
                         // 10^6 random directions for the ~4k-sample sets and 2 * 10^5 for the ~16k-sample sets.
                         ::testing::Values(Case{"OctaHemi2_n32", PositionScheme::kOctaHemi2, 32, 1000000},
                                           Case{"OctaHemi2_n64", PositionScheme::kOctaHemi2, 64, 200000},
                                           Case{"EaOctaGrid_n65", PositionScheme::kEqualAreaOctaGrid, 65, 1000000},
                                           Case{"EaOctaGrid_n129", PositionScheme::kEqualAreaOctaGrid, 129, 200000},
                                           Case{"Fibonacci_n4226", PositionScheme::kSphericalFibonacci, 4226, 1000000},
                                           Case{"Fibonacci_n16642", PositionScheme::kSphericalFibonacci, 16642,
                                                200000}),
                         caseName);

TEST(PositionLookupSmall, AgreesWithBruteForceForSmallParams) {
  // Small parameters, where the sphere's curvature is largest relative to the sample spacing.
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci}) {
    const uint32_t last = sc == PositionScheme::kSphericalFibonacci ? 64 : 16;
    for (uint32_t n = 1; n <= last; ++n) {
      const PositionSet s = make(sc, n);
      const ExactNearest ref(s);
      const Measured m = measure(
          ref, [&](Vec3 d) { return s.nearest(d); }, scaled(4000), n);
      ASSERT_EQ(m.random.fail, 0u) << positionSchemeName(sc) << " n=" << n << ": " << m.random.summary();
      ASSERT_EQ(m.adversarial.fail, 0u) << positionSchemeName(sc) << " n=" << n << ": " << m.adversarial.summary();
      for (uint32_t i = 0; i < s.count(); ++i) ASSERT_EQ(s.nearest(s.position(i)), canonical(s, i));
    }
  }
}

TEST(PositionLookupLarge, FibonacciLargestNSpotCheck) {
  // n = 2^24: binary32 positions are too coarse to rank neighbours (spacing 8.6e-4 rad), so the
  // reference evaluates the definition in long double. Exact reference: the samples are sorted by
  // z, and every sample nearer than the answer lies in the band |z_i - z_q| < chord(answer).
  using L = long double;
  const uint32_t un = 1u << 24;
  const int64_t n = un;
  const PositionSet fib = make(PositionScheme::kSphericalFibonacci, un);
  auto exact = [&](int64_t i) {
    const uint64_t f = uint64_t(i) * 0x9E3779B97F4A7C15ull;
    const L ph = 2 * 3.14159265358979323846264338327950288L * (L(f) / 18446744073709551616.0L);
    const L rho = std::sqrt(L((2 * i + 1) * (2 * n - 2 * i - 1))) / n;
    return std::array<L, 3>{rho * std::cos(ph), rho * std::sin(ph), L(n - 2 * i - 1) / n};
  };
  Rng rng{3};
  for (int k = 0; k < int(scaled(200)); ++k) {
    const Vec3 q = toF(rng.direction());
    const uint32_t got = fib.nearest(q);
    const auto g = exact(got);
    const L gd = g[0] * q.x + g[1] * q.y + g[2] * q.z;
    // q is a unit vector only to binary32 precision: the band is computed from the normalised query.
    const L len = std::sqrt(L(q.x) * q.x + L(q.y) * q.y + L(q.z) * q.z);
    const double qz = double(q.z / len);
    const double chord = std::sqrt(std::max(0.0, double(2 - 2 * (gd / len)))) + 1e-9;
    const int64_t lo = std::max<int64_t>(0, int64_t(std::floor((n * (1 - qz - chord) - 1) / 2)) - 1);
    const int64_t hi = std::min<int64_t>(n - 1, int64_t(std::ceil((n * (1 - qz + chord) - 1) / 2)) + 1);
    ASSERT_LE(lo, hi) << "query " << k;
    for (int64_t i = lo; i <= hi; ++i) {
      const auto p = exact(i);
      ASSERT_LE(double(p[0] * q.x + p[1] * q.y + p[2] * q.z - gd), 1e-12) << "query " << k << " i=" << i;
    }
  }
}

}  // namespace
}  // namespace vff
