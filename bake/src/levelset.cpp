// levelset.cpp - baking from an OpenVDB level set (vff/bake/levelset.h). The only translation unit of
// the baker that includes OpenVDB (its headers are heavy to compile).
//
// Why LevelSetRayIntersector in a loop of our own, not an Embree user geometry in baker.cpp's packet
// pipeline: a user geometry's intersect callback would run the same OpenVDB search one ray at a time
// (OpenVDB has no packet intersector), so Embree's packets would add a BVH of one primitive and a
// callback per ray and no speed; and baker.cpp's Scene is built around a triangle mesh. What the two
// share is what makes the maps (positional samples, texel directions, frames, encodings): libvff's
// public functions, called here exactly as traceMap calls them, with the same split of work (one map
// per task), so the output does not depend on the thread count either.
#include "vff/bake/levelset.h"

#include <sys/stat.h>

#include <openvdb/io/File.h>
#include <openvdb/math/Ray.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/RayIntersector.h>
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <vector>

#include "mesh_importers.h"
#include "platform/parallel.h"
#include "vff/bake/exception_text.h"
#include "vff/bake/sphere.h"
#include "vff/bc4.h"
#include "vff/direction.h"
#include "vff/encoding.h"
#include "vff/positions.h"

namespace vff::bake {

namespace {

// Secant steps after the linear search has bracketed the zero crossing between two samples of the
// interpolated distance. OpenVDB's default is none (one linear interpolation), which leaves a hit up
// to about half a voxel off the interpolant's zero on a sphere; each step cuts that by orders of
// magnitude, and three reach float precision for four more trilinear lookups per hit. The level-set
// tests (vdb_check sphere-error: distances within the interpolation bound of ~1e-2 voxel) fail
// without these steps.
constexpr int kSecantSteps = 3;
using Search = openvdb::tools::LinearSearchImpl<openvdb::FloatGrid, kSecantSteps>;
using Intersector = openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid, Search>;

constexpr unsigned char kVdbMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};  // int64 0x56444220, LE

std::string quoteName(const std::string& s) { return "\"" + s + "\""; }

const char* className(openvdb::GridClass c) {
  switch (c) {
    case openvdb::GRID_LEVEL_SET: return "level set";
    case openvdb::GRID_FOG_VOLUME: return "fog volume";
    case openvdb::GRID_STAGGERED: return "staggered";
    default: return "unknown class";
  }
}

// "\"a\" (float, level set), \"v\" (vec3s, unknown class)": the grids of a file, for messages.
std::string gridList(const openvdb::GridPtrVec& grids) {
  std::string s;
  for (const auto& g : grids) {
    if (!s.empty()) s += ", ";
    s += quoteName(g->getName()) + " (" + g->valueType() + ", " + className(g->getGridClass()) + ")";
  }
  return s;
}

Result<uint64_t> hashFile(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  XXH3_state_t* s = XXH3_createState();
  XXH3_64bits_reset(s);
  std::vector<unsigned char> buf(1 << 20);
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) XXH3_64bits_update(s, buf.data(), n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  const uint64_t h = XXH3_64bits_digest(s);
  XXH3_freeState(s);
  if (failed) return makeError(Code::kIoRead, path + ": cannot be read");
  return h;
}

}  // namespace

struct LevelSet::Impl {
  openvdb::FloatGrid::Ptr grid;
  LevelSetInfo info;
};

LevelSet::LevelSet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;
LevelSet::~LevelSet() = default;
const LevelSetInfo& LevelSet::info() const noexcept { return impl_->info; }

bool looksLikeVdb(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char b[8] = {};
  const size_t n = std::fread(b, 1, 8, f);
  std::fclose(f);
  return n == 8 && std::memcmp(b, kVdbMagic, 8) == 0;
}

