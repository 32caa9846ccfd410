// vec3.h - the small vector arithmetic of the query tests (libvff's own operators are internal).
#pragma once

#include <cmath>

#include "vff/direction.h"
#include "vff/format.h"

namespace vff::test {

inline Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 mul(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 unit(Vec3 a) { return mul(a, 1.0f / std::sqrt(dot3(a, a))); }
// The centre of a field's bounding sphere.
inline Vec3 centerOf(const FieldDesc& f) { return {f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]}; }

}  // namespace vff::test
