// vff_web_reference FIELD OUT.pgm SIZE nearest|interpolated
//
// The CPU reference of web/'s reference view (web/src/viewer/passes.js, referenceView): ground ambient
// occlusion seen from straight above, the object unrotated. Pixel (x, y) of SIZE x SIZE looks at
// the ground point (cx + (2 (x + 0.5) / SIZE - 1) 2R, cy - R, cz + (2 (y + 0.5) / SIZE - 1) 2R)
// (the ground plane touches the bottom of the bounding sphere); its value is the mean, over the
// AO_RAYS directions of aoDirection below, of FieldQuery::visibility (interpolated) or of
// !occluded (nearest) for rays of length 4R, written as round(255 * mean) in a binary PGM with
// row 0 at y = 0. The browser test renders the same view with the GLSL ES port and compares.
#include <vff/vff.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr int kAoRays = 32;  // web/src/viewer/passes.js REFERENCE_AO_RAYS

// Direction i of the cosine-weighted hemisphere set around +y (web/src/viewer/passes.js aoDirection):
// a spherical Fibonacci spiral, in binary32 as the shader computes it.
vff::Vec3 aoDirection(int i) {
  const float u = (float(i) + 0.5f) / float(kAoRays);
  const float r = std::sqrt(u);
  const float phi = float(i) * 2.39996323f;
  return vff::Vec3{r * std::cos(phi), std::sqrt(1.0f - u), r * std::sin(phi)};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: vff_web_reference FIELD OUT.pgm SIZE nearest|interpolated\n");
    return 1;
  }
  const int size = std::atoi(argv[3]);
  const bool interpolated = std::strcmp(argv[4], "interpolated") == 0;
  vff::Result<vff::File> f = vff::File::open(argv[1]);
  if (!f) {
    std::fprintf(stderr, "vff_web_reference: %s\n", f.error().toString().c_str());
    return 3;
  }
  vff::Result<vff::FieldQuery> q = vff::FieldQuery::fromFile(*f);
  if (!q) {
    std::fprintf(stderr, "vff_web_reference: %s\n", q.error().toString().c_str());
    return 4;
  }
  const vff::FieldDesc& fd = q->field();
  const float R = fd.sphere.radius;
  const vff::Vec3 c{fd.sphere.center[0], fd.sphere.center[1], fd.sphere.center[2]};
  vff::QueryOptions opt;
  opt.reconstruction = interpolated ? vff::Reconstruction::kInterpolated : vff::Reconstruction::kNearest;
  opt.intraBias = 0.0f;
  std::vector<unsigned char> img(size_t(size) * size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const vff::Vec3 p{c.x + (2.0f * (float(x) + 0.5f) / float(size) - 1.0f) * 2.0f * R, c.y - R,
                        c.z + (2.0f * (float(y) + 0.5f) / float(size) - 1.0f) * 2.0f * R};
      float open = 0.0f;
      for (int i = 0; i < kAoRays; ++i) {
        const vff::Ray ray{p, aoDirection(i), 0.0f, 4.0f * R};
        open += interpolated ? q->visibility(ray, opt) : (q->occluded(ray, opt) ? 0.0f : 1.0f);
      }
      img[size_t(y) * size + x] = static_cast<unsigned char>(std::lround(255.0f * open / float(kAoRays)));
    }
  const std::string tmp = std::string(argv[2]) + ".part";
  std::FILE* out = std::fopen(tmp.c_str(), "wb");
  if (!out) {
    std::fprintf(stderr, "vff_web_reference: %s: cannot write\n", tmp.c_str());
    return 2;
  }
  std::fprintf(out, "P5\n%d %d\n255\n", size, size);
  const bool ok = std::fwrite(img.data(), 1, img.size(), out) == img.size();
  if (std::fclose(out) != 0 || !ok || std::rename(tmp.c_str(), argv[2]) != 0) {
    std::fprintf(stderr, "vff_web_reference: %s: cannot write\n", argv[2]);
    return 2;
  }
  return 0;
}