Result<LevelSet> LevelSet::load(const std::string& path, const LevelSetLoadOptions& options) {
  // Open errors (a FIFO or folder too: not a regular file) and the magic number first, so that
  // OpenVDB only ever sees .vdb files.
  struct stat st {};
  if (Status s = detail::checkReadable(path, &st); !s) return std::move(s).error();
  auto hash = hashFile(path);
  if (!hash) return std::move(hash).error();
  if (!looksLikeVdb(path))
    return makeError(Code::kMeshParse, path + ": not an OpenVDB file (no .vdb magic number)");
  openvdb::initialize();  // registers the grid types; idempotent and thread-safe

  auto impl = std::make_unique<Impl>();
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    // Grid names, types and classes without the trees, to pick the grid before reading voxels.
    const openvdb::GridPtrVecPtr headers = file.readAllGridMetadata();
    if (!headers || headers->empty()) {
      file.close();
      return makeError(Code::kMeshEmpty, path + ": the file holds no grid");
    }
    openvdb::GridBase::Ptr chosen;
    if (!options.grid.empty()) {
      for (const auto& g : *headers)
        if (g->getName() == options.grid) {
          chosen = g;
          break;
        }
      if (!chosen)
        return makeError(Code::kInvalidArgument,
                         path + ": no grid named " + quoteName(options.grid) + " (grids: " + gridList(*headers) + ")");
      if (chosen->getGridClass() != openvdb::GRID_LEVEL_SET || !chosen->isType<openvdb::FloatGrid>()) {
        const std::string what = chosen->getGridClass() == openvdb::GRID_FOG_VOLUME
                                     ? "a fog volume (densities), not a level set"
                                     : std::string("a ") + chosen->valueType() + " grid of class " +
                                           className(chosen->getGridClass());
        return makeError(Code::kMeshUnsupported,
                         path + ": grid " + quoteName(options.grid) + " is " + what +
                             "; vff-bake bakes float level sets (signed distances, class \"level set\")");
      }
    } else {
      for (const auto& g : *headers)
        if (g->getGridClass() == openvdb::GRID_LEVEL_SET && g->isType<openvdb::FloatGrid>()) {
          chosen = g;
          break;
        }
      if (!chosen)
        return makeError(Code::kMeshUnsupported,
                         path + ": no float grid of class level set (grids: " + gridList(*headers) +
                             "); vff-bake bakes level sets (signed distances), not fog volumes or vector grids");
    }
    // readGrid finds a grid by name: with repeated names, the first of that name (checked again below).
    const openvdb::GridBase::Ptr base = file.readGrid(chosen->getName());
    file.close();
    impl->grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!impl->grid || impl->grid->getGridClass() != openvdb::GRID_LEVEL_SET)
      return makeError(Code::kMeshUnsupported,
                       path + ": grid " + quoteName(chosen->getName()) + " is repeated; its first copy is not a float level set");
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory, path + ": out of memory while reading the grid");
  } catch (const std::exception& e) {
    return makeError(Code::kMeshParse, path + ": cannot read as OpenVDB (corrupt or truncated): " + exceptionText(e));
  }

  const openvdb::FloatGrid& g = *impl->grid;
  LevelSetInfo& info = impl->info;
  info.grid = g.getName();
  info.fileXxh3 = *hash;
  const std::string where = path + ": grid " + quoteName(info.grid);
  if (!g.transform().isLinear())
    return makeError(Code::kMeshUnsupported, where + " has a non-linear (frustum) transform; only linear ones are supported");
  if (!g.hasUniformVoxels())
    return makeError(Code::kMeshUnsupported, where + " has non-cubic voxels; the ray intersector needs uniform ones");
  info.voxelSize = g.voxelSize()[0];
  const float background = g.background();
  if (!std::isfinite(background) || !(background > 0) || !(info.voxelSize > 0) || !std::isfinite(info.voxelSize))
    return makeError(Code::kMeshUnsupported,
                     where + " is not a narrow-band level set: its background (the band's half width) is " +
                         std::to_string(background));
  info.halfWidth = background / info.voxelSize;
  info.activeVoxels = g.activeVoxelCount();
  if (info.activeVoxels == 0) return makeError(Code::kMeshEmpty, where + " has no active voxel: no surface");
  const openvdb::CoordBBox box = g.evalActiveVoxelBoundingBox();
  for (int k = 0; k < 3; ++k) {
    info.boundsMin[k] = std::numeric_limits<double>::infinity();
    info.boundsMax[k] = -std::numeric_limits<double>::infinity();
  }
  for (int c = 0; c < 8; ++c) {
    const openvdb::Vec3d ijk((c & 1 ? box.max() : box.min()).x(), (c & 2 ? box.max() : box.min()).y(),
                             (c & 4 ? box.max() : box.min()).z());
    const openvdb::Vec3d w = g.indexToWorld(ijk);
    for (int k = 0; k < 3; ++k) {
      info.boundsMin[k] = std::min(info.boundsMin[k], w[k]);
      info.boundsMax[k] = std::max(info.boundsMax[k], w[k]);
    }
  }
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(info.boundsMin[k]) || !std::isfinite(info.boundsMax[k]) ||
        std::abs(info.boundsMin[k]) > 1e30 || std::abs(info.boundsMax[k]) > 1e30)
      return makeError(Code::kMeshUnsupported, where + " has bounds that do not fit in float coordinates");
  return LevelSet(std::move(impl));
}

Result<FieldDesc> describeLevelSetBake(const LevelSet& levelSet, const BakeOptions& options) {
  BakeOptions o = options;
  if (!o.sphere) {
    const LevelSetInfo& info = levelSet.info();
    std::vector<float> corners;
    for (int c = 0; c < 8; ++c)
      for (int k = 0; k < 3; ++k)
        corners.push_back(static_cast<float>((c >> k) & 1 ? info.boundsMax[k] : info.boundsMin[k]));
    Sphere s = minimalEnclosingSphere(corners);
    // A band one voxel thick (a single plane) still gets a sphere with a radius.
    if (!(s.radius > 0)) s.radius = static_cast<float>(info.voxelSize);
    o.sphere = s;
  }
  return describeBake(Mesh{}, o);  // with a sphere given, describeBake does not look at the mesh
}

