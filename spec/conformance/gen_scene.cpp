// gen_scene.cpp - the conformance vectors' source data (gen_scene.h).
#include "gen_scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <span>
#include <string>
#include <utility>

namespace vff::gen {

namespace {

// ---- Source data: an analytic scene ---------------------------------------------------------------
// The maps hold the distance from the bounding sphere to an off-centre sphere of radius 0.7R, along
// each texel-centre ray, and its normal at the hit. The positional samples are the generator's own
// stand-ins (an octahedral low-discrepancy set; spec/geometry.md's schemes are not used for content),
// so the values are exact for these positions, not for the FDSC's scheme. Directions and frames are
// computed here in double precision, independently of libvff, and checked against it.
struct D3 {
  double x = 0, y = 0, z = 0;
};
D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
D3 operator*(D3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
D3 normalize(D3 a) {
  return a * (1.0 / std::sqrt(dot(a, a)));
}

D3 standInPosition(uint32_t k, uint32_t count) {
  const double u = 2.0 * ((k + 0.5) / count) - 1.0;
  const double v = 2.0 * std::fmod(k * 0.6180339887498949 + 0.25, 1.0) - 1.0;
  D3 p{u, v, 1.0 - std::fabs(u) - std::fabs(v)};
  if (p.z < 0) {
    p.x = (1.0 - std::fabs(v)) * (u >= 0 ? 1.0 : -1.0);
    p.y = (1.0 - std::fabs(u)) * (v >= 0 ? 1.0 : -1.0);
  }
  return normalize(p);
}

struct Frame3 {
  D3 t, b, n;
};
Frame3 duffFrame(D3 n) {
  const double s = n.z >= 0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n.z);
  const double k = n.x * n.y * a;
  return {{1.0 + s * n.x * n.x * a, s * k, -s * n.x}, {k, s + n.y * n.y * a, -n.y}, n};
}

D3 localDirection(DirectionScheme scheme, uint32_t m, uint32_t i, uint32_t j) {
  const double a = (2.0 * i + 1.0) / m - 1.0, b = (2.0 * j + 1.0) / m - 1.0;
  if (scheme == DirectionScheme::kHemiOctahedral) {
    const double x = (a + b) * 0.5, y = (a - b) * 0.5;
    return normalize({x, y, 1.0 - std::fabs(x) - std::fabs(y)});
  }
  constexpr double kQuarterPi = 0.78539816339744830962;
  double r = 0, phi = 0;
  if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0 * kQuarterPi - kQuarterPi * (a / b);
  }
  const double s = r * std::sqrt(2.0 - r * r);
  return {s * std::cos(phi), s * std::sin(phi), 1.0 - r * r};
}

}  // namespace

Content makeContent(const FieldDesc& f) {
  Content c;
  const uint32_t m = f.mapResolution;
  const uint64_t mapBytes = distanceMapBytes(f.distanceEncoding, m);
  const bool withNormals = f.normalEncoding != NormalEncoding::kNone;
  c.distance.assign(mapBytes * f.mapCount, 0);
  if (withNormals) c.normals.assign(normalMapBytes(f.normalEncoding, m) * f.mapCount, 0);
  const double r = f.sphere.radius;
  const D3 centre{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const D3 inner = centre + D3{0.10, -0.08, 0.12} * r;
  const double innerRadius = 0.7 * r;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    const D3 p = standInPosition(k, f.mapCount);
    const D3 n = p * -1.0;
    const Frame3 fr = duffFrame(n);
    const Frame lib = frameFromNormal({float(n.x), float(n.y), float(n.z)});
    const double frameErr = std::fabs(lib.t.x - fr.t.x) + std::fabs(lib.t.y - fr.t.y) + std::fabs(lib.t.z - fr.t.z) +
                            std::fabs(lib.b.x - fr.b.x) + std::fabs(lib.b.y - fr.b.y) + std::fabs(lib.b.z - fr.b.z);
    if (frameErr > 1e-5) fail("libvff's frameFromNormal disagrees with the Duff et al. 2017 basis");
    const D3 origin = centre + p * r;
    auto map = std::span<uint8_t>(c.distance).subspan(k * mapBytes, mapBytes);
    const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
    if (bc4 && k == 0) c.codes.assign(uint64_t(m) * m * f.mapCount, 255);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const D3 l = localDirection(f.directionScheme, m, i, j);
        const Vec3 ll = texelDirection(f.directionScheme, m, i, j);
        if (std::fabs(ll.x - l.x) + std::fabs(ll.y - l.y) + std::fabs(ll.z - l.z) > 1e-5)
          fail(std::string("libvff's texelDirection disagrees for ") + directionSchemeName(f.directionScheme));
        const D3 w = fr.t * l.x + fr.b * l.y + fr.n * l.z;
        const D3 oc = origin - inner;
        const double bq = dot(oc, w), cq = dot(oc, oc) - innerRadius * innerRadius;
        const double disc = bq * bq - cq;
        const bool hit = disc >= 0;
        const double t = hit ? -bq - std::sqrt(disc) : 0.0;
        const uint32_t code = encodeDistance(f.distanceEncoding, hit, float(t), f.sphere.radius, ll.z);
        if (bc4)
          c.codes[(uint64_t(k) * m + j) * m + i] = uint8_t(code);
        else
          storeCode(f.distanceEncoding, map, m, i, j, code);
        (hit ? c.hits : c.misses)++;
        if (hit && withNormals) {
          const D3 nn = normalize(origin + w * t - inner);
          encodeNormal({float(nn.x), float(nn.y), float(nn.z)},
                       &c.normals[(uint64_t(k) * m * m + uint64_t(j) * m + i) * 4]);
        }
      }
    // bc4-diameter: the blocks come from libvff's encoder; the checks decode them with the reference
    // decoder below, written from spec/format.md 7.4.
    if (bc4) encodeBc4Map(std::span<const uint8_t>(c.codes).subspan(uint64_t(k) * m * m, uint64_t(m) * m), m, map);
  }
  return c;
}

