// vff/bake/baker.h - baking a visibility field from a triangle mesh with Embree 3.
//
// From every positional sample on the bounding sphere, one ray per map texel is cast over the inward
// hemisphere (through the texel centre, in the sample's tangent frame); the first-hit distance is
// quantised into the chosen encoding, misses get the miss code, and with normals enabled the shading
// normal at the hit (interpolated vertex normals when the mesh has them, else the geometric normal)
// goes into the normal field. Hits are two-sided. The output does not depend on the thread count.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "vff/bake/mesh.h"
#include "vff/format.h"

namespace vff::bake {

struct BakeOptions {
  PositionScheme positionScheme = PositionScheme::kOctaHemi2;
  uint32_t positionParam = 32;  // octa-hemi2 n = 32: the paper's 4226 maps
  DirectionScheme directionScheme = DirectionScheme::kConcentricEqualArea;
  uint32_t mapResolution = 64;
  DistanceEncoding encoding = DistanceEncoding::kUnorm8Diameter;
  bool normals = false;
  unsigned threads = 0;          // 0: all hardware threads
  std::optional<Sphere> sphere;  // default: the minimal enclosing sphere of the mesh's vertices
  // Called from the baking threads with (maps done, maps total); keep it cheap and thread-safe.
  std::function<void(uint64_t, uint64_t)> progress;
  // When set, read by the baking threads before each map: once it holds true they take no more
  // maps and bakeField fails with kBadState ("cancelled"). For callers that stop a bake from
  // another thread (a Ctrl-C in the Python module).
  const std::atomic<bool>* cancel = nullptr;
  // Bake only maps [mapBegin, mapEnd) of the field (indices in its sample order); mapEnd 0 means
  // the last map. A map's bytes do not depend on the range it is baked in, so ranges baked apart
  // and put side by side are the whole bake's maps. A range outside the field is kInvalidArgument.
  uint32_t mapBegin = 0;
  uint32_t mapEnd = 0;
};

struct BakeStats {
  uint64_t rays = 0;
  uint64_t hits = 0;
  double seconds = 0;  // tracing and encoding, without the scene build
};

struct BakedField {
  FieldDesc field;
  // The baked maps, map-major: mapCount maps, or mapEnd - mapBegin of a range bake (field still
  // describes the whole field).
  std::vector<uint8_t> distance;
  std::vector<uint8_t> normals;  // empty unless options.normals
  BakeStats stats;
};

// An Embree scene of one mesh, reusable across bakes and traces.
class Scene {
 public:
  // threads: Embree's build threads (0: all).
  static Result<Scene> create(const Mesh& mesh, unsigned threads = 0);
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  ~Scene();

  const Mesh& mesh() const noexcept;
  // Peak bytes Embree allocated for the scene (its BVH and buffers).
  uint64_t embreeBytes() const noexcept;
  struct Impl;  // opaque
  explicit Scene(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
  friend Result<BakedField> bakeField(const Scene&, const BakeOptions&);
  friend Result<BakeStats> traceOnly(const Scene&, const BakeOptions&);
};

// The field description a bake with these options produces (sphere, counts, encodings).
Result<FieldDesc> describeBake(const Mesh& mesh, const BakeOptions& options);

// Bakes the field. Errors: invalid options (kInvalidArgument, kPositionScheme, kMapResolution...).
Result<BakedField> bakeField(const Scene& scene, const BakeOptions& options);

// Casts exactly the rays bakeField casts, in the same packets and threads, and keeps nothing: the
// baseline for the bake benchmark.
Result<BakeStats> traceOnly(const Scene& scene, const BakeOptions& options);

}  // namespace vff::bake