Result<BakedField> bakeLevelSet(const LevelSet& levelSet, const BakeOptions& options) {
  auto fd = describeLevelSetBake(levelSet, options);
  if (!fd) return std::move(fd).error();
  const FieldDesc f = *fd;
  auto ps = PositionSet::fromField(f);
  if (!ps) return std::move(ps).error();
  const uint32_t m = f.mapResolution;
  const size_t texels = size_t(m) * m;
  std::vector<Vec3> local(texels);
  std::vector<float> cosAlpha(texels);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) {
      local[size_t(j) * m + i] = texelDirection(f.directionScheme, m, i, j);
      cosAlpha[size_t(j) * m + i] = local[size_t(j) * m + i].z;
    }
  const uint64_t distBytes = distanceMapBytes(f.distanceEncoding, m);
  const uint64_t normBytes = normalMapBytes(f.normalEncoding, m);

  BakedField out;
  out.field = f;
  try {
    out.distance.assign(distBytes * f.mapCount, 0);
    if (options.normals) out.normals.assign(normBytes * f.mapCount, 0);
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory,
                     "cannot allocate the field's " + std::to_string((distBytes + normBytes) * f.mapCount) + " bytes");
  }

  const openvdb::FloatGrid& grid = *levelSet.impl_->grid;
  std::unique_ptr<Intersector> master;
  try {
    master = std::make_unique<Intersector>(grid);
  } catch (const std::exception& e) {
    return makeError(Code::kMeshUnsupported, "grid \"" + grid.getName() + "\": " + exceptionText(e));
  }
  const float R = f.sphere.radius;
  // Rays end well past the far side of the sphere (2R): only empty space lies beyond it.
  const double tMax = 4.0 * double(R);

  auto traceMap = [&](Intersector& isect, uint32_t k) -> uint64_t {
    const Vec3 u = ps->position(k);
    const Vec3 origin{f.sphere.center[0] + R * u.x, f.sphere.center[1] + R * u.y, f.sphere.center[2] + R * u.z};
    const Frame frame = frameFromNormal({-u.x, -u.y, -u.z});
    const std::span<uint8_t> dmap(out.distance.data() + k * distBytes, distBytes);
    uint8_t* nmap = options.normals ? out.normals.data() + k * normBytes : nullptr;
    uint64_t hits = 0;
    // bc4-diameter: the map's unorm8-diameter codes first, then its BC4 blocks (vff/bc4.h).
    const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
    thread_local std::vector<uint8_t> codes;
    if (bc4) codes.assign(texels, 255);
    for (size_t t = 0; t < texels; ++t) {
      const Vec3 d = toWorld(frame, local[t]);
      openvdb::Vec3d dir(d.x, d.y, d.z);
      dir.normalize();
      // t0 is OpenVDB's smallest positive time (its Ray asserts t0 > 0 in debug builds).
      const Intersector::RayType ray(openvdb::Vec3d(origin.x, origin.y, origin.z), dir,
                                     openvdb::math::Delta<double>::value(), tMax);
      openvdb::Vec3d world, normal;
      double time = 0;
      const bool hit = isect.intersectsWS(ray, world, normal, time);
      hits += hit;
      const float distance = hit ? std::max(0.0f, static_cast<float>(time)) : 0.0f;
      const uint32_t code = encodeDistance(f.distanceEncoding, hit, distance, R, cosAlpha[t]);
      if (bc4) codes[t] = uint8_t(code);
      else storeCode(f.distanceEncoding, dmap, m, uint32_t(t % m), uint32_t(t / m), code);
      if (nmap && hit) {
        // The intersector's normal is the gradient of the trilinear interpolant, already taken to
        // world space by the inverse transpose of the grid's Jacobian (BoxStencil::gradient), and
        // normalised; normalised again in float for encodeNormal.
        const double len = normal.length();
        if (len > 0 && std::isfinite(len))
          encodeNormal({float(normal.x() / len), float(normal.y() / len), float(normal.z() / len)}, nmap + 4 * t);
      }
    }
    if (bc4) encodeBc4Map(codes, m, dmap);
    return hits;
  };

  const uint32_t maps = f.mapCount;
  std::atomic<uint64_t> hits{0}, done{0};
  // Each worker its own copy of the intersector, made on its thread: the search's value accessor is
  // not thread-safe (and each copy on the heap of its own, away from the others' cache lines).
  std::vector<std::unique_ptr<Intersector>> isects(parallel::workerCount(maps, 1, options.threads));
  const auto t0 = std::chrono::steady_clock::now();
  parallel::parallelForWorkers(maps, 1, options.threads, [&](unsigned w, size_t begin, size_t end) {
    if (!isects[w]) isects[w] = std::make_unique<Intersector>(*master);
    for (size_t i = begin; i < end; ++i) {
      hits.fetch_add(traceMap(*isects[w], uint32_t(i)), std::memory_order_relaxed);
      const uint64_t n = done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (options.progress) options.progress(n, maps);
    }
  });
  out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.stats.rays = uint64_t(maps) * texels;
  out.stats.hits = hits;
  return out;
}

}  // namespace vff::bake
