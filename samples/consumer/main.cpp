// vff_consumer: writes a tiny visibility field, reads it back and prints what an engine would
// look at first. Usage: vff_consumer [out.vff]
#include <cstdio>
#include <vector>

#include <vff/vff.h>

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "consumer.vff";
  vff::FieldDesc field;
  field.sphere = {{0, 0, 0}, 1.0f};
  field.positionScheme = vff::PositionScheme::kOctaHemi2;
  field.positionParam = 1;  // 10 maps
  field.mapCount = vff::positionCount(field.positionScheme, field.positionParam).value();
  field.directionScheme = vff::DirectionScheme::kConcentricEqualArea;
  field.mapResolution = 8;
  field.distanceEncoding = vff::DistanceEncoding::kUnorm8Diameter;

  // Every ray hits at half the chord: code round(254 * cos(alpha) / 2).
  std::vector<uint8_t> maps(field.mapCount * 64);
  for (uint32_t k = 0; k < field.mapCount; ++k)
    for (uint32_t j = 0; j < 8; ++j)
      for (uint32_t i = 0; i < 8; ++i) {
        const float cosAlpha = vff::texelDirection(field.directionScheme, 8, i, j).z;
        maps[k * 64 + j * 8 + i] = uint8_t(vff::encodeDistance(field.distanceEncoding, true, cosAlpha, 1.0f, cosAlpha));
      }
  if (vff::Status s = vff::writeFile(path, field, maps); !s) {
    std::fprintf(stderr, "vff_consumer: error: %s: %s\n", path, s.error().toString().c_str());
    return 2;
  }
  vff::Result<vff::File> file = vff::File::open(path);
  if (!file) {
    std::fprintf(stderr, "vff_consumer: error: %s: %s\n", path, file.error().toString().c_str());
    return 3;
  }
  const vff::LayoutDesc& l = file->layout();
  auto map = file->mapData(vff::Plane::kDistance, 0);
  const vff::Texel centre = vff::decodeDistance(field.distanceEncoding, (*map)[4 * 8 + 4], 1.0f,
                                                vff::texelDirection(field.directionScheme, 8, 4, 4).z);
  std::printf("vff %u.%u: %u maps of %ux%u, %u slice(s) of %ux%u, centre texel of map 0: %.4f\n",
              file->info().versionMajor, file->info().versionMinor, file->field().mapCount,
              file->field().mapResolution, file->field().mapResolution, l.sliceCount, l.sliceWidth, l.sliceHeight,
              double(centre.distance));
  return vff::validateFile(path).valid() ? 0 : 3;
}
