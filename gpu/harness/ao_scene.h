// ao_scene.h - the ground-plane ambient occlusion of the paper's Fig. 3, reduced to what a GPU and
// a CPU can compute from the same inputs: shared by vff-gpu-bench and tests/gpu.
//
// The scene: the field's object above a ground plane y = groundY (object space; the object stands
// on it), seen from straight above: pixel (x, y) of a size x size image is the plane point
// (cx - 2R + (x + 0.5) s, groundY, cz - 2R + (y + 0.5) s), s = 4R / size, normal (0, 1, 0). This is
// the G-buffer (point, normal per pixel) that samples/experiments computes with a camera and an
// exact primary ray; here it is analytic so that no ray tracer is needed.
//
// The rays: every pixel casts `rays` cosine-weighted directions from origin = point + normal * eps
// (eps = 1e-4 R) with tmin 0, tmax 2R and intra bias 0 (a plane point has no surface of its own),
// as ao.cpp. Ray i of pixel p uses entry (offset(p) + i) mod T of a table of T unit local directions
// (z up, cosine-weighted, drawn once on the CPU), turned into the pixel's frame with
// vff::frameFromNormal (GLSL vffFrame): world = t l.x + b l.y + n l.z, each operation rounded.
// GPU and CPU therefore answer bit-identical rays, and the AO images differ only by the queries.
//
// AO = the unoccluded share: the mean over the rays of 1 - occluded (kNearest) or of visibility
// (kInterpolated).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "platform/parallel.h"
#include "vff/direction.h"
#include "vff/query.h"

namespace vff::harness {

inline constexpr uint32_t kAoTableSize = 8192;

struct AoScene {
  int size = 0;
  float eps = 0, tmax = 0;
  std::vector<float> gbuffer;     // per pixel: point xyz, 0, normal xyz, 0
  std::vector<float> directions;  // kAoTableSize local unit directions: xyz, 0
};

// The per-pixel start in the direction table (an integer hash, identical in GLSL).
inline uint32_t aoPixelOffset(uint32_t pixel) {
  uint32_t h = pixel * 747796405u + 2891336453u;
  h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
  return ((h >> 22u) ^ h) % kAoTableSize;
}

inline AoScene makeAoScene(const FieldDesc& field, float groundY, int size, float aoDistance = 2.0f) {
  AoScene s;
  s.size = size;
  const float R = field.sphere.radius;
  s.eps = 1e-4f * R;
  s.tmax = aoDistance * R;
  const float step = 4.0f * R / float(size);
  const float x0 = field.sphere.center[0] - 2.0f * R, z0 = field.sphere.center[2] - 2.0f * R;
  s.gbuffer.assign(size_t(size) * size * 8, 0.0f);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      float* g = &s.gbuffer[(size_t(y) * size + x) * 8];
      g[0] = x0 + (float(x) + 0.5f) * step;
      g[1] = groundY;
      g[2] = z0 + (float(y) + 0.5f) * step;
      g[5] = 1.0f;  // normal (0, 1, 0)
    }
  std::mt19937 rng(20240601u);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  s.directions.resize(size_t(kAoTableSize) * 4);
  for (uint32_t i = 0; i < kAoTableSize; ++i) {
    const float u1 = u(rng), u2 = u(rng);
    const float r = std::sqrt(u1), phi = 6.28318531f * u2;
    s.directions[4 * i] = r * std::cos(phi);
    s.directions[4 * i + 1] = r * std::sin(phi);
    s.directions[4 * i + 2] = std::sqrt(std::max(0.0f, 1.0f - u1));
  }
  return s;
}

// Ray i of pixel p (the CPU side of the GLSL below).
inline Ray aoRay(const AoScene& s, uint32_t p, int i) {
  const float* g = &s.gbuffer[size_t(p) * 8];
  const Vec3 n{g[4], g[5], g[6]};
  const Frame f = frameFromNormal(n);
  const float* l = &s.directions[size_t((aoPixelOffset(p) + uint32_t(i)) % kAoTableSize) * 4];
  const Vec3 d{f.t.x * l[0] + f.b.x * l[1] + f.n.x * l[2], f.t.y * l[0] + f.b.y * l[1] + f.n.y * l[2],
               f.t.z * l[0] + f.b.z * l[1] + f.n.z * l[2]};
  const Vec3 o{g[0] + n.x * s.eps, g[1] + n.y * s.eps, g[2] + n.z * s.eps};
  return Ray{o, d, 0.0f, s.tmax};
}

