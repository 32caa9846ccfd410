// vff/positions.h - the positional samples on the bounding sphere: index <-> unit vector, and the
// O(1) nearest-sample lookup.
//
// The normative definition is spec/positions.md; this header is its manual. A field stores one map
// per positional sample. Sample `index` sits at the outward unit vector position(index) on the
// (unit) bounding sphere, and its map looks inward: the map's frame is frameFromNormal(-position(i))
// (vff/direction.h). All three schemes are parameterised by one integer n (FieldDesc::positionParam):
//
//   octa-hemi2 (kOctaHemi2), 1 <= n <= 1024, 2(2n^2 + 2n + 1) samples (4226 at n = 32, 16642 at
//     n = 64; the layout of Gaitatzes et al. 2008 / 2010). Two hemispheres, upper (z >= 0) first:
//     the vertices of the upper, then the lower, half of an octahedron whose edges are split into n
//     segments, projected radially onto the sphere. The 4n equator vertices belong to both halves
//     and are stored once per hemisphere (twice in all); nearest() returns the upper copy.
//   ea-octa-grid (kEqualAreaOctaGrid), 1 <= n <= 2048, n^2 samples: the centres of an n x n grid of
//     cells on the square [-1,1]^2 mapped to the sphere with Clarberg's equal-area octahedral map
//     (as pbrt-v4's EqualAreaSquareToSphere). Every sample covers the same solid angle 4 pi / n^2.
//   fibonacci (kSphericalFibonacci), 1 <= n <= 2^24, n samples: the spherical Fibonacci point set
//     of Keinert et al. 2015, z_i = 1 - (2i+1)/n, phi_i = 2 pi frac(i (Phi - 1)).
//
// Precision. position() evaluates the spec's formulas in binary64 and rounds once to float32 (in
// practice the correctly rounded value; bit-identical across IEEE-754 platforms up to the last bit
// of the C library's sin/cos). nearest() is exact: it returns the sample with the largest dot
// product with the query among all samples (computed in binary64 from the unrounded positions),
// equal dot products going to the smallest index. A binary32 port of the same algorithm (the GLSL
// listing in the spec) returns the same index except within binary32 rounding of a tie, where
// either sample is equally near.
#pragma once

#include <cstdint>

#include "vff/direction.h"
#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"

namespace vff {

// An immutable description of a positional sample set. Holds a few scalars: cheap to copy, and
// every member function is const and thread-safe. A default-constructed PositionSet is empty
// (scheme kInvalid, count 0); only create() and fromField() make a usable one.
class VFF_API PositionSet {
 public:
  PositionSet() = default;

  // The sample set of `scheme` with parameter `param` (the n above). Fails with kPositionScheme for
  // an unknown scheme or a parameter outside the range above (the same check as positionCount()).
  static Result<PositionSet> create(PositionScheme scheme, uint32_t param);

  // The sample set of a field description: create(f.positionScheme, f.positionParam), and then
  // kMapCount unless f.mapCount equals count(). Nothing else of `f` is checked.
  static Result<PositionSet> fromField(const FieldDesc& f);

  PositionScheme scheme() const noexcept { return scheme_; }
  uint32_t param() const noexcept { return param_; }
  uint32_t count() const noexcept { return count_; }  // number of samples (= maps)

  // The outward unit vector of sample `index`. Precondition: index < count(); an index out of
  // range returns {0, 0, 0} (as does every index when count() == 0). Deterministic: see Precision.
  Vec3 position(uint32_t index) const noexcept;

  // The index of the sample nearest to `direction` (largest dot product), in O(1). The direction
  // need not be normalised; it must be finite and non-zero, otherwise (and for an empty set) the
  // result is 0. Always returns an index < count() when count() > 0. nearest(position(i)) == i for
  // every i, except the lower copy of an octa-hemi2 equator sample, which returns its upper copy.
  uint32_t nearest(Vec3 direction) const noexcept;

  // The candidates nearest() chooses from, in O(1) (at most kMaxCandidates; the nearest sample is
  // always among them): for callers that keep their own table of positions, such as a binary32
  // query, which then take the candidate with the largest dot product, ties to the smallest index.
  // Returns their number (>= 1 when count() > 0; a zero or non-finite direction gives {0}).
  static constexpr uint32_t kMaxCandidates = 9;
  uint32_t candidates(Vec3 direction, uint32_t out[kMaxCandidates]) const noexcept;

  // The map frame of sample `index`: frameFromNormal(-position(index)). Same precondition.
  Frame frame(uint32_t index) const noexcept { return frameFromNormal(negate(position(index))); }

 private:
  static Vec3 negate(Vec3 v) noexcept { return {-v.x, -v.y, -v.z}; }

  PositionScheme scheme_ = PositionScheme::kInvalid;
  uint32_t param_ = 0;
  uint32_t count_ = 0;
};

}  // namespace vff