Refinement makeRefinementSource(const FieldDesc& f, const Content& c, float margin, uint32_t level) {
  Refinement r;
  r.margin = margin;
  const uint32_t m = f.mapResolution;
  const uint64_t mapBytes = distanceMapBytes(f.distanceEncoding, m);
  const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
  const uint64_t texels = uint64_t(f.mapCount) * m * m;
  r.unsure.assign((texels + 7) / 8, 0);
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    const auto map = std::span<const uint8_t>(c.distance).subspan(k * mapBytes, mapBytes);
    const auto hit = [&](int64_t i, int64_t j) {
      const uint32_t code = bc4 ? c.codes[(uint64_t(k) * m + uint64_t(j)) * m + uint64_t(i)]
                                : loadCode(f.distanceEncoding, map, m, uint32_t(i), uint32_t(j));
      return code != (bc4 ? 255u : missCode(f.distanceEncoding));
    };
    for (int64_t j = 0; j < m; ++j)
      for (int64_t i = 0; i < m; ++i) {
        bool unsure = false;
        for (const auto& [di, dj] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
          const int64_t ni = i + di, nj = j + dj;
          if (ni >= 0 && nj >= 0 && ni < m && nj < m && hit(ni, nj) != hit(i, j)) unsure = true;
        }
        if (!unsure) continue;
        const uint64_t x = (uint64_t(k) * m + uint64_t(j)) * m + uint64_t(i);
        r.unsure[x / 8] = uint8_t(r.unsure[x / 8] | 1u << (x % 8));
        ++r.unsureTexels;
      }
  }
  // The octahedron: +x, -x, +y, -y, +z, -z; faces counter-clockwise seen from outside.
  std::vector<D3> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<uint32_t> tris = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  for (uint32_t l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    const auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      dirs.push_back(normalize(dirs[a] + dirs[b]));
      return mid[key] = uint32_t(dirs.size() - 1);
    };
    std::vector<uint32_t> next;
    for (size_t t = 0; t < tris.size(); t += 3) {
      const uint32_t a = tris[t], b = tris[t + 1], cc = tris[t + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, cc), ca = midpoint(cc, a);
      next.insert(next.end(), {a, ab, ca, ab, b, bc, ca, bc, cc, ab, bc, ca});
    }
    tris = std::move(next);
  }
  const double rr = f.sphere.radius;
  const D3 inner = D3{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]} + D3{0.10, -0.08, 0.12} * rr;
  for (const D3& d : dirs) {
    const D3 p = inner + d * (0.7 * rr);
    r.positions.insert(r.positions.end(), {float(p.x), float(p.y), float(p.z)});
  }
  r.indices = std::move(tris);
  return r;
}

}  // namespace vff::gen
