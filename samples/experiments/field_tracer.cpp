// field_tracer.cpp - the approximation: visibility fields baked in memory with vff::bake and
// queried with vff::FieldQuery, placed in the world with vff::Instance.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "common.h"
#include "vff/reader.h"
#include "vff/refine.h"

namespace vffx {

std::string FieldConfig::name() const {
  const uint32_t maps = 2 * (2 * n * n + 2 * n + 1);
  return std::to_string(maps) + "x" + std::to_string(mapSize) + "x" + std::to_string(mapSize);
}

bool parseFieldConfig(const std::string& text, FieldConfig* out) {
  unsigned maps = 0, m1 = 0, m2 = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%ux%ux%u%c", &maps, &m1, &m2, &tail) != 3 || m1 != m2 || m1 == 0 || m1 > 4096)
    return false;
  for (uint32_t n = 1; n <= 1024; ++n) {
    if (2 * (2 * n * n + 2 * n + 1) == maps) {
      out->n = n;
      out->mapSize = m1;
      return true;
    }
  }
  return false;
}

std::optional<int> singleConfig(const Options& o, const std::string& fallback, FieldConfig* out) {
  const std::string text = o.configs.empty() ? fallback : o.configs.front();
  if (parseFieldConfig(text, out)) return std::nullopt;
  vff::cli::usageError(kProg, "--config " + text + ": expected MAPSxMxM with an octa-hemi2 map count");
  return vff::cli::kExitUsage;
}

vff::Result<std::unique_ptr<BakedQuery>> bakeQuery(const World& world, const vff::bake::Scene& scene,
                                                   const FieldConfig& config, bool normals, unsigned threads) {
  vff::bake::BakeOptions bo;
  bo.positionScheme = vff::PositionScheme::kOctaHemi2;
  bo.positionParam = config.n;
  bo.mapResolution = config.mapSize;
  bo.encoding = vff::DistanceEncoding::kUnorm8Diameter;
  bo.normals = normals;
  bo.threads = threads;
  bo.sphere = world.objectSphere;
  const auto t0 = std::chrono::steady_clock::now();
  auto baked = vff::bake::bakeField(scene, bo);
  if (!baked) return std::move(baked).error();
  auto q = std::make_unique<BakedQuery>();
  q->config = config;
  q->name = q->description = config.name();
  q->baked = std::move(*baked);
  q->bakeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto query = vff::FieldQuery::fromMaps(q->baked.field, q->baked.distance, q->baked.normals);
  if (!query) return std::move(query).error();
  q->query = std::move(*query);
  q->instance.field = &q->query;
  q->instance.transform = world.transform;
  return q;
}

vff::Status refineQuery(const World& world, BakedQuery* q, const vff::RefineOptions& options) {
  auto r = vff::makeRefinement(q->baked.field, q->baked.distance, world.objectMesh.positions, world.objectMesh.indices,
                               options);
  if (!r) return std::move(r).error();
  q->refinement = std::move(*r);
  auto query = vff::FieldQuery::fromMaps(q->baked.field, q->baked.distance, q->baked.normals, q->refinement.view());
  if (!query) return std::move(query).error();
  q->query = std::move(*query);
  q->instance.field = &q->query;
  return {};
}

vff::Result<std::unique_ptr<BakedQuery>> loadQuery(const World& world, const std::string& path, bool normals) {
  auto file = vff::File::open(path);
  if (!file) return std::move(file).error();
  const vff::FieldDesc& fd = file->field();
  // The same object: the sphere the bakes use, and the mesh the file was baked from when it says.
  const vff::Sphere& s = world.objectSphere;
  const float tol = 1e-5f * s.radius;
  if (std::fabs(fd.sphere.center[0] - s.center[0]) > tol || std::fabs(fd.sphere.center[1] - s.center[1]) > tol ||
      std::fabs(fd.sphere.center[2] - s.center[2]) > tol || std::fabs(fd.sphere.radius - s.radius) > tol) {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "the field's bounding sphere (centre %.7g %.7g %.7g, radius %.7g) is not the mesh's minimal "
                  "enclosing sphere (centre %.7g %.7g %.7g, radius %.7g): not a field of this mesh, or baked with "
                  "another sphere",
                  double(fd.sphere.center[0]), double(fd.sphere.center[1]), double(fd.sphere.center[2]),
                  double(fd.sphere.radius), double(s.center[0]), double(s.center[1]), double(s.center[2]),
                  double(s.radius));
    return vff::makeError(vff::Code::kInvalidArgument, buf);
  }
  if (!file->metadata().empty()) {
    // The geometry hash matches the same triangles read from any file format; files from before it
    // existed carry only the hash of the mesh as baked (vertex order included).
    const auto meta = nlohmann::json::parse(file->metadata(), nullptr, false);
    const nlohmann::json* source = meta.is_object() && meta.contains("vff.source") && meta["vff.source"].is_object()
                                       ? &meta["vff.source"]
                                       : nullptr;
    for (const char* key : {"geometryHash", "xxh3"}) {
      if (!source || !source->contains(key) || !(*source)[key].is_string()) continue;
      const uint64_t h = std::string(key) == "xxh3" ? vff::bake::meshHash(world.objectMesh)
                                                    : vff::bake::geometryHash(world.objectMesh);
      const std::string want = vff::cli::hexDigits64(h);
      const std::string got = (*source)[key].get<std::string>();
      if (got != want)
        return vff::makeError(vff::Code::kInvalidArgument, "the field was baked from other geometry: META vff.source." +
                                                               std::string(key) + " is " + got +
                                                               ", the loaded mesh's is " + want);
      break;
    }
  }
  if (normals && !file->hasNormals())
    return vff::makeError(vff::Code::kUnsupported, "this experiment needs a normal plane, and the field has none");

  auto q = std::make_unique<BakedQuery>();
  q->baked.field = fd;
  for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal}) {
    if (!file->plane(p).present) continue;
    std::vector<uint8_t>& out = p == vff::Plane::kDistance ? q->baked.distance : q->baked.normals;
    out.reserve(file->plane(p).rawBytes);
    for (uint32_t b = 0; b < file->plane(p).blocks.size(); ++b) {
      auto bytes = file->blockData(p, b);
      if (!bytes) return std::move(bytes).error();
      out.insert(out.end(), bytes->begin(), bytes->end());
    }
  }
  q->config.n = fd.positionScheme == vff::PositionScheme::kOctaHemi2 ? fd.positionParam : 0;
  q->config.mapSize = fd.mapResolution;
  const size_t slash = path.find_last_of('/');
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  q->name = base.size() > 4 && base.ends_with(".vff") ? base.substr(0, base.size() - 4) : base;
  q->description = base + " (" + std::to_string(fd.mapCount) + "x" + std::to_string(fd.mapResolution) + "x" +
                   std::to_string(fd.mapResolution) + " " + vff::distanceEncodingName(fd.distanceEncoding) + ")";
  auto query = vff::FieldQuery::fromMaps(q->baked.field, q->baked.distance, q->baked.normals);
  if (!query) return std::move(query).error();
  q->query = std::move(*query);
  q->instance.field = &q->query;
  q->instance.transform = world.transform;
  return q;
}

}  // namespace vffx
