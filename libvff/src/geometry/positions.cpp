// Positional-sample schemes (spec/positions.md). Every formula below is the spec's, evaluated in
// IEEE-754 binary64 in the order written there; position() rounds the result to float32 once.
#include "vff/positions.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace vff {
namespace {

constexpr double kHalfPi = 1.5707963267948966;      // binary64 nearest pi/2
constexpr double kTwoPi = 6.283185307179586;        // binary64 nearest 2 pi
constexpr double kPiSqrt5 = 7.024814731040727;      // binary64 nearest pi sqrt(5)
constexpr double kInvLogPhi2 = 1.0390434606175138;  // binary64 nearest 1 / log(Phi^2)

struct D3 {
  double x = 0, y = 0, z = 0;
};

double dot(const D3& a, const D3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

Vec3 toFloat(const D3& p) {
  return {float(p.x), float(p.y), float(p.z)};
}

// Keeps the best candidate: the largest dot product, ties to the smallest index.
struct Best {
  double dot = -HUGE_VAL;
  uint32_t index = 0;
  void offer(double d, uint32_t i) {
    if (d > dot || (d == dot && i < index)) {
      dot = d;
      index = i;
    }
  }
};

// ---- octa-hemi2 -------------------------------------------------------------------------------
// Grid point (i, j) of hemisphere h, |i| + |j| <= n: the integer vector (i, j, s (n - |i| - |j|)),
// s = +1 for h = 0 and -1 for h = 1, normalised.

uint32_t octaHemiCount(uint32_t n) {
  return 2 * n * n + 2 * n + 1;
}

// Index of the first point of row j within a hemisphere: rows -n .. j-1 hold
// (n + j)^2 points for j <= 0 and (n + j)^2 - 2 j (j - 1) for j >= 0.
int64_t octaRowStart(int64_t n, int64_t j) {
  const int64_t t = n + j;
  return j <= 0 ? t * t : t * t - 2 * j * (j - 1);
}

uint32_t octaIndex(int64_t n, int64_t h, int64_t i, int64_t j) {
  const int64_t w = n - (j < 0 ? -j : j);  // row j spans i = -w .. w
  return uint32_t(h * int64_t(octaHemiCount(uint32_t(n))) + octaRowStart(n, j) + i + w);
}

uint64_t isqrt(uint64_t v) {
  uint64_t r = uint64_t(std::sqrt(double(v)));
  while (r * r > v) --r;
  while ((r + 1) * (r + 1) <= v) ++r;
  return r;
}

// Local index k (within a hemisphere) -> (i, j). Rows j < 0 hold local indices [0, n^2), row 0
// holds [n^2, n^2 + 2n + 1); the order is symmetric under k -> H-1-k, (i, j) -> (-i, -j).
void octaDecode(int64_t n, int64_t k, int64_t* i, int64_t* j) {
  const int64_t hemi = int64_t(octaHemiCount(uint32_t(n)));
  const bool mirrored = k >= n * n + 2 * n + 1;
  if (mirrored) k = hemi - 1 - k;
  int64_t ii, jj;
  if (k < n * n) {
    jj = int64_t(isqrt(uint64_t(k))) - n;  // (n + j)^2 <= k < (n + j + 1)^2
    ii = k - octaRowStart(n, jj) - (n + jj);
  } else {
    jj = 0;
    ii = k - n * n - n;
  }
  *i = mirrored ? -ii : ii;
  *j = mirrored ? -jj : jj;
}

D3 octaPoint(int64_t n, int64_t s, int64_t i, int64_t j) {
  const int64_t ai = i < 0 ? -i : i, aj = j < 0 ? -j : j;
  const int64_t k = s * (n - ai - aj);
  const double len = std::sqrt(double(i * i + j * j + k * k));
  return {double(i) / len, double(j) / len, double(k) / len};
}

D3 octaPosition(uint32_t n, uint32_t index) {
  const uint32_t hemi = octaHemiCount(n);
  const int64_t h = index < hemi ? 0 : 1;
  int64_t i, j;
  octaDecode(n, int64_t(index) - h * hemi, &i, &j);
  return octaPoint(n, h == 0 ? 1 : -1, i, j);
}

// Offers every candidate of the O(1) lookup: offer(index, position) where position() computes the
// binary64 position on demand (callers with a table of positions need not call it).
template <class Offer>
void octaCandidates(uint32_t un, const D3& q, Offer&& offer) {
  const int64_t n = un;
  // Restricting to the query's hemisphere is exact: the other hemisphere is its mirror image.
  const int64_t h = q.z >= 0 ? 0 : 1;
  const int64_t s = h == 0 ? 1 : -1;
  // Quadrant frame (a, b) = (|i|, |j|); the query's projection onto the octahedron, scaled by n.
  const double l1 = std::fabs(q.x) + std::fabs(q.y) + std::fabs(q.z);
  const double pa = std::fabs(q.x) / l1 * double(n), pb = std::fabs(q.y) / l1 * double(n);
  const int64_t a0 = std::min(int64_t(pa), n - 1), b0 = std::min(int64_t(pb), n - 1);
  const int64_t si = q.x < 0 ? -1 : 1, sj = q.y < 0 ? -1 : 1;
  // The unit cell's corners, and the far vertices of the four triangles adjacent to its two.
  static constexpr int kCand[8][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {-1, 1}, {1, -1}, {2, 0}, {0, 2}};
  for (const auto& c : kCand) {
    const int64_t a = a0 + c[0], b = b0 + c[1];
    const int64_t aa = a < 0 ? -a : a, ab = b < 0 ? -b : b;
    if (aa + ab > n) continue;
    const int64_t i = si * a, j = sj * b;
    // An equator point (|i| + |j| = n) is canonically its hemisphere-0 copy.
    offer(octaIndex(n, aa + ab == n ? 0 : h, i, j), [=] { return octaPoint(n, s, i, j); });
  }
}

// ---- ea-octa-grid -----------------------------------------------------------------------------
// Cell (i, j) has its centre at (u, v) = (P/n, Q/n), P = 2i + 1 - n, Q = 2j + 1 - n; Clarberg's
// equal-area octahedral map in integer-scaled form (every quantity below is an integer times 1/n).

D3 eaCell(int64_t n, int64_t i, int64_t j) {
  const int64_t p = 2 * i + 1 - n, q = 2 * j + 1 - n;
  const int64_t up = p < 0 ? -p : p, vp = q < 0 ? -q : q;
  int64_t a, b, zs;
  if (up + vp <= n) {  // inner diamond: upper hemisphere
    a = up;
    b = vp;
    zs = 1;
  } else {  // outer triangles: folded onto the lower hemisphere
    a = n - vp;
    b = n - up;
    zs = -1;
  }
  const int64_t r = a + b;  // the radius r = (a + b)/n in [0, 1]
  const double nn = double(n * n);
  if (r == 0) return {0.0, 0.0, double(zs)};
  const double z = double(zs * (n * n - r * r)) / nn;
  const double rho = double(r) * std::sqrt(double(2 * n * n - r * r)) / nn;
  const double ang = double(a) / double(r) * kHalfPi;
  const double angY = double(b) / double(r) * kHalfPi;
  const double x = rho * std::sin(ang), y = rho * std::sin(angY);
  return {p < 0 ? -x : x, q < 0 ? -y : y, z};
}

D3 eaPosition(uint32_t n, uint32_t index) {
  return eaCell(n, index % n, index / n);
}

// The octahedral wrap of a cell index one step outside the grid: crossing an edge of the square
// mirrors the coordinate across that edge and the other coordinate across the square's centre.
void eaWrap(int64_t n, int64_t* i, int64_t* j) {
  if (*i < 0 || *i >= n) {
    *i = *i < 0 ? 0 : n - 1;
    *j = n - 1 - *j;
  }
  if (*j < 0 || *j >= n) {
    *j = *j < 0 ? 0 : n - 1;
    *i = n - 1 - *i;
  }
}

template <class Offer>
void eaCandidates(uint32_t un, const D3& q, Offer&& offer) {
  const int64_t n = un;
  // Inverse map (sphere -> square), exact form of pbrt-v4's EqualAreaSphereToSquare.
  const double x = std::fabs(q.x), y = std::fabs(q.y), z = std::fabs(q.z);
  const double r = std::sqrt((x * x + y * y) / (1.0 + z));  // sqrt(1 - |z|) for a unit vector
  const double b = r * (std::atan2(y, x) / kHalfPi);
  const double a = r - b;
  double up = a, vp = b;
  if (q.z < 0) {
    up = 1.0 - b;
    vp = 1.0 - a;
  }
  const double u = q.x < 0 ? -up : up, v = q.y < 0 ? -vp : vp;
  const double fn = double(n);
  const int64_t i0 = std::clamp(int64_t(std::floor((u + 1.0) * 0.5 * fn)), int64_t(0), n - 1);
  const int64_t j0 = std::clamp(int64_t(std::floor((v + 1.0) * 0.5 * fn)), int64_t(0), n - 1);
  for (int64_t dj = -1; dj <= 1; ++dj)
    for (int64_t di = -1; di <= 1; ++di) {
      int64_t i = i0 + di, j = j0 + dj;
      eaWrap(n, &i, &j);
      offer(uint32_t(j * n + i), [=] { return eaCell(n, i, j); });
    }
}

// ---- fibonacci --------------------------------------------------------------------------------
// z_i = (n - 2i - 1)/n, phi_i = 2 pi frac(i K / 2^64) with K = floor(2^64 (Phi - 1)).

constexpr uint64_t kGolden64 = 0x9E3779B97F4A7C15ull;  // floor(2^64 (Phi - 1)), Phi = (1 + sqrt 5)/2

// frac(m K / 2^64) as a binary64 in [0, 1) (top 53 bits of the 64-bit fraction).
double fibFrac(uint64_t m) {
  return double((m * kGolden64) >> 11) * 0x1p-53;
}

// The same fraction centred in [-1/2, 1/2): the azimuth step of an index offset m, over 2 pi.
double fibStep(uint64_t m) {
  return double(int64_t(m * kGolden64) >> 11) * 0x1p-53;
}

D3 fibPosition(uint32_t n, uint32_t index) {
  const int64_t N = n, i = index;
  const double z = double(N - 2 * i - 1) / double(N);
  const double rho = std::sqrt(double((2 * i + 1) * (2 * N - 2 * i - 1))) / double(N);
  const double phi = fibFrac(index) * kTwoPi;
  return {rho * std::cos(phi), rho * std::sin(phi), z};
}

// F_0 .. F_21. The zone k below is at most 19 for every n <= 2^24.
constexpr uint64_t kFib[22] = {0,  1,   1,   2,   3,   5,   8,    13,   21,   34,   55,
                               89, 144, 233, 377, 610, 987, 1597, 2584, 4181, 6765, 10946};

template <class Offer>
void fibCandidates(uint32_t un, const D3& q, Offer&& offer) {
  const int64_t n = un;
  // Zone: the pair of Fibonacci index offsets (F_k, F_k+1) that form a good lattice basis at the
  // query's latitude (Keinert et al. 2015): k = max(2, floor(log(n pi sqrt5 rho^2) / log(Phi^2))).
  // For v <= 1 (this includes rho = 0, where the logarithm is undefined) k = 2 without it.
  const double rho2 = q.x * q.x + q.y * q.y;
  const double v = double(n) * kPiSqrt5 * rho2;
  const int k = v > 1.0 ? std::clamp(int(std::floor(std::log(v) * kInvLogPhi2)), 2, 20) : 2;
  const uint64_t f0 = kFib[k], f1 = kFib[k + 1];
  // Basis vectors in the unrolled (phi, z) plane, and the query relative to sample 0.
  const double p0 = kTwoPi * fibStep(f0), p1 = kTwoPi * fibStep(f1);
  const double z0 = -2.0 * double(f0) / double(n), z1 = -2.0 * double(f1) / double(n);
  const double phi = std::atan2(q.y, q.x);
  const double dz = q.z - (1.0 - 1.0 / double(n));
  const double det = p0 * z1 - p1 * z0;
  const double c0 = std::floor((phi * z1 - p1 * dz) / det);
  const double c1 = std::floor((p0 * dz - z0 * phi) / det);
  for (int s = 0; s < 4; ++s) {
    const double idx = (c0 + double(s & 1)) * double(f0) + (c1 + double(s >> 1)) * double(f1);
    if (!(idx >= 0.0 && idx < double(n))) continue;
    const uint32_t i = uint32_t(idx);
    offer(i, [=] { return fibPosition(un, i); });
  }
}

}  // namespace

Result<PositionSet> PositionSet::create(PositionScheme scheme, uint32_t param) {
  auto count = positionCount(scheme, param);
  if (!count) return count.error();
  PositionSet set;
  set.scheme_ = scheme;
  set.param_ = param;
  set.count_ = *count;
  return set;
}

Result<PositionSet> PositionSet::fromField(const FieldDesc& f) {
  auto set = create(f.positionScheme, f.positionParam);
  if (!set) return set;
  if (set->count() != f.mapCount)
    return makeError(Code::kMapCount, std::string(positionSchemeName(f.positionScheme)) + " n=" +
                                          std::to_string(f.positionParam) + " yields " + std::to_string(set->count()) +
                                          " maps, mapCount is " + std::to_string(f.mapCount));
  return set;
}

Vec3 PositionSet::position(uint32_t index) const noexcept {
  if (index >= count_) return {};
  switch (scheme_) {
    case PositionScheme::kOctaHemi2:
      return toFloat(octaPosition(param_, index));
    case PositionScheme::kEqualAreaOctaGrid:
      return toFloat(eaPosition(param_, index));
    case PositionScheme::kSphericalFibonacci:
      return toFloat(fibPosition(param_, index));
    case PositionScheme::kInvalid:
      break;
  }
  return {};
}

namespace {

// Normalises a finite, non-zero direction in binary64; false otherwise.
bool unitQuery(Vec3 d, D3* q) {
  *q = {d.x, d.y, d.z};
  if (!std::isfinite(q->x) || !std::isfinite(q->y) || !std::isfinite(q->z)) return false;
  const double len = std::sqrt(dot(*q, *q));
  if (!(len > 0.0)) return false;
  *q = {q->x / len, q->y / len, q->z / len};
  return true;
}

template <class Offer>
void forEachCandidate(PositionScheme scheme, uint32_t param, const D3& q, Offer&& offer) {
  switch (scheme) {
    case PositionScheme::kOctaHemi2:
      octaCandidates(param, q, offer);
      break;
    case PositionScheme::kEqualAreaOctaGrid:
      eaCandidates(param, q, offer);
      break;
    case PositionScheme::kSphericalFibonacci:
      fibCandidates(param, q, offer);
      break;
    case PositionScheme::kInvalid:
      break;
  }
}

}  // namespace

uint32_t PositionSet::nearest(Vec3 direction) const noexcept {
  D3 q;
  if (count_ == 0 || !unitQuery(direction, &q)) return 0;
  Best best;
  forEachCandidate(scheme_, param_, q, [&](uint32_t index, auto&& position) { best.offer(dot(position(), q), index); });
  return best.index;
}

uint32_t PositionSet::candidates(Vec3 direction, uint32_t out[kMaxCandidates]) const noexcept {
  D3 q;
  if (count_ == 0 || !unitQuery(direction, &q)) {
    out[0] = 0;
    return count_ == 0 ? 0 : 1;
  }
  uint32_t count = 0;
  forEachCandidate(scheme_, param_, q, [&](uint32_t index, auto&&) {
    if (count < kMaxCandidates) out[count++] = index;
  });
  return count;
}

}  // namespace vff
