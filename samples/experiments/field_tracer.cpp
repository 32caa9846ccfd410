// field_tracer.cpp - the approximation: visibility fields baked in memory with vff::bake and
// queried with vff::FieldQuery, placed in the world with vff::Instance.
#include <chrono>
#include <cstdio>

#include "common.h"

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
  q->baked = std::move(*baked);
  q->bakeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto query = vff::FieldQuery::fromMaps(q->baked.field, q->baked.distance, q->baked.normals);
  if (!query) return std::move(query).error();
  q->query = std::move(*query);
  q->instance.field = &q->query;
  q->instance.transform = world.transform;
  return q;
}

}  // namespace vffx
