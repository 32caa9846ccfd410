// surface_sampler.h - points on a mesh's surface, area-weighted, with their face normals: where
// the benchmarks start AO rays, as a renderer's AO pass does.
#pragma once

#include <algorithm>
#include <utility>
#include <vector>

#include "common.h"

namespace vffx {

// The mesh's points, less `center` (the object's frame centred on its sphere, or zero).
class SurfaceSampler {
 public:
  SurfaceSampler(const vff::bake::Mesh& m, const float center[3]) : m_(m) {
    for (int a = 0; a < 3; ++a) c_[a] = center[a];
    double sum = 0;
    cdf_.reserve(m.triangleCount());
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      sum += double(length(cross(vertex(t, 1) - vertex(t, 0), vertex(t, 2) - vertex(t, 0))));
      cdf_.push_back(sum);
    }
  }
  // A point and its unit face normal from three uniform numbers.
  std::pair<Vec3, Vec3> sample(float u0, float u1, float u2) const {
    const size_t t = std::min(cdf_.size() - 1, size_t(std::lower_bound(cdf_.begin(), cdf_.end(), double(u0) * cdf_.back()) -
                                                      cdf_.begin()));
    const float su = std::sqrt(u1);
    const Vec3 a = vertex(t, 0), b = vertex(t, 1), c = vertex(t, 2);
    return {a * (1 - su) + b * (su * (1 - u2)) + c * (su * u2), normalize(cross(b - a, c - a))};
  }

 private:
  Vec3 vertex(size_t t, int k) const {
    const float* p = &m_.positions[3 * size_t(m_.indices[3 * t + size_t(k)])];
    return {p[0] - c_[0], p[1] - c_[1], p[2] - c_[2]};
  }
  const vff::bake::Mesh& m_;
  float c_[3];
  std::vector<double> cdf_;
};

}  // namespace vffx
