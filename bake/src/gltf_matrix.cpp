// gltf_matrix.cpp - see gltf_matrix.h.
#include "gltf_matrix.h"

#include <cmath>

namespace vff::bake::detail {

GltfMatrix gltfIdentity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

GltfMatrix gltfMul(const GltfMatrix& a, const GltfMatrix& b) {
  GltfMatrix r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[size_t(k * 4 + rr)] * b[size_t(c * 4 + k)];
      r[size_t(c * 4 + rr)] = s;
    }
  return r;
}

GltfMatrix gltfTrs(const double t[3], const double q[4], const double s[3]) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                       2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                       2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
  GltfMatrix m = gltfIdentity();
  for (int c = 0; c < 3; ++c)
    for (int rr = 0; rr < 3; ++rr) m[size_t(c * 4 + rr)] = r[c * 3 + rr] * s[c];
  m[12] = t[0];
  m[13] = t[1];
  m[14] = t[2];
  return m;
}

std::string gltfNotSimilarity(const GltfMatrix& m, double* scale) {
  const double a[3][3] = {{m[0], m[4], m[8]}, {m[1], m[5], m[9]}, {m[2], m[6], m[10]}};
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  if (det < 0) return "mirror";
  if (!(det > 0)) return "non-uniform scale";
  const double s = std::cbrt(det);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double dot = 0;  // (A^T A)_ij
      for (int k = 0; k < 3; ++k) dot += a[k][i] * a[k][j];
      if (std::fabs(dot - (i == j ? s * s : 0.0)) > 1e-5 * s * s) return "non-uniform scale";
    }
  if (scale) *scale = s;
  return "";
}

}  // namespace vff::bake::detail