// The CPU image: AO per pixel with the batch visibility call of `q` (a FieldQuery, or a
// vff::Scene: one call per pixel), on `threads` threads (0: every core), one row per chunk; each
// pixel's AO at its index, so the image does not depend on the thread count.
template <class Query>
std::vector<float> cpuAo(const Query& q, const AoScene& s, int rays, Reconstruction r, unsigned threads = 1) {
  std::vector<float> out(size_t(s.size) * s.size);
  // Ground points are on no object: section 7.4 (spec/geometry.md), as the GLSL below.
  const QueryOptions qo{.reconstruction = r, .origin = RayOrigin::kOffObject};
  struct Buffers {
    std::vector<Ray> batch;
    std::vector<float> vis;  // kNearest: 0 or 1, as !occluded()
  };
  const size_t rows = size_t(std::max(s.size, 0));
  std::vector<Buffers> buffers(parallel::workerCount(rows, 1, threads));
  parallel::parallelForWorkers(rows, 1, threads, [&](unsigned w, size_t y0, size_t y1) {
    Buffers& b = buffers[w];
    b.batch.resize(size_t(std::max(rays, 0)));  // (on the worker's thread, its first row)
    b.vis.resize(b.batch.size());
    for (int y = int(y0); y < int(y1); ++y)
      for (int x = 0; x < s.size; ++x) {
        const uint32_t p = uint32_t(y * s.size + x);
        for (int i = 0; i < rays; ++i) b.batch[size_t(i)] = aoRay(s, p, i);
        (void)q.visibility(std::span<const Ray>(b.batch), std::span<float>(b.vis), qo);
        float open = 0;
        for (float v : b.vis) open += v;
        out[p] = open / float(rays);
      }
  });
  return out;
}

// The compute shader after `#version 430` and vff_query.glsl: one invocation per pixel, 8 x 8
// groups. Uniforms: location 0 size, 1 rays, 2 interpolated (0/1), 3 eps, 4 tmax, 5 first row.
// AO_VISIBILITY and AO_OCCLUDED are the queries it makes; a scene (vff_scene.glsl) defines them
// as vffSceneVisibility and vffSceneOccluded before this text.
inline constexpr const char* kAoShader = R"(
#ifndef AO_VISIBILITY
#define AO_VISIBILITY(o, d) vffVisibility(o, d, 0.0, aoTmax, VFF_OFF_OBJECT)
#define AO_OCCLUDED(o, d) vffOccluded(o, d, 0.0, aoTmax, VFF_OFF_OBJECT)
#endif
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 5) readonly buffer AoGBuffer { vec4 aoGBuffer[]; };
layout(std430, binding = 6) readonly buffer AoDirections { vec4 aoDirections[]; };
layout(std430, binding = 7) writeonly buffer AoImage { float aoImage[]; };
layout(location = 0) uniform int aoSize;
layout(location = 1) uniform int aoRays;
layout(location = 2) uniform int aoInterpolated;
layout(location = 3) uniform float aoEps;
layout(location = 4) uniform float aoTmax;
layout(location = 5) uniform int aoFirstRow;
uint aoPixelOffset(uint pixel) {
  uint h = pixel * 747796405u + 2891336453u;
  h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
  return ((h >> 22u) ^ h) % 8192u;
}
void main() {
  ivec2 xy = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, aoFirstRow);
  if (xy.x >= aoSize || xy.y >= aoSize) return;
  uint p = uint(xy.y * aoSize + xy.x);
  vec3 point = aoGBuffer[2u * p].xyz;
  vec3 n = aoGBuffer[2u * p + 1u].xyz;
  mat3 F = vffFrame(n);
  precise vec3 o = point + n * aoEps;
  uint base = aoPixelOffset(p);
  precise float open = 0.0;
  for (int i = 0; i < aoRays; ++i) {
    vec3 l = aoDirections[(base + uint(i)) % 8192u].xyz;
    precise vec3 d = vec3(F[0].x * l.x + F[1].x * l.y + F[2].x * l.z, F[0].y * l.x + F[1].y * l.y + F[2].y * l.z,
                          F[0].z * l.x + F[1].z * l.y + F[2].z * l.z);
    if (aoInterpolated != 0) open += AO_VISIBILITY(o, d);
    else open += AO_OCCLUDED(o, d) ? 0.0 : 1.0;
  }
  aoImage[p] = open / float(aoRays);
}
)";

// |a - b| on the 8-bit scale (round(255 clamp(v)), as samples/experiments' PNGs), and the mean
// and least AO of a (the reference image: whether the objects occlude the ground at all).
struct AoDiff {
  double max = 0, rms = 0;
  uint64_t differing = 0;
  double meanA = 0, minA = 1;
};
inline AoDiff compareAo(const std::vector<float>& a, const std::vector<float>& b) {
  AoDiff d;
  double sum = 0;
  auto q = [](float v) { return std::round(255.0 * std::clamp(double(v), 0.0, 1.0)); };
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    const double e = std::fabs(q(a[i]) - q(b[i]));
    d.max = std::max(d.max, e);
    sum += e * e;
    d.differing += e > 0;
  }
  for (float v : a) d.meanA += v, d.minA = std::min(d.minA, double(v));
  d.rms = a.empty() ? 0.0 : std::sqrt(sum / double(a.size()));
  d.meanA = a.empty() ? 0.0 : d.meanA / double(a.size());
  return d;
}

}  // namespace vff::harness
