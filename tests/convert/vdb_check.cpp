// vdb_check: writes the OpenVDB inputs of the level-set and .vdb export tests and checks results
// against OpenVDB (read independently of vff-convert) or against exact geometry.
//
//   vdb_check write OUT.vdb [GRID...]
//       a .vdb with the listed grids, in that order (no GRID: a file without grids). GRID is one of
//         sphere,NAME,R,CX,CY,CZ,H       level set of a sphere (openvdb::tools::createLevelSetSphere),
//                                        voxel size H, half width 3 voxels
//         rotsphere,NAME,R,CX,CY,CZ,H    the same sphere sampled on a rotated and shifted voxel grid
//                                        (exact distances at the voxel centres)
//         mesh,NAME,SHAPE,H              meshToLevelSet of a procedural mesh (vff/bake/procedural.h)
//         meshfile,NAME,PATH,H           meshToLevelSet of a mesh file (vff/bake/mesh.h importers)
//         fog,NAME                       a fog volume (sdfToFogVolume of a unit sphere)
//         vector,NAME                    a Vec3f grid
//         float,NAME                     a float grid of unknown class
//         emptyls,NAME                   a level set without active voxels
//         stretched,NAME                 a level set with non-cubic voxels
//   vdb_check sphere-error FIELD.vff CX CY CZ R H
//       checks every texel of FIELD, baked from a level set of the sphere (C, R) with voxel size H,
//       against the exact ray-sphere intersection (bounds below); prints the largest errors; exit 1
//       when a texel breaks its bound.
//   vdb_check verify FIELD.vff EXPORT.vdb
//       checks a vff-convert --to vdb export against its source: grids, types, classes, backgrounds,
//       metadata, and every voxel of every slice (composed by libvff's File::readSlice) against the
//       texel there: active exactly at hits, holding the decoded distance and normal.
//   vdb_check count-hits FIELD.vff
//       prints the number of hit texels of the field's maps.
//   vdb_check provenance EXPORT.vdb SOURCE
//       prints the export's vff.provenance and checks it: SOURCE's own META entries, then the
//       export's entry naming SOURCE (file name, format, XXH3-64 of its bytes, its field).
//   vdb_check edit IN.vdb OUT.vdb voxel-outside|field-json|scale-values
//       a damaged copy: an active voxel outside the slices, vff.field replaced by "{}", or every
//       non-zero distance multiplied by 1.0001.
//   vdb_check compare-mesh MESH.vff LEVELSET.vff H
//       compares a mesh bake with a bake of the mesh's level set (same sphere and options): hit/miss
//       agreement and distance differences, with the thresholds printed.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include <xxhash.h>

#include <fstream>
#include <iterator>

#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vff/vff.h"

namespace {

using namespace vff;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string part; std::getline(ss, part, ',');) out.push_back(part);
  return out;
}

openvdb::FloatGrid::Ptr exactSphere(float r, openvdb::Vec3d c, double h, bool rotated) {
  auto xf = openvdb::math::Transform::createLinearTransform(h);
  if (rotated) {
    xf->postRotate(0.5, openvdb::math::X_AXIS);
    xf->postRotate(0.3, openvdb::math::Z_AXIS);
    xf->postTranslate(openvdb::Vec3d(0.37 * h, -0.21 * h, 0.11 * h));
  }
  const double band = 3 * h;
  auto g = openvdb::FloatGrid::create(float(band));
  g->setTransform(xf);
  g->setGridClass(openvdb::GRID_LEVEL_SET);
  openvdb::Vec3d lo(1e30), hi(-1e30);
  for (int k = 0; k < 8; ++k) {
    const openvdb::Vec3d w(c.x() + (k & 1 ? 1 : -1) * (r + band + h), c.y() + (k & 2 ? 1 : -1) * (r + band + h),
                           c.z() + (k & 4 ? 1 : -1) * (r + band + h));
    const openvdb::Vec3d i = xf->worldToIndex(w);
    lo = openvdb::math::minComponent(lo, i);
    hi = openvdb::math::maxComponent(hi, i);
  }
  auto acc = g->getAccessor();
  for (int x = int(std::floor(lo.x())); x <= int(std::ceil(hi.x())); ++x)
    for (int y = int(std::floor(lo.y())); y <= int(std::ceil(hi.y())); ++y)
      for (int z = int(std::floor(lo.z())); z <= int(std::ceil(hi.z())); ++z) {
        const openvdb::Coord ijk(x, y, z);
        const double phi = (xf->indexToWorld(ijk) - c).length() - r;
        if (std::abs(phi) < band) acc.setValue(ijk, float(phi));
      }
  openvdb::tools::signedFloodFill(g->tree());
  return g;
}

