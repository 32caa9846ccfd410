// scene_bench.h - what scene-bench's two tables share (scene_bench.cpp: moving instances, time
// per frame; scene_forms.cpp: the forms in which a renderer casts its rays).
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <random>
#include <vector>

#include "common.h"
#include "surface_sampler.h"
#include "vff/embree.h"
#include "vff/scene.h"

namespace vffx {

struct Side {
  double commit = 0, rays = 0;  // seconds, summed over frames
};

// What every count's frames share: the options, the field and its sphere, the query options and the
// surface the rays start on.
struct Bench {
  const Options& o;
  unsigned threads;
  const vff::FieldQuery& q;
  const vff::Sphere& s;  // the field's sphere
  float R;
  // The field's default intra bias: the rays start on the objects' surfaces.
  vff::QueryOptions qo;
  const SurfaceSampler& surface;
};

// One instance count's scenes and sums. Every count's scenes exist at once: the counts take turns
// frame by frame (runSceneBench). A count owns its Embree objects, and releases them on every way
// out.
struct Count {
  uint32_t n = 0;
  std::mt19937_64 g;
  float side = 0;
  RTCScene exact = nullptr, hybrid = nullptr;
  std::vector<RTCGeometry> inst;
  std::vector<vff::embree::FieldGeometry> fields;
  vff::Scene scene;
  Side a, b, c;
  double answers = 0;  // (b)'s floor, summed over frames
  uint64_t agreeAB = 0, agreeBC = 0, agreeBD = 0, total = 0, pairs = 0;
  ~Count() {
    fields.clear();  // (each detaches from `hybrid`, which must still exist)
    for (RTCGeometry gi : inst) rtcReleaseGeometry(gi);
    if (hybrid) rtcReleaseScene(hybrid);
    if (exact) rtcReleaseScene(exact);
  }
};

// n instances at random in a cube whose volume grows with n: (a) instances of `mesh`, (b) the
// field's vff::Scene, (c) the field's Embree geometries.
std::unique_ptr<Count> makeCount(const Bench& b, uint32_t n, RTCDevice device, RTCScene mesh);

// A random placement in the cube [0, side]^3.
vff::RigidTransform randomPlacement(std::mt19937_64& g, float side);
// The field's object space has its sphere's centre at s.center: the same shift.
vff::RigidTransform fieldPlacement(const vff::RigidTransform& x, const vff::Sphere& s);

// The second table (scene_forms.cpp): for the counts up to 1000, random and tile-coherent AO rays
// cast by Embree's triangles and the hybrid as single rays, packets of 16 and streams, and the
// two-pass hybrid against vff::Scene. Returns an exit code.
int runRayForms(const Bench& b, const std::vector<std::unique_ptr<Count>>& counts, RTCDevice device, RTCScene mesh);

}  // namespace vffx
