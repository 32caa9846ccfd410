#include "vff/bake/procedural.h"

#include <cmath>
#include <cstdio>

namespace vff::bake {
namespace {

constexpr float kPi = 3.14159265358979323846f;

struct V3 {
  float x, y, z;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 crossp(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 norm(V3 a) {
  const float l = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
  return l > 0 ? V3{a.x / l, a.y / l, a.z / l} : V3{0, 0, 1};
}

void addVertex(Mesh& m, V3 p, V3 n) {
  m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
  m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
}

// Quads of a (rows+1) x (cols+1) vertex grid starting at `base`; wrapCols joins the last column.
void gridFaces(Mesh& m, uint32_t base, uint32_t rows, uint32_t cols, bool flip) {
  const uint32_t w = cols + 1;
  for (uint32_t r = 0; r < rows; ++r)
    for (uint32_t c = 0; c < cols; ++c) {
      const uint32_t a = base + r * w + c, b = a + 1, d = a + w, e = d + 1;
      if (flip) m.indices.insert(m.indices.end(), {a, e, b, a, d, e});
      else m.indices.insert(m.indices.end(), {a, b, e, a, e, d});
    }
}

}  // namespace

Mesh makeSphere(float radius, uint32_t rings, uint32_t segments) {
  Mesh m;
  for (uint32_t r = 0; r <= rings; ++r) {
    const float th = kPi * float(r) / float(rings);
    for (uint32_t s = 0; s <= segments; ++s) {
      const float ph = 2 * kPi * float(s) / float(segments);
      const V3 n{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      addVertex(m, {radius * n.x, radius * n.y, radius * n.z}, n);
    }
  }
  gridFaces(m, 0, rings, segments, true);
  return m;
}

Mesh makeBox(float hx, float hy, float hz) {
  Mesh m;
  const V3 n[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const V3& f : n) {
    // Two tangents of the face, corners counter-clockwise seen from outside.
    const V3 u = std::fabs(f.x) > 0 ? V3{0, 1, 0} : V3{1, 0, 0};
    const V3 v = crossp(f, u);
    const uint32_t base = uint32_t(m.positions.size() / 3);
    for (int k = 0; k < 4; ++k) {
      const float su = (k == 1 || k == 2) ? 1.f : -1.f, sv = (k >= 2) ? 1.f : -1.f;
      const V3 p{(f.x + su * u.x + sv * v.x) * hx, (f.y + su * u.y + sv * v.y) * hy, (f.z + su * u.z + sv * v.z) * hz};
      addVertex(m, p, f);
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return m;
}

namespace {
// A tube of `radius` around a closed curve given by `curve(t)`, t in [0, 1).
template <class F>
Mesh tube(F curve, float radius, uint32_t segments, uint32_t sides) {
  Mesh m;
  for (uint32_t i = 0; i <= segments; ++i) {
    const float t = float(i % segments) / float(segments);
    const V3 p = curve(t), q = curve(t + 1e-3f);
    const V3 tan = norm(sub(q, p));
    V3 up = std::fabs(tan.z) < 0.9f ? V3{0, 0, 1} : V3{1, 0, 0};
    const V3 b = norm(crossp(tan, up));
    const V3 nn = crossp(b, tan);
    for (uint32_t j = 0; j <= sides; ++j) {
      const float a = 2 * kPi * float(j % sides) / float(sides);
      const V3 d{std::cos(a) * nn.x + std::sin(a) * b.x, std::cos(a) * nn.y + std::sin(a) * b.y,
                 std::cos(a) * nn.z + std::sin(a) * b.z};
      addVertex(m, {p.x + radius * d.x, p.y + radius * d.y, p.z + radius * d.z}, d);
    }
  }
  gridFaces(m, 0, segments, sides, false);
  return m;
}
}  // namespace

Mesh makeTorusKnot(uint32_t p, uint32_t q, float tubeRadius, uint32_t segments, uint32_t sides) {
  return tube(
      [&](float t) {
        const float a = 2 * kPi * t;
        const float r = 0.6f + 0.3f * std::cos(float(q) * a);
        return V3{r * std::cos(float(p) * a), r * std::sin(float(p) * a), 0.3f * std::sin(float(q) * a)};
      },
      tubeRadius, segments, sides);
}

Mesh makeBowl(float thickness, uint32_t rings, uint32_t segments) {
  Mesh m;
  // Outer and inner hemispherical surfaces (z <= 0), joined by a rim ring.
  for (int layer = 0; layer < 2; ++layer) {
    const float r = layer == 0 ? 1.0f : 1.0f - thickness;
    for (uint32_t i = 0; i <= rings; ++i) {
      const float th = 0.5f * kPi * float(i) / float(rings);  // 0 at the rim, pi/2 at the bottom
      for (uint32_t s = 0; s <= segments; ++s) {
        const float ph = 2 * kPi * float(s) / float(segments);
        const V3 n{std::cos(th) * std::cos(ph), std::cos(th) * std::sin(ph), -std::sin(th)};
        addVertex(m, {r * n.x, r * n.y, r * n.z}, layer == 0 ? n : V3{-n.x, -n.y, -n.z});
      }
    }
    gridFaces(m, uint32_t(layer) * (rings + 1) * (segments + 1), rings, segments, layer == 0);
  }
  // Rim: connect the first ring of both layers.
  const uint32_t inner = (rings + 1) * (segments + 1);
  for (uint32_t s = 0; s < segments; ++s)
    m.indices.insert(m.indices.end(), {s, inner + s, s + 1, s + 1, inner + s, inner + s + 1});
  return m;
}

Mesh makeRod(float length, float radius, uint32_t segments, uint32_t sides) {
  // A closed tube: a long thin loop (a stadium shape) keeps the mesh watertight without caps.
  const float half = 0.5f * length;
  return tube(
      [&](float t) {
        const float a = 2 * kPi * t;
        return V3{half * std::cos(a), 2.0f * radius * std::sin(a), 0.0f};
      },
      radius, segments, sides);
}

const std::vector<std::string>& shapeNames() {
  static const std::vector<std::string> names = {"sphere", "box", "torus-knot", "bowl", "rod"};
  return names;
}

Mesh makeShape(const std::string& name) {
  if (name == "sphere") return makeSphere(1.0f);
  if (name == "box") return makeBox(1.0f, 0.5f, 0.25f);
  if (name == "torus-knot") return makeTorusKnot();
  if (name == "bowl") return makeBowl();
  if (name == "rod") return makeRod();
  return {};
}

Status writeObj(const Mesh& m, const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return makeError(Code::kIoWrite, path + ": cannot open for writing");
  for (size_t i = 0; i < m.vertexCount(); ++i)
    std::fprintf(f, "v %.9g %.9g %.9g\n", double(m.positions[3 * i]), double(m.positions[3 * i + 1]),
                 double(m.positions[3 * i + 2]));
  const bool n = !m.normals.empty();
  for (size_t i = 0; n && i < m.vertexCount(); ++i)
    std::fprintf(f, "vn %.9g %.9g %.9g\n", double(m.normals[3 * i]), double(m.normals[3 * i + 1]),
                 double(m.normals[3 * i + 2]));
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const uint32_t a = m.indices[3 * t] + 1, b = m.indices[3 * t + 1] + 1, c = m.indices[3 * t + 2] + 1;
    if (n) std::fprintf(f, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
    else std::fprintf(f, "f %u %u %u\n", a, b, c);
  }
  const bool ok = std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !ok) return makeError(Code::kIoWrite, path + ": write failed");
  return {};
}

}  // namespace vff::bake