int write(int argc, char** argv) {
  if (argc < 3) return 2;
  openvdb::initialize();
  openvdb::GridPtrVec grids;
  for (int a = 3; a < argc; ++a) {
    const std::vector<std::string> p = split(argv[a]);
    const std::string& kind = p.at(0);
    openvdb::GridBase::Ptr g;
    if ((kind == "sphere" || kind == "rotsphere") && p.size() == 7) {
      const float r = std::stof(p[2]);
      const openvdb::Vec3d c(std::stod(p[3]), std::stod(p[4]), std::stod(p[5]));
      const double h = std::stod(p[6]);
      if (kind == "sphere")
        g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(r, openvdb::Vec3f(c), float(h), 3.0f);
      else
        g = exactSphere(r, c, h, true);
    } else if ((kind == "mesh" || kind == "meshfile") && p.size() == 4) {
      bake::Mesh m;
      if (kind == "mesh") {
        m = bake::makeShape(p[2]);
      } else {
        auto loaded = bake::loadMesh(p[2]);
        if (!loaded) {
          std::fprintf(stderr, "vdb_check: %s\n", loaded.error().toString().c_str());
          return 2;
        }
        m = std::move(*loaded);
      }
      if (m.triangleCount() == 0) return 2;
      std::vector<openvdb::Vec3s> pts;
      std::vector<openvdb::Vec3I> tris;
      for (size_t v = 0; v < m.vertexCount(); ++v)
        pts.emplace_back(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
      for (size_t t = 0; t < m.triangleCount(); ++t)
        tris.emplace_back(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
      const auto xf = openvdb::math::Transform::createLinearTransform(std::stod(p[3]));
      g = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, pts, tris, 3.0f);
    } else if (kind == "fog" && p.size() == 2) {
      auto s = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.05f);
      openvdb::tools::sdfToFogVolume(*s);
      g = s;
    } else if (kind == "vector" && p.size() == 2) {
      auto v = openvdb::Vec3fGrid::create();
      v->getAccessor().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(1, 0, 0));
      g = v;
    } else if (kind == "float" && p.size() == 2) {
      auto f = openvdb::FloatGrid::create(0.0f);
      f->getAccessor().setValueOn(openvdb::Coord(1, 2, 3), 0.5f);
      g = f;
    } else if (kind == "emptyls" && p.size() == 2) {
      auto f = openvdb::FloatGrid::create(0.3f);
      f->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
      f->setGridClass(openvdb::GRID_LEVEL_SET);
      g = f;
    } else if (kind == "stretched" && p.size() == 2) {
      auto s = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.05f);
      s->transform().postScale(openvdb::Vec3d(1, 2, 1));
      g = s;
    } else {
      std::fprintf(stderr, "vdb_check: bad grid spec %s\n", argv[a]);
      return 2;
    }
    g->setName(p.at(1));
    grids.push_back(g);
  }
  openvdb::io::File(argv[2]).write(grids);
  return 0;
}

struct Ray {
  double o[3], d[3];
};

// The ray of texel (i, j) of map k, exactly as the bakers build it (float origin on the sphere,
// float direction from the map frame), in double.
Ray texelRay(const FieldDesc& f, const PositionSet& ps, uint32_t k, uint32_t i, uint32_t j) {
  const float R = f.sphere.radius;
  const Vec3 u = ps.position(k);
  const Vec3 origin{f.sphere.center[0] + R * u.x, f.sphere.center[1] + R * u.y, f.sphere.center[2] + R * u.z};
  const Vec3 d = toWorld(frameFromNormal({-u.x, -u.y, -u.z}), texelDirection(f.directionScheme, f.mapResolution, i, j));
  Ray r{{origin.x, origin.y, origin.z}, {d.x, d.y, d.z}};
  const double len = std::sqrt(r.d[0] * r.d[0] + r.d[1] * r.d[1] + r.d[2] * r.d[2]);
  for (double& v : r.d) v /= len;
  return r;
}

