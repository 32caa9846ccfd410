// vff/direction.h - direction maps (inward hemisphere <-> square) and the per-map tangent frame.
//
// Conventions (spec/geometry.md):
//   - A map's local frame is (t, b, n) where n is the *inward* unit normal at the positional sample
//     (n = -p for a sample at unit position p on the sphere) and (t, b) is the Duff et al. 2017 basis.
//   - A local direction (x, y, z) has z = cos(alpha) >= 0, alpha being the angle to n.
//   - Square coordinates (u, v) lie in [-1, 1]^2. Texel (i, j) of an M x M map covers
//     u in [-1 + 2i/M, -1 + 2(i+1)/M], v likewise with j; j is the row (v grows with j).
//     Texel (i, j) is stored at byte index j*M + i of the map (row-major, rows tightly packed).
#pragma once

#include <cstdint>

#include "vff/export.h"
#include "vff/format.h"

namespace vff {

struct Vec3 {
  float x = 0, y = 0, z = 0;
};
struct Vec2 {
  float x = 0, y = 0;
};

// Orthonormal frame (t, b, n) around unit vector n, Duff et al. 2017 ("Building an Orthonormal
// Basis, Revisited") with s = (n.z >= 0 ? 1 : -1):
//   a = -1/(s + n.z), k = n.x n.y a,
//   t = (1 + s n.x^2 a, s k, -s n.x),  b = (k, s + n.y^2 a, -n.y).
struct Frame {
  Vec3 t, b, n;
};
VFF_API Frame frameFromNormal(Vec3 n) noexcept;

// Local (frame) coordinates <-> world coordinates.
VFF_API Vec3 toLocal(const Frame& f, Vec3 world) noexcept;
VFF_API Vec3 toWorld(const Frame& f, Vec3 local) noexcept;

// Square [-1,1]^2 -> unit local direction with z >= 0.
VFF_API Vec3 squareToHemisphere(DirectionScheme scheme, Vec2 uv) noexcept;
// Unit local direction with z >= 0 -> square [-1,1]^2 (inverse of the above). Directions with z < 0
// are treated as z = 0 (the horizon).
VFF_API Vec2 hemisphereToSquare(DirectionScheme scheme, Vec3 dir) noexcept;

// Texel (i, j) containing square point uv, clamped to [0, M-1].
VFF_API void squareToTexel(Vec2 uv, uint32_t mapResolution, uint32_t* i, uint32_t* j) noexcept;
// Centre of texel (i, j) in square coordinates.
VFF_API Vec2 texelCenter(uint32_t i, uint32_t j, uint32_t mapResolution) noexcept;
// The local direction through the centre of texel (i, j).
VFF_API Vec3 texelDirection(DirectionScheme scheme, uint32_t mapResolution, uint32_t i, uint32_t j) noexcept;

}  // namespace vff
