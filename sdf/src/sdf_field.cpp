// sdf_field.cpp - sphere tracing through SdfField's NanoVDB grid (sdf_field.h), with NanoVDB's
// read accessor (it caches the path to the last leaf, which consecutive steps of a ray mostly
// revisit). One template over the grid's value type (Fp8 or float).
//
// The trilinear sample is written here: Debian's nanovdb/util/SampleFromVoxels.h (10.0.1) does not
// compile (it names is_floating_point without its namespace). It is the same interpolation: the
// eight values around floor(p), voxel centres at integer coordinates.
#include <algorithm>
#include <cmath>
#include <limits>

#include "sdf_impl.h"

namespace vffx {

namespace {

using vff::Vec3;

template <class BuildT>
class Tracer {
 public:
  using Grid = nanovdb::NanoGrid<BuildT>;
  using Accessor = typename Grid::AccessorType;

  Tracer(const Grid* grid, float voxel, float band, const vff::RigidTransform& transform)
      : grid_(grid), acc_(grid->getAccessor()), voxel_(voxel), band_(band), transform_(transform) {
    const nanovdb::CoordBBox box = grid->indexBBox();
    // Beyond the active voxels every value is the band's (a tile): a sample there needs its
    // neighbour inside, so the box is one voxel wider than the active one.
    for (int a = 0; a < 3; ++a) {
      lo_[a] = float(box.min()[a]) - 1.0f;
      hi_[a] = float(box.max()[a]) + 1.0f;
    }
  }

  // Distance in voxels at index-space point p.
  float sample(const nanovdb::Vec3f& p) const {
    const float fx = std::floor(p[0]), fy = std::floor(p[1]), fz = std::floor(p[2]);
    const float u = p[0] - fx, v = p[1] - fy, w = p[2] - fz;
    const int32_t x = int32_t(fx), y = int32_t(fy), z = int32_t(fz);
    float c[2][2][2];
    // The eight values from one leaf when they all lie in it (most cells), else through the accessor.
    const auto* leaf = ((x & 7) < 7 && (y & 7) < 7 && (z & 7) < 7) ? acc_.probeLeaf(nanovdb::Coord(x, y, z)) : nullptr;
    for (int32_t i = 0; i < 2; ++i)
      for (int32_t j = 0; j < 2; ++j)
        for (int32_t k = 0; k < 2; ++k)
          c[i][j][k] = leaf ? leaf->getValue(nanovdb::Coord(x + i, y + j, z + k))
                            : acc_.getValue(nanovdb::Coord(x + i, y + j, z + k));
    auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
    const float x00 = lerp(c[0][0][0], c[1][0][0], u), x10 = lerp(c[0][1][0], c[1][1][0], u);
    const float x01 = lerp(c[0][0][1], c[1][0][1], u), x11 = lerp(c[0][1][1], c[1][1][1], u);
    return lerp(lerp(x00, x10, v), lerp(x01, x11, v), w) / voxel_;
  }