// Checks a bake of a sphere's level set against the sphere. With h the voxel size, the level set
// holds exact signed distances at the voxel centres; trilinear interpolation of the distance to
// the centre, phi = |x - c| - r, is off by at most eps = (h^2 / 8) (|phi_xx| + |phi_yy| + |phi_zz|)
// <= (h^2 / 8) * 3 / (r - sqrt(3) h) inside the band (each second derivative <= 1 / |x - c|), so the
// zero crossing lies between the spheres of radius r - eps and r + eps. Hence, for a ray at distance b
// from the centre:
//   b <= r - eps: a hit, first along the ray between t(r + eps) and t(r - eps), where
//                 t(rho) = tc - sqrt(rho^2 - b^2); stored within half a quantisation step q/2;
//   b >= r + eps: a miss;
//   between:      grazing, either (counted, not checked).
// A slack of 1e-5 R covers float rounding (origins, directions, stored distances) and the secant
// search's last step. Normals: the gradient of a trilinear interpolant is off from the exact
// gradient by at most (h / 2) * (sum of second derivatives) <= (h / 2) * sqrt(3) / (r - sqrt(3) h) in
// length (first order), i.e. in angle; plus 2e-4 rad for oct-snorm16 and the stored distance's
// rounding (the exact normal is taken at the decoded hit point).
int sphereError(int argc, char** argv) {
  if (argc != 8) return 2;
  auto file = File::open(argv[2]);
  if (!file) {
    std::fprintf(stderr, "vdb_check: %s\n", file.error().toString().c_str());
    return 2;
  }
  const double c[3] = {std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])};
  const double r = std::atof(argv[6]), h = std::atof(argv[7]);
  const FieldDesc& f = file->field();
  auto ps = PositionSet::fromField(f);
  if (!ps) return 2;
  const uint32_t m = f.mapResolution;
  const double eps = h * h / 8 * 3 / (r - std::sqrt(3.0) * h);
  const double slack = 1e-5 * f.sphere.radius;
  const double normalBound = h / 2 * std::sqrt(3.0) / (r - std::sqrt(3.0) * h) + 2e-4;
  uint64_t hits = 0, misses = 0, grazing = 0, bad = 0, normalsChecked = 0;
  double worstRatio = 0, worstDist = 0, worstNormal = 0, worstNormalRatio = 0;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    auto dmap = file->mapData(Plane::kDistance, k);
    if (!dmap) return 2;
    std::span<const uint8_t> nmap;
    if (file->hasNormals()) {
      auto n = file->mapData(Plane::kNormal, k);
      if (!n) return 2;
      nmap = *n;
    }
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const Ray ray = texelRay(f, *ps, k, i, j);
        const double cosAlpha = texelDirection(f.directionScheme, m, i, j).z;
        const Texel t = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, *dmap, m, i, j), f.sphere.radius,
                                       float(cosAlpha));
        double oc[3], tc = 0, oc2 = 0;
        for (int a = 0; a < 3; ++a) {
          oc[a] = ray.o[a] - c[a];
          tc -= oc[a] * ray.d[a];
          oc2 += oc[a] * oc[a];
        }
        const double b2 = std::max(0.0, oc2 - tc * tc), b = std::sqrt(b2);
        if (b > r - eps && b < r + eps) {
          ++grazing;
          continue;
        }
        const bool hitExpected = b <= r - eps;
        if (t.hit != hitExpected) {
          if (bad++ < 10)
            std::printf("map %u texel (%u, %u): %s, expected a %s (ray %.6f from the centre, sphere %.6f +- %.2g)\n", k, i,
                        j, t.hit ? "hit" : "miss", hitExpected ? "hit" : "miss", b, r, eps);
          continue;
        }
        if (!t.hit) {
          ++misses;
          continue;
        }
        ++hits;
        if (f.distanceEncoding == DistanceEncoding::kBit1) continue;
        const double q = quantizationStep(f.distanceEncoding, f.sphere.radius, float(cosAlpha));
        const double near = tc - std::sqrt(std::max(0.0, (r + eps) * (r + eps) - b2));
        const double far = tc - std::sqrt(std::max(0.0, (r - eps) * (r - eps) - b2));
        const double exact = tc - std::sqrt(r * r - b2);
        const double lo = near - q / 2 - slack, hi = far + q / 2 + slack;
        worstDist = std::max(worstDist, std::abs(t.distance - exact));
        // How much of its allowance a texel uses: |error| / (allowed distance on that side).
        const double allowance = t.distance < exact ? exact - lo : hi - exact;
        worstRatio = std::max(worstRatio, std::abs(t.distance - exact) / allowance);
        if (t.distance < lo || t.distance > hi) {
          if (bad++ < 10)
            std::printf("map %u texel (%u, %u): distance %.7f outside [%.7f, %.7f] (exact %.7f, q %.3g)\n", k, i, j,
                        t.distance, lo, hi, exact, q);
          continue;
        }
        if (!nmap.empty()) {
          const Vec3 n = decodeNormal(nmap.data() + 4 * (uint64_t{j} * m + i));
          double p[3], len = 0, dot = 0;
          for (int a = 0; a < 3; ++a) {
            p[a] = ray.o[a] + t.distance * ray.d[a] - c[a];
            len += p[a] * p[a];
          }
          len = std::sqrt(len);
          dot = (n.x * p[0] + n.y * p[1] + n.z * p[2]) / len;
          const double angle = std::acos(std::clamp(dot, -1.0, 1.0));
          ++normalsChecked;
          worstNormal = std::max(worstNormal, angle);
          worstNormalRatio = std::max(worstNormalRatio, angle / normalBound);
          if (angle > normalBound) {
            if (bad++ < 10)
              std::printf("map %u texel (%u, %u): normal %.6f rad from the sphere's (bound %.6f)\n", k, i, j, angle,
                          normalBound);
          }
        }
      }
  }
  std::printf("hits %llu, misses %llu, grazing (either) %llu, bad %llu\n", (unsigned long long)hits,
              (unsigned long long)misses, (unsigned long long)grazing, (unsigned long long)bad);
  std::printf("interpolation bound eps %.3g; largest |distance - exact| %.3g, largest share of a texel's allowance %.3f\n",
              eps, worstDist, worstRatio);
  if (normalsChecked)
    std::printf("normals: %llu checked, largest angle %.3g rad (bound %.3g, largest share %.3f)\n",
                (unsigned long long)normalsChecked, worstNormal, normalBound, worstNormalRatio);
  if (hits == 0 || misses == 0) {
    std::printf("expected both hits and misses\n");
    return 1;
  }
  return bad == 0 ? 0 : 1;
}

