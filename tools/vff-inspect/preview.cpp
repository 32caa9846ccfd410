// preview.cpp - a PNG contact sheet of the first maps of the distance plane.
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>

#include "cli.h"
#include "inspect.h"
#include "vff/direction.h"
#include "vff/encoding.h"

namespace vff::inspect {

namespace {

constexpr uint8_t kMiss[3] = {16, 32, 112};   // dark blue
constexpr uint8_t kSeparator[3] = {0, 0, 0};  // black; hits are never darker than kFarGrey
constexpr double kNearGrey = 255, kFarGrey = 48;

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

}  // namespace

PreviewGeometry previewGeometry(uint32_t mapResolution, uint32_t maps) {
  PreviewGeometry g;
  g.maps = maps;
  if (maps == 0) return g;
  g.columns = static_cast<uint32_t>(std::ceil(std::sqrt(double(maps))));
  while (uint64_t{g.columns} * g.columns < maps) ++g.columns;  // guard against sqrt rounding
  while (g.columns > 1 && uint64_t{g.columns - 1} * (g.columns - 1) >= maps) --g.columns;
  g.rows = (maps + g.columns - 1) / g.columns;
  g.width = uint64_t{g.columns} * (uint64_t{mapResolution} + 1) + 1;
  g.height = uint64_t{g.rows} * (uint64_t{mapResolution} + 1) + 1;
  return g;
}

Result<PreviewGeometry> writePreview(const File& file, const std::string& path, uint32_t maps) {
  const FieldDesc& field = file.field();
  const uint32_t m = field.mapResolution;
  const DistanceEncoding enc = field.distanceEncoding;
  const PreviewGeometry g = previewGeometry(m, std::min(maps, field.mapCount));
  if (g.maps == 0) return makeError(Code::kInvalidArgument, "the field has no maps to preview");
  if (g.width * g.height > kMaxPreviewPixels)
    return makeError(Code::kInvalidArgument, "a preview of " + std::to_string(g.maps) + " maps would be " +
                                                 std::to_string(g.width) + " x " + std::to_string(g.height) +
                                                 " pixels; ask for fewer with --maps");

  const auto w = static_cast<size_t>(g.width), h = static_cast<size_t>(g.height);
  std::vector<uint8_t> rgb(w * h * 3);
  for (size_t p = 0; p < w * h; ++p) std::copy(kSeparator, kSeparator + 3, &rgb[p * 3]);

  std::vector<float> cosAlpha(uint64_t{m} * m, 1.0f);
  if (enc == DistanceEncoding::kUnorm8Chord)
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) cosAlpha[uint64_t{j} * m + i] = texelDirection(field.directionScheme, m, i, j).z;
  const float radius = field.sphere.radius;
  const double diameter = 2.0 * double(radius);

  for (uint32_t k = 0; k < g.maps; ++k) {
    auto map = file.mapData(Plane::kDistance, k);
    if (!map) return std::move(map).error();
    const size_t x0 = size_t{k % g.columns} * (m + 1) + 1, y0 = size_t{k / g.columns} * (m + 1) + 1;
    for (uint32_t j = 0; j < m; ++j) {
      uint8_t* row = &rgb[((y0 + j) * w + x0) * 3];
      for (uint32_t i = 0; i < m; ++i) {
        const Texel t = decodeDistance(enc, loadCode(enc, *map, m, i, j), radius, cosAlpha[uint64_t{j} * m + i]);
        uint8_t* px = row + size_t{i} * 3;
        if (!t.hit) {
          std::copy(kMiss, kMiss + 3, px);
          continue;
        }
        // bit1 stores no distance: every hit is at distance 0, i.e. white.
        const double f = std::clamp(double(t.distance) / diameter, 0.0, 1.0);
        const auto grey = static_cast<uint8_t>(std::lround(kNearGrey - f * (kNearGrey - kFarGrey)));
        px[0] = px[1] = px[2] = grey;
      }
    }
  }

  std::vector<uint8_t> png;
  if (!stbi_write_png_to_func(appendBytes, &png, static_cast<int>(w), static_cast<int>(h), 3, rgb.data(),
                              static_cast<int>(w * 3)))
    return makeError(Code::kIoWrite, path + ": cannot encode the PNG");
  Status s = cli::writeFileAtomic(path, png);
  if (!s) return std::move(s).error();
  return g;
}

}  // namespace vff::inspect