  // Traces one world ray. cone: tan(half-angle) of the cone estimate, 0 for none; *visibility gets
  // it (1 without a cone: the caller uses hit). Returns the hit, t and the index-space hit point.
  SdfHit trace(const vff::Ray& ray, const SdfTraceOptions& o, float cone, float* visibility,
               nanovdb::Vec3f* at) const {
    SdfHit h;
    *visibility = 1.0f;
    const Vec3 po = transform_.toObjectPoint(ray.origin), vo = transform_.toObjectVector(ray.direction);
    const nanovdb::Vec3f org = grid_->worldToIndexF(nanovdb::Vec3f(po.x, po.y, po.z));
    const nanovdb::Vec3f dir = grid_->worldToIndexDirF(nanovdb::Vec3f(vo.x, vo.y, vo.z));
    const float len = dir.length();  // voxels per unit of t
    if (!(len > 0)) return h;
    // The slab test against the grid's box.
    float t0 = ray.tmin + o.startVoxels / len, t1 = ray.tmax;
    for (int a = 0; a < 3; ++a) {
      if (dir[a] == 0) {  // parallel to the slab: inside it or never
        if (org[a] < lo_[a] || org[a] > hi_[a]) return h;
        continue;
      }
      const float inv = 1.0f / dir[a];
      float ta = (lo_[a] - org[a]) * inv, tb = (hi_[a] - org[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (!(t0 <= t1)) return h;
    const float minStep = o.minStepVoxels / len;
    float t = t0;
    for (int step = 0; step < o.maxSteps; ++step) {
      const nanovdb::Vec3f p = org + dir * t;
      const float d = sample(p);
      h.steps = step + 1;
      // Empty-space skipping: the next step reaches at least the end of the empty block around p.
      const float skip = o.skipEmpty ? emptyExit(p, org, dir) : 0.0f;
      if (cone > 0) {
        // The share of the cone's disc left open, as a ramp over its radius at t: a half when the
        // axis grazes the surface; the trace goes on inside until the disc is covered.
        *visibility = std::min(*visibility, 0.5f + 0.5f * d / (std::max(t * len, kSdfConeMinDistance) * cone));
        // Deeper inside than the band reaches: the depth is unknown, and the disc taken as covered.
        if (*visibility <= 0.0f || d <= -kSdfConeDepth * band_) {
          h.hit = true;
          h.t = t;
          *visibility = 0.0f;
          return h;
        }
        t = std::max(t + std::max(std::fabs(d) / len, minStep), skip);
        if (t > t1) break;
        continue;
      }
      if (d < o.hitVoxels) {
        h.hit = true;
        h.t = t;
        *at = p;
        *visibility = 0.0f;
        return h;
      }
      t = std::max(t + std::max(d / len, minStep), skip);
      if (t > t1) break;
    }
    *visibility = std::clamp(*visibility, 0.0f, 1.0f);
    return h;
  }

  // When the voxel nearest p lies in a block of the tree with no leaf (a tile: 8^3, 128^3 or 4096^3
  // voxels with no surface voxel), the t where the ray leaves the points whose nearest voxel is in
  // that block: no surface lies there (a surface there would have made the voxels around it active,
  // the band being a voxel wide at least). Else 0.
  float emptyExit(const nanovdb::Vec3f& p, const nanovdb::Vec3f& org, const nanovdb::Vec3f& dir) const {
    const nanovdb::Coord ijk(int32_t(std::lround(p[0])), int32_t(std::lround(p[1])), int32_t(std::lround(p[2])));
    const int32_t dim = int32_t(acc_.getDim(ijk, 0));
    if (dim <= 1) return 0.0f;
    float exit = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (dir[a] == 0) continue;
      const float base = float(ijk[a] & ~(dim - 1));
      const float bound = dir[a] > 0 ? base + float(dim) - 0.5f : base - 0.5f;
      exit = std::min(exit, (bound - org[a]) / dir[a]);
    }
    return std::isfinite(exit) ? exit * (1.0f + kSdfSkipNudge) + kSdfSkipNudge : 0.0f;
  }

  // The unit world-space normal at index point p: the distance's central differences.
  Vec3 normal(const nanovdb::Vec3f& p) const {
    const float e = 0.5f;
    const float gx = sample(p + nanovdb::Vec3f(e, 0, 0)) - sample(p - nanovdb::Vec3f(e, 0, 0));
    const float gy = sample(p + nanovdb::Vec3f(0, e, 0)) - sample(p - nanovdb::Vec3f(0, e, 0));
    const float gz = sample(p + nanovdb::Vec3f(0, 0, e)) - sample(p - nanovdb::Vec3f(0, 0, e));
    const Vec3 n = transform_.toWorldVector(Vec3{gx, gy, gz});
    const float l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    return l > 0 ? Vec3{n.x / l, n.y / l, n.z / l} : Vec3{0, 1, 0};
  }

 private:
  const Grid* grid_;
  Accessor acc_;
  float voxel_, band_;
  const vff::RigidTransform& transform_;
  float lo_[3], hi_[3];
};

// tan(half-angle) of the cone estimate for this ray; 0: none.
float coneTan(const vff::Ray& ray, const SdfTraceOptions& o) {
  if (o.coneRadiusAtEnd > 0) {
    const float l = std::sqrt(ray.direction.x * ray.direction.x + ray.direction.y * ray.direction.y +
                              ray.direction.z * ray.direction.z);
    return o.coneRadiusAtEnd / (ray.tmax * l);
  }
  return std::max(o.coneTan, 0.0f);
}

// fn(tracer) with the tracer of the grid's value type.
template <class Fn>
void withTracer(const SdfField::Impl& s, const vff::RigidTransform& transform, Fn&& fn) {
  if (s.values == SdfValues::kFp8)
    fn(Tracer<nanovdb::Fp8>(s.handle.grid<nanovdb::Fp8>(), s.voxel, s.band, transform));
  else
    fn(Tracer<float>(s.handle.grid<float>(), s.voxel, s.band, transform));
}

}  // namespace

SdfHit SdfField::intersect(const vff::Ray& ray, const SdfTraceOptions& options) const {
  SdfHit h;
  withTracer(*impl_, transform, [&](const auto& tracer) {
    float vis = 0;
    nanovdb::Vec3f at;
    h = tracer.trace(ray, options, 0.0f, &vis, &at);
    if (h.hit) h.normal = tracer.normal(at);
  });
  return h;
}

bool SdfField::occluded(const vff::Ray& ray, const SdfTraceOptions& options) const {
  uint8_t out = 0;
  occluded(std::span<const vff::Ray>(&ray, 1), std::span<uint8_t>(&out, 1), options);
  return out != 0;
}

float SdfField::visibility(const vff::Ray& ray, const SdfTraceOptions& options) const {
  float out = 0;
  visibility(std::span<const vff::Ray>(&ray, 1), std::span<float>(&out, 1), options);
  return out;
}

void SdfField::occluded(std::span<const vff::Ray> rays, std::span<uint8_t> out, const SdfTraceOptions& options) const {
  withTracer(*impl_, transform, [&](const auto& tracer) {
    float vis = 0;
    nanovdb::Vec3f at;
    for (size_t i = 0; i < rays.size() && i < out.size(); ++i)
      out[i] = tracer.trace(rays[i], options, 0.0f, &vis, &at).hit ? 1 : 0;
  });
}

void SdfField::visibility(std::span<const vff::Ray> rays, std::span<float> out, const SdfTraceOptions& options) const {
  withTracer(*impl_, transform, [&](const auto& tracer) {
    float vis = 0;
    nanovdb::Vec3f at;
    for (size_t i = 0; i < rays.size() && i < out.size(); ++i) {
      const float cone = coneTan(rays[i], options);
      const bool hit = tracer.trace(rays[i], options, cone, &vis, &at).hit;
      out[i] = cone > 0 ? vis : hit ? 0.0f : 1.0f;
    }
  });
}

uint64_t SdfField::bytes() const { return impl_->bricks; }
uint64_t SdfField::nanovdbBytes() const { return impl_->handle.size(); }
uint64_t SdfField::denseBytes() const { return impl_->dense; }
float SdfField::voxelSize() const { return impl_->voxel; }
uint32_t SdfField::dims(int axis) const { return impl_->dims[axis]; }
SdfValues SdfField::values() const { return impl_->values; }
int SdfField::builds() const { return impl_->builds; }
double SdfField::buildSeconds() const { return impl_->seconds; }
float SdfField::bandVoxels() const { return impl_->band; }
std::span<const uint8_t> SdfField::gridBuffer() const {
  return {static_cast<const uint8_t*>(impl_->handle.data()), size_t(impl_->handle.size())};
}

}  // namespace vffx