// The code of slice texel (x, y) in a slice of width w composed by File::readSlice.
uint32_t sliceCode(DistanceEncoding e, const std::vector<uint8_t>& s, uint32_t w, uint32_t x, uint32_t y) {
  switch (e) {
    case DistanceEncoding::kUnorm16Diameter: {
      const size_t at = 2 * (size_t(y) * w + x);
      return uint32_t(s[at] | s[at + 1] << 8);
    }
    case DistanceEncoding::kBit1: return (s[size_t(y) * (w / 8) + x / 8] >> (x & 7)) & 1u;
    default: return s[size_t(y) * w + x];
  }
}

#define CHECK(cond, ...)                 \
  do {                                   \
    if (!(cond)) {                       \
      std::printf("FAIL: " __VA_ARGS__); \
      std::printf("\n");                 \
      return 1;                          \
    }                                    \
  } while (0)

int verify(int argc, char** argv) {
  if (argc != 4) return 2;
  auto file = File::open(argv[2]);
  if (!file) return 2;
  const FieldDesc& f = file->field();
  const LayoutDesc& l = file->layout();
  openvdb::initialize();
  openvdb::io::File vdb(argv[3]);
  vdb.open();
  openvdb::GridPtrVecPtr grids = vdb.getGrids();
  vdb.close();
  const bool normals = file->hasNormals();
  CHECK(grids->size() == (normals ? 2u : 1u), "%zu grids", grids->size());
  auto dist = openvdb::gridPtrCast<openvdb::FloatGrid>(openvdb::findGridByName(*grids, "distance"));
  CHECK(dist, "no float grid \"distance\"");
  CHECK(std::isinf(dist->background()) && dist->background() > 0, "background %g is not +inf", dist->background());
  CHECK(dist->getGridClass() == openvdb::GRID_UNKNOWN, "distance grid class is not unknown");
  CHECK(dist->voxelSize() == openvdb::Vec3d(1.0), "voxel size is not 1");
  auto norm = openvdb::gridPtrCast<openvdb::Vec3fGrid>(openvdb::findGridByName(*grids, "normal"));
  CHECK(!normals || norm, "no vec3s grid \"normal\"");
  // Metadata: the field JSON and the provenance.
  const auto fieldMeta = dist->getMetadata<openvdb::StringMetadata>("vff.field");
  CHECK(fieldMeta, "no string metadata vff.field");
  const nlohmann::json j = nlohmann::json::parse(fieldMeta->value());
  CHECK(j.at("format") == "vff-convert-vdb/1", "vff.field format");
  CHECK(j.at("field").at("mapCount") == f.mapCount, "vff.field mapCount");
  CHECK(j.at("field").at("distanceEncoding") == distanceEncodingName(f.distanceEncoding), "vff.field encoding");
  CHECK(j.at("layout").at("sliceCount") == l.sliceCount && j.at("layout").at("sliceWidth") == l.sliceWidth,
        "vff.field layout");
  const std::string meta(file->metadata());
  CHECK(meta.empty() ? j.at("metadata").is_null() : j.at("metadata") == nlohmann::json::parse(meta),
        "vff.field metadata differs from the source's META");
  const auto prov = dist->getMetadata<openvdb::StringMetadata>("vff.provenance");
  CHECK(prov, "no string metadata vff.provenance");
  const nlohmann::json pj = nlohmann::json::parse(prov->value());
  CHECK(pj.is_array() && !pj.empty() && pj.back().at("tool") == "vff-convert" &&
            pj.back().at("operations") == nlohmann::json::array({"to-vdb"}),
        "vff.provenance: %s", prov->value().c_str());
  CHECK(dist->getMetadata<openvdb::StringMetadata>("vff.plane")->value() == "distance", "vff.plane");

  // Every voxel of every slice, against the slices libvff composes.
  std::vector<uint8_t> slice(file->sliceBytes(Plane::kDistance)), nslice;
  if (normals) nslice.resize(file->sliceBytes(Plane::kNormal));
  auto da = dist->getConstAccessor();
  uint64_t hits = 0;
  const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
  const uint32_t m = f.mapResolution, g = l.gutter, tile = l.tileSize;
  for (uint32_t s = 0; s < l.sliceCount; ++s) {
    CHECK(file->readSlice(Plane::kDistance, s, slice), "readSlice");
    if (normals) CHECK(file->readSlice(Plane::kNormal, s, nslice), "readSlice normals");
    for (uint32_t y = 0; y < l.sliceHeight; ++y)
      for (uint32_t x = 0; x < l.sliceWidth; ++x) {
        const uint32_t code = sliceCode(f.distanceEncoding, slice, l.sliceWidth, x, y);
        const bool hit = code != missCode(f.distanceEncoding);
        const openvdb::Coord c{int(x), int(y), int(s)};
        float v = 0;
        const bool active = da.probeValue(c, v);
        CHECK(active == hit, "slice %u texel (%u, %u): %s but voxel %s", s, x, y, hit ? "hit" : "miss",
              active ? "active" : "inactive");
        if (!hit) continue;
        ++hits;
        // The texel's map and position in it (gutter texels repeat the nearest edge texel).
        const uint32_t tileX = x / tile, tileY = y / tile;
        const uint32_t k = s * perSlice + tileY * l.tilesPerRow + tileX;
        CHECK(k < f.mapCount, "hit in an unused tile");
        const int64_t li = int64_t(x % tile) - g, lj = int64_t(y % tile) - g;
        const uint32_t i = uint32_t(std::clamp<int64_t>(li, 0, m - 1)), jj = uint32_t(std::clamp<int64_t>(lj, 0, m - 1));
        const float cosAlpha = texelDirection(f.directionScheme, m, i, jj).z;
        const Texel t = decodeDistance(f.distanceEncoding, code, f.sphere.radius, cosAlpha);
        CHECK(v == t.distance, "slice %u texel (%u, %u): voxel %.9g, texel decodes to %.9g", s, x, y, v, t.distance);
        if (normals) {
          const Vec3 n = decodeNormal(nslice.data() + 4 * (size_t(y) * l.sliceWidth + x));
          openvdb::Vec3f nv;
          CHECK(norm->getConstAccessor().probeValue(c, nv), "normal voxel inactive at a hit");
          CHECK(nv == openvdb::Vec3f(n.x, n.y, n.z), "slice %u texel (%u, %u): normal differs", s, x, y);
        }
      }
  }
  CHECK(dist->activeVoxelCount() == hits, "%llu active voxels, %llu hit texels",
        (unsigned long long)dist->activeVoxelCount(), (unsigned long long)hits);
  if (normals) CHECK(norm->activeVoxelCount() == hits, "normal grid: %llu active voxels", (unsigned long long)norm->activeVoxelCount());
  std::printf("%llu hit texels = active voxels\n", (unsigned long long)hits);
  return 0;
}

