// vff/bake/sphere.h - the minimal enclosing sphere of a point set.
#pragma once

#include <span>

#include "vff/format.h"

namespace vff::bake {

// The smallest sphere containing every point (Welzl's algorithm, move-to-front, on a fixed-seed
// shuffle so the result is deterministic), computed in double precision, then rounded to float so
// that every point is still inside: the returned radius is the largest float distance from the
// float centre, rounded up. `xyz` holds 3 floats per point; at least one point.
Sphere minimalEnclosingSphere(std::span<const float> xyz);

}  // namespace vff::bake
