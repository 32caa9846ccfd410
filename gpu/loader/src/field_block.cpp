// What vff_gl uploads, computed on the CPU without any GL call (vff/gl/loader.h): the uniform block
// FieldBlock, the floats of the positions buffer and the shader's #define lines. Kept apart from
// the GL calls (loader.cpp) so that tests can check them where no GL library is installed.
#include <cmath>
#include <cstdint>
#include <vector>

#include "vff/encoding.h"
#include "vff/gl/loader.h"
#include "vff/positions.h"
#include "vff/query.h"

namespace vff::gl {
namespace {

constexpr float kPi = 3.14159265358979323846f;

bool hasChordTable(const FieldDesc& field) noexcept {
  return field.distanceEncoding == DistanceEncoding::kUnorm8Chord;
}

// Where the neighbour lists start in the positions buffer, in vec4 units: after the positions and
// (unorm8-chord) the M * M decode scales, padded to whole vec4.
uint32_t neighbourOffsetOf(const FieldDesc& field) noexcept {
  const size_t mapTexels = size_t(field.mapResolution) * field.mapResolution;
  return uint32_t(field.mapCount + (hasChordTable(field) ? (mapTexels + 3) / 4 : 0));
}

}  // namespace

Result<FieldBlock> makeFieldBlock(const FieldDesc& field, const LayoutDesc& layout) {
  if (Status s = checkFieldDesc(field); !s) return s.error();
  if (Status s = checkLayout(layout, field); !s) return s.error();
  FieldBlock b;
  for (int i = 0; i < 3; ++i) b.sphereCenter[i] = field.sphere.center[i];
  const float radius = field.sphere.radius;
  b.sphereRadius = radius;
  b.positionScheme = uint32_t(field.positionScheme);
  b.positionParam = field.positionParam;
  b.mapCount = field.mapCount;
  b.directionScheme = uint32_t(field.directionScheme);
  b.mapResolution = field.mapResolution;
  b.distanceEncoding = uint32_t(field.distanceEncoding);
  b.missCode = missCode(field.distanceEncoding);
  b.normalEncoding = uint32_t(field.normalEncoding);
  b.target = uint32_t(layout.target);
  b.gutter = layout.gutter;
  b.tileSize = layout.tileSize;
  b.tilesPerRow = layout.tilesPerRow;
  b.tilesPerColumn = layout.tilesPerColumn;
  b.sliceWidth = layout.sliceWidth;
  b.sliceHeight = layout.sliceHeight;
  b.sliceCount = layout.sliceCount;
  b.intraBias = defaultIntraBias(field);
  // One code step, vff::quantizationStep, so that the shader's decoded distances are the CPU's.
  // unorm8-chord's step depends on the texel (the table in the positions buffer); bit1 has none.
  b.distanceScale = hasChordTable(field) ? 0.0f : quantizationStep(field.distanceEncoding, radius, 1.0f);
  b.invRadius = 1.0f / radius;
  b.twoRadius = 2.0f * radius;
  b.neighbourOffset = neighbourOffsetOf(field);
  // As FieldQuery::Impl::build.
  const float spacing = std::sqrt(4.0f * kPi / float(field.mapCount));
  const float r = kQueryKernelSpacings * spacing;
  b.kernelRadius2 = r * r;
  return b;
}

Result<std::vector<uint32_t>> neighbourLists(const FieldDesc& field) {
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  return queryNeighbours(*ps);
}

Result<std::vector<float>> makePositionsBuffer(const FieldDesc& field) {
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  const uint32_t neighbourOffset = neighbourOffsetOf(field);
  std::vector<float> positions(size_t(neighbourOffset) * 4 + size_t(field.mapCount) * kNeighbours, 0.0f);
  if (hasChordTable(field)) {
    // The decode step of every texel: the chord of its centre direction.
    float* scale = positions.data() + size_t(field.mapCount) * 4;
    const uint32_t m = field.mapResolution;
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const float cosAlpha = texelDirection(field.directionScheme, m, i, j).z;
        scale[size_t(j) * m + i] = quantizationStep(DistanceEncoding::kUnorm8Chord, field.sphere.radius, cosAlpha);
      }
  }
  for (uint32_t k = 0; k < field.mapCount; ++k) {
    const Vec3 u = ps->position(k);
    positions[4 * size_t(k)] = u.x;
    positions[4 * size_t(k) + 1] = u.y;
    positions[4 * size_t(k) + 2] = u.z;
  }
  if (field.mapCount > (1u << 24))
    return makeError(Code::kUnsupported, "vff_gl stores sample indices as binary32: at most 2^24 maps");
  auto nb = neighbourLists(field);
  if (!nb) return nb.error();
  float* lists = positions.data() + size_t(neighbourOffset) * 4;
  for (size_t i = 0; i < nb->size(); ++i) lists[i] = (*nb)[i] == UINT32_MAX ? -1.0f : float((*nb)[i]);
  return positions;
}

const char* shaderDefines(const FieldDesc& field, const LayoutDesc& layout) noexcept {
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) return "#define VFF_MAPS_BC4\n";
  return layout.target == LayoutTarget::kTexture3D ? "#define VFF_MAPS_3D\n" : "";
}

}  // namespace vff::gl