int countHits(int argc, char** argv) {
  if (argc != 3) return 2;
  auto file = File::open(argv[2]);
  if (!file) return 2;
  const FieldDesc& f = file->field();
  uint64_t hits = 0;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    auto d = file->mapData(Plane::kDistance, k);
    if (!d) return 2;
    for (uint32_t j = 0; j < f.mapResolution; ++j)
      for (uint32_t i = 0; i < f.mapResolution; ++i)
        hits += loadCode(f.distanceEncoding, *d, f.mapResolution, i, j) != missCode(f.distanceEncoding);
  }
  std::printf("%llu\n", (unsigned long long)hits);
  return 0;
}

int provenance(int argc, char** argv) {
  if (argc != 4) return 2;
  openvdb::initialize();
  openvdb::io::File vdb(argv[2]);
  vdb.open();
  const openvdb::GridPtrVecPtr grids = vdb.readAllGridMetadata();
  vdb.close();
  auto dist = openvdb::findGridByName(*grids, "distance");
  CHECK(dist, "no grid \"distance\"");
  const auto text = dist->getMetadata<openvdb::StringMetadata>("vff.provenance");
  CHECK(text, "no string metadata vff.provenance");
  std::printf("%s\n", text->value().c_str());
  const nlohmann::json p = nlohmann::json::parse(text->value());
  CHECK(p.is_array() && !p.empty(), "not a non-empty array");
  // The source's bytes and field.
  std::ifstream in(argv[3], std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)XXH3_64bits(bytes.data(), bytes.size()));
  auto file = File::open(argv[3]);
  CHECK(file, "the source is not a .vff");
  nlohmann::json before = nlohmann::json::array();
  if (!file->metadata().empty()) {
    const nlohmann::json meta = nlohmann::json::parse(file->metadata());
    if (meta.contains("vff.provenance")) before = meta.at("vff.provenance");
  }
  CHECK(p.size() == before.size() + 1, "%zu entries, the source has %zu", p.size(), before.size());
  for (size_t k = 0; k < before.size(); ++k) CHECK(p[k] == before[k], "entry %zu differs from the source's", k);
  const nlohmann::json& e = p.back();
  std::string name = argv[3];
  if (const size_t slash = name.find_last_of('/'); slash != std::string::npos) name = name.substr(slash + 1);
  CHECK(e.at("tool") == "vff-convert" && e.at("version") == kLibraryVersion, "tool/version");
  CHECK(e.at("operations") == nlohmann::json::array({"to-vdb"}), "operations");
  const nlohmann::json& src = e.at("source");
  CHECK(src.at("name") == name && src.at("format") == "vff", "source name/format");
  CHECK(src.at("xxh3") == hex, "source xxh3 %s, the file's is %s", src.at("xxh3").dump().c_str(), hex);
  CHECK(src.at("mapCount") == file->field().mapCount &&
            src.at("distanceEncoding") == distanceEncodingName(file->field().distanceEncoding),
        "source field");
  return 0;
}

