// sdf_build.cpp - SdfField::build: OpenVDB's narrow-band level set of a mesh, copied into NanoVDB,
// its voxel size searched for the largest grid within the byte budget (sdf_field.h). The only
// translation unit of vff-experiments that includes OpenVDB (its headers are heavy to compile).
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <string>

#include "sdf_impl.h"

namespace vffx {

namespace {

struct Geometry {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  double area = 0;
  openvdb::Vec3d lo{std::numeric_limits<double>::max()};
};

Geometry toOpenVdb(const vff::bake::Mesh& m) {
  Geometry g;
  g.points.reserve(m.vertexCount());
  for (size_t v = 0; v < m.vertexCount(); ++v)
    g.points.emplace_back(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
  for (const openvdb::Vec3s& p : g.points) g.lo = openvdb::math::minComponent(g.lo, openvdb::Vec3d(p));
  g.triangles.reserve(m.triangleCount());
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const openvdb::Vec3I tri(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
    g.triangles.push_back(tri);
    const openvdb::Vec3d a(g.points[tri[0]]), b(g.points[tri[1]]), c(g.points[tri[2]]);
    g.area += 0.5 * (b - a).cross(c - a).length();
  }
  return g;
}

// One grid at voxel size h: the level set, then its NanoVDB copy. The index space starts a band
// and two voxels below the mesh's box, so that every index is positive and the tree has one root
// tile (an object across the origin would take eight of NanoVDB's upper nodes).
nanovdb::GridHandle<nanovdb::HostBuffer> buildAt(const Geometry& g, double h, const SdfBuildOptions& o) {
  const openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(h);
  xform->postTranslate(g.lo - openvdb::Vec3d(h * (o.bandVoxels + 2.0)));
  const openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
      *xform, g.points, g.triangles, {}, o.bandVoxels, o.bandVoxels);
  if (o.values == SdfValues::kFp8)
    return nanovdb::openToNanoVDB<nanovdb::HostBuffer, openvdb::FloatTree, nanovdb::Fp8>(*grid);
  return nanovdb::openToNanoVDB<nanovdb::HostBuffer, openvdb::FloatTree, float>(*grid);
}

struct Sizes {
  uint64_t bricks = 0, dense = 0;
  uint32_t dims[3] = {0, 0, 0};
};

// The brick layout's bytes and the dense grid's (sdf_field.h), from the grid's leaves and box.
Sizes measure(const nanovdb::GridHandle<nanovdb::HostBuffer>& handle, SdfValues values) {
  const bool fp8 = values == SdfValues::kFp8;
  const nanovdb::CoordBBox box = fp8 ? handle.grid<nanovdb::Fp8>()->indexBBox() : handle.grid<float>()->indexBBox();
  const uint64_t leaves = fp8 ? handle.grid<nanovdb::Fp8>()->tree().nodeCount(0) : handle.grid<float>()->tree().nodeCount(0);
  Sizes s;
  s.dense = fp8 ? 1 : 4;
  uint64_t blocks = 1;
  for (int a = 0; a < 3; ++a) {
    s.dims[a] = box.empty() ? 0 : uint32_t(box.max()[a] - box.min()[a] + 1);
    s.dense *= s.dims[a];
    blocks *= (s.dims[a] + 7) / 8;
  }
  s.bricks = leaves * (fp8 ? 512 + 8 : 512 * 4) + blocks * 4;
  return s;
}

}  // namespace

SdfField::SdfField(SdfField&&) noexcept = default;
SdfField& SdfField::operator=(SdfField&&) noexcept = default;
SdfField::~SdfField() = default;

vff::Result<SdfField> SdfField::build(const vff::bake::Mesh& objectMesh, const SdfBuildOptions& options) {
  if (objectMesh.triangleCount() == 0) return vff::makeError(vff::Code::kInvalidArgument, "the mesh has no triangles");
  if (!(options.bandVoxels >= 1.0f)) return vff::makeError(vff::Code::kInvalidArgument, "the band must be a voxel wide at least");
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::initialize();
  const Geometry g = toOpenVdb(objectMesh);
  const double budget = double(options.budgetBytes);
  const double valueBytes = options.values == SdfValues::kFp8 ? 1.0 : 4.0;
  // First guess: the band's voxels (area x 2 bands / h^2), about twice that once rounded up to
  // whole leaves with their headers.
  double h = std::sqrt(std::max(g.area, 1e-12) * 2.0 * options.bandVoxels * valueBytes * 2.0 / budget);
  if (options.budgetBytes < kSdfMinBudget)
    return vff::makeError(vff::Code::kInvalidArgument, "a budget under " + std::to_string(kSdfMinBudget) + " bytes holds no distance grid");
  double exponent = 2.0;  // bytes ~ h^-exponent: a band's area; a volume's (3) when the band fills the object
  double prevH = 0, prevBytes = 0, bestBytes = 0;
  SdfField out;
  out.impl_ = std::make_unique<Impl>();
  try {
    for (int k = 0; k < 24; ++k) {
      nanovdb::GridHandle<nanovdb::HostBuffer> handle = buildAt(g, h, options);
      ++out.impl_->builds;
      const Sizes sizes = measure(handle, options.values);
      const double bytes = double(sizes.bricks);
      if (bytes <= budget && bytes > bestBytes) {
        bestBytes = bytes;
        out.impl_->handle = std::move(handle);
        out.impl_->voxel = float(h);
        out.impl_->bricks = sizes.bricks;
        out.impl_->dense = sizes.dense;
        std::copy(sizes.dims, sizes.dims + 3, out.impl_->dims);
      }
      // Close enough under the budget: leaves come in 8^3 units, so the size moves in steps.
      if (bestBytes >= 0.96 * budget || (k >= 5 && bestBytes > 0)) break;
      if (prevH > 0 && bytes != prevBytes && h != prevH)
        exponent = std::clamp(std::log(bytes / prevBytes) / std::log(prevH / h), 1.5, 3.5);
      prevH = h;
      prevBytes = bytes;
      // Aim a little under the budget, so that the next step is likelier to fit.
      h *= std::pow(bytes / (0.98 * budget), 1.0 / exponent);
    }
  } catch (const std::bad_alloc&) {
    return vff::makeError(vff::Code::kOutOfMemory, "out of memory while building the distance grid");
  } catch (const std::exception& e) {
    return vff::makeError(vff::Code::kBadState, std::string("OpenVDB: ") + e.what());
  }
  if (bestBytes == 0)
    return vff::makeError(vff::Code::kInvalidArgument,
                          "no distance grid of this mesh fits in " + std::to_string(options.budgetBytes) + " bytes");
  Impl& s = *out.impl_;
  s.values = options.values;
  s.band = options.bandVoxels;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace vffx
