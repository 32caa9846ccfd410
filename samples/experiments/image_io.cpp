// image_io.cpp - PNG (stb_image_write), EXR (OpenEXR 3) and error heat maps; error statistics.
#include <ImfRgbaFile.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <exception>

#include "common.h"

namespace vffx {

namespace {

uint8_t to8(float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

vff::Error writeError(const std::string& path, const std::string& why) {
  return vff::Error{vff::Code::kIoWrite, 0, vff::kNoOffset, path + ": " + why};
}

vff::Status writeRgb8(const std::vector<uint8_t>& rgb, int w, int h, const std::string& path) {
  if (!stbi_write_png(path.c_str(), w, h, 3, rgb.data(), w * 3)) return writeError(path, "cannot write the PNG");
  return {};
}

// Black -> red -> yellow -> white for t in [0, 1].
void ramp(float t, uint8_t* out) {
  t = std::clamp(t, 0.0f, 1.0f) * 3.0f;
  const float r = std::min(t, 1.0f), g = std::clamp(t - 1.0f, 0.0f, 1.0f), b = std::clamp(t - 2.0f, 0.0f, 1.0f);
  out[0] = to8(r);
  out[1] = to8(g);
  out[2] = to8(b);
}

}  // namespace

vff::Status writePng(const Image& image, const std::string& path) {
  std::vector<uint8_t> rgb(image.rgb.size() * 3);
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    rgb[3 * i] = to8(image.rgb[i].x);
    rgb[3 * i + 1] = to8(image.rgb[i].y);
    rgb[3 * i + 2] = to8(image.rgb[i].z);
  }
  return writeRgb8(rgb, image.width, image.height, path);
}

vff::Status writeExr(const Image& image, const std::string& path) {
  try {
    std::vector<Imf::Rgba> px(image.rgb.size());
    for (size_t i = 0; i < px.size(); ++i) px[i] = Imf::Rgba(image.rgb[i].x, image.rgb[i].y, image.rgb[i].z, 1.0f);
    Imf::RgbaOutputFile file(path.c_str(), image.width, image.height, Imf::WRITE_RGB);
    file.setFrameBuffer(px.data(), 1, size_t(image.width));
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    return writeError(path, e.what());
  }
  return {};
}

vff::Status writeErrorMap(const Image& reference, const Image& image, const std::vector<uint8_t>& mask,
                          float gain, const std::string& path) {
  std::vector<uint8_t> rgb(image.rgb.size() * 3, 40);
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    if (!mask[i]) continue;
    const Vec3 a = reference.rgb[i], b = image.rgb[i];
    const int d = std::max({std::abs(int(to8(a.x)) - int(to8(b.x))), std::abs(int(to8(a.y)) - int(to8(b.y))),
                            std::abs(int(to8(a.z)) - int(to8(b.z)))});
    ramp(float(d) * gain / 255.0f, &rgb[3 * i]);
  }
  return writeRgb8(rgb, image.width, image.height, path);
}

ErrorStats compareImages(const Image& reference, const Image& image, const std::vector<uint8_t>& mask) {
  ErrorStats s;
  double sum = 0;
  uint64_t n = 0;
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    if (!mask[i]) continue;
    ++s.pixels;
    const float a[3] = {reference.rgb[i].x, reference.rgb[i].y, reference.rgb[i].z};
    const float b[3] = {image.rgb[i].x, image.rgb[i].y, image.rgb[i].z};
    for (int c = 0; c < 3; ++c) {
      const double d = double(to8(a[c])) - double(to8(b[c]));
      sum += d * d;
      s.max = std::max(s.max, std::abs(d));
      ++n;
    }
  }
  s.rms = n ? std::sqrt(sum / double(n)) : 0.0;
  return s;
}

Image sideBySide(const std::vector<Image>& images) {
  Image side;
  if (images.empty()) return side;
  side.height = images[0].height;
  for (const Image& im : images) side.width += im.width;
  side.rgb.resize(size_t(side.width) * size_t(side.height));
  int left = 0;
  for (const Image& im : images) {
    for (int y = 0; y < std::min(side.height, im.height); ++y)
      for (int x = 0; x < im.width; ++x) side.at(left + x, y) = im.at(x, y);
    left += im.width;
  }
  return side;
}

}  // namespace vffx