int edit(int argc, char** argv) {
  if (argc != 5) return 2;
  openvdb::initialize();
  openvdb::io::File in(argv[2]);
  in.open();
  openvdb::GridPtrVecPtr grids = in.getGrids();
  in.close();
  auto dist = openvdb::gridPtrCast<openvdb::FloatGrid>(openvdb::findGridByName(*grids, "distance"));
  if (!dist) return 2;
  const std::string mode = argv[4];
  if (mode == "voxel-outside")
    dist->getAccessor().setValueOn(openvdb::Coord(-1, 0, 0), 0.5f);
  else if (mode == "field-json")
    dist->insertMeta("vff.field", openvdb::StringMetadata("{}"));
  else if (mode == "scale-values")
    for (auto it = dist->beginValueOn(); it; ++it) it.setValue(*it * 1.0001f);
  else
    return 2;
  openvdb::io::File(argv[3]).write(*grids);
  return 0;
}

// A mesh bake against a bake of the mesh's level set (meshToLevelSet, voxel h). meshToLevelSet
// stores the exact distance to the triangles at the voxel centres, so on smooth parts the zero
// crossing of the interpolant is within (h^2 / 8) * 3 * curvature of the triangles (2.5e-4 for h =
// 0.01 on the torus knot's tube of radius 0.15): rays that hit both agree to that over the cosine of
// incidence, plus one quantisation step q. Creases, silhouettes and where the tube nearly touches
// itself differ more. Checked as statistics over the texels: hit/miss agreement >= 99%, among
// texels hit by both >= 99% within h + q, and the median difference <= h / 10 + q / 2.
int compareMesh(int argc, char** argv) {
  if (argc != 5) return 2;
  auto a = File::open(argv[2]);
  auto b = File::open(argv[3]);
  if (!a || !b) return 2;
  const double h = std::atof(argv[4]);
  const FieldDesc& f = a->field();
  CHECK(f.mapCount == b->field().mapCount && f.mapResolution == b->field().mapResolution &&
            f.distanceEncoding == b->field().distanceEncoding &&
            std::memcmp(&f.sphere, &b->field().sphere, sizeof f.sphere) == 0,
        "the two fields differ in layout or sphere");
  const uint32_t m = f.mapResolution;
  uint64_t same = 0, total = 0, both = 0, within = 0;
  std::vector<double> diffs;
  double q = 0;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    auto da = a->mapData(Plane::kDistance, k);
    auto db = b->mapData(Plane::kDistance, k);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const float cosAlpha = texelDirection(f.directionScheme, m, i, j).z;
        q = std::max(q, double(quantizationStep(f.distanceEncoding, f.sphere.radius, cosAlpha)));
        const Texel ta = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, *da, m, i, j), f.sphere.radius, cosAlpha);
        const Texel tb = decodeDistance(f.distanceEncoding, loadCode(f.distanceEncoding, *db, m, i, j), f.sphere.radius, cosAlpha);
        ++total;
        same += ta.hit == tb.hit;
        if (ta.hit && tb.hit) {
          ++both;
          const double d = std::abs(double(ta.distance) - tb.distance);
          diffs.push_back(d);
          within += d <= h + q;
        }
      }
  }
  std::sort(diffs.begin(), diffs.end());
  const double median = diffs.empty() ? 0 : diffs[diffs.size() / 2];
  const double agree = double(same) / double(total), share = both ? double(within) / double(both) : 0;
  std::printf("hit/miss agreement %.4f (>= 0.99); hit by both %llu; within h + q = %.4g: %.4f (>= 0.99); "
              "median difference %.4g (<= h/10 + q/2 = %.4g)\n",
              agree, (unsigned long long)both, h + q, share, median, h / 10 + q / 2);
  CHECK(agree >= 0.99 && share >= 0.99 && median <= h / 10 + q / 2 && both > 0, "outside the thresholds");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const std::string cmd = argv[1];
  try {
    if (cmd == "write") return write(argc, argv);
    if (cmd == "sphere-error") return sphereError(argc, argv);
    if (cmd == "verify") return verify(argc, argv);
    if (cmd == "compare-mesh") return compareMesh(argc, argv);
    if (cmd == "count-hits") return countHits(argc, argv);
    if (cmd == "provenance") return provenance(argc, argv);
    if (cmd == "edit") return edit(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vdb_check: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr, "vdb_check: unknown command %s\n", cmd.c_str());
  return 2;
}
