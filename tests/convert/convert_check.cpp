// convert_check: writes the inputs of the vff-convert tests and compares fields.
//
//   convert_check write OUT ENCODING [--normals] [--n N] [--m M] [--gutter G] [--radius R]
//       OUT: octa-hemi2 n (default 1: 10 maps) of M x M (default 8) texels, concentric directions,
//       deterministic pseudo-random codes covering every code value of 8-bit encodings (and the
//       ends of unorm16: 0, 1, 65533, 65534, 65535), about 1 in 8 texels a miss; with --normals,
//       at hits random unit normals or raw random oct-snorm16 codes (half each), zero at misses. Metadata
//       {"name":"convert fixture","n":N}.
//   convert_check plain-exr OUT [FIELD]
//       a 4x4 single-part EXR (channel Y) without the vff.field attribute, or with FIELD as its text.
//   convert_check perturb-exr IN OUT
//       copies a FLOAT EXR from vff-convert, multiplying every finite non-zero Y by 1.0001.
//   convert_check compare A B [--normal-tolerance K]
//       exit 0 when A and B have the same field description and metadata, byte-identical distance
//       maps, and normal codes that differ by at most K (default 0) per component. Prints what differs.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vff/vff.h"

namespace {

using namespace vff;

uint32_t mix(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// A plain 4x4 EXR with a FLOAT Y channel and no vff.field attribute.
int plainExr(int argc, char** argv) {
  if (argc != 3 && argc != 4) return 2;
  Imf::Header h(4, 4);
  h.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  if (argc == 4) h.insert("vff.field", Imf::StringAttribute(argv[3]));
  std::vector<float> y(16, 0.5f);
  Imf::FrameBuffer fb;
  fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), h.dataWindow()));
  Imf::OutputFile out(argv[2], h);
  out.setFrameBuffer(fb);
  out.writePixels(4);
  return 0;
}

// Copies a FLOAT multi-part EXR, multiplying every finite, non-zero Y by (1 + 1e-4): the values are
// then no longer decoded distances (what an image edit does).
int perturbExr(int argc, char** argv) {
  if (argc != 4) return 2;
  Imf::MultiPartInputFile in(argv[2]);
  std::vector<Imf::Header> headers;
  for (int p = 0; p < in.parts(); ++p) headers.push_back(in.header(p));
  Imf::MultiPartOutputFile out(argv[3], headers.data(), int(headers.size()));
  for (int p = 0; p < in.parts(); ++p) {
    const Imath::Box2i dw = headers[size_t(p)].dataWindow();
    const size_t texels = size_t(dw.max.x - dw.min.x + 1) * size_t(dw.max.y - dw.min.y + 1);
    std::vector<std::vector<float>> channels;
    std::vector<std::string> names;
    Imf::FrameBuffer fb;
    for (auto c = headers[size_t(p)].channels().begin(); c != headers[size_t(p)].channels().end(); ++c) {
      if (c.channel().type != Imf::FLOAT) continue;  // HALF channels (miss) are copied below
      names.push_back(c.name());
    }
    channels.resize(names.size(), std::vector<float>(texels));
    for (size_t c = 0; c < names.size(); ++c) fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, channels[c].data(), dw));
    std::vector<std::vector<uint16_t>> halves;
    std::vector<std::string> halfNames;
    for (auto c = headers[size_t(p)].channels().begin(); c != headers[size_t(p)].channels().end(); ++c)
      if (c.channel().type == Imf::HALF) halfNames.push_back(c.name());
    halves.resize(halfNames.size(), std::vector<uint16_t>(texels));
    for (size_t c = 0; c < halfNames.size(); ++c)
      fb.insert(halfNames[c], Imf::Slice::Make(Imf::HALF, halves[c].data(), dw));
    Imf::InputPart ip(in, p);
    ip.setFrameBuffer(fb);
    ip.readPixels(dw.min.y, dw.max.y);
    for (size_t c = 0; c < names.size(); ++c)
      if (names[c] == "Y")
        for (float& v : channels[c])
          if (std::isfinite(v) && v != 0.0f) v *= 1.0001f;
    Imf::OutputPart op(out, p);
    op.setFrameBuffer(fb);
    op.writePixels(dw.max.y - dw.min.y + 1);
  }
  return 0;
}

int usage() {
  std::fprintf(stderr,
               "usage: convert_check write OUT ENCODING [--normals] [--n N] [--m M] [--gutter G] [--radius R]\n"
               "       convert_check compare A B [--normal-tolerance K]\n");
  return 2;
}

int write(int argc, char** argv) {
  if (argc < 4) return usage();
  const std::string out = argv[2], enc = argv[3];
  bool normals = false;
  uint32_t n = 1, m = 8, gutter = 0;
  float radius = 1.5f;
  for (int a = 4; a < argc; ++a) {
    const std::string opt = argv[a];
    if (opt == "--normals")
      normals = true;
    else if (a + 1 < argc && opt == "--n")
      n = uint32_t(std::atoi(argv[++a]));
    else if (a + 1 < argc && opt == "--m")
      m = uint32_t(std::atoi(argv[++a]));
    else if (a + 1 < argc && opt == "--gutter")
      gutter = uint32_t(std::atoi(argv[++a]));
    else if (a + 1 < argc && opt == "--radius")
      radius = std::strtof(argv[++a], nullptr);
    else
      return usage();
  }
  FieldDesc f;
  f.sphere = {{0.25f, -1.0f, 3.0f}, radius};
  f.positionScheme = PositionScheme::kOctaHemi2;
  f.positionParam = n;
  f.mapCount = positionCount(PositionScheme::kOctaHemi2, n).value();
  f.directionScheme = DirectionScheme::kConcentricEqualArea;
  f.mapResolution = m;
  f.normalEncoding = normals ? NormalEncoding::kOctSnorm16 : NormalEncoding::kNone;
  if (enc == "unorm8-diameter")
    f.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  else if (enc == "unorm8-chord")
    f.distanceEncoding = DistanceEncoding::kUnorm8Chord;
  else if (enc == "unorm16-diameter")
    f.distanceEncoding = DistanceEncoding::kUnorm16Diameter;
  else if (enc == "bit1")
    f.distanceEncoding = DistanceEncoding::kBit1;
  else
    return usage();

  const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m), nBytes = normalMapBytes(f.normalEncoding, m);
  std::vector<uint8_t> dist(dBytes * f.mapCount), norm(nBytes * f.mapCount);
  const uint32_t miss = missCode(f.distanceEncoding), maxHit = maxHitCode(f.distanceEncoding);
  const uint32_t ends[] = {0, 1, maxHit - 1, maxHit, miss};
  uint64_t t = 0;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    std::span<uint8_t> map(dist.data() + k * dBytes, dBytes);
    for (uint32_t j = 0; j < m; ++j) {
      for (uint32_t i = 0; i < m; ++i, ++t) {
        const uint32_t h = mix(uint32_t(t) * 2654435761u + 12345u);
        uint32_t code;
        if (f.distanceEncoding == DistanceEncoding::kBit1)
          code = (h & 7) ? 1 : 0;
        else if (maxHit == 254)
          code = uint32_t(t % 256);  // every 8-bit code, misses included
        else if (t < 5)
          code = ends[t];
        else
          code = (h & 7) ? h % (maxHit + 1) : miss;
        storeCode(f.distanceEncoding, map, m, i, j, code);
        const bool hit = code != miss;  // bit1: miss code 0
        if (normals && hit && (h & 0x100)) {
          // Half of the normals are raw codes: every code a file may hold, seam duplicates included.
          const auto cx = static_cast<uint16_t>(int32_t(mix(h + 1) % 65535) - 32767);
          const auto cy = static_cast<uint16_t>(int32_t(mix(h + 2) % 65535) - 32767);
          uint8_t* o = norm.data() + k * nBytes + 4 * (uint64_t{j} * m + i);
          o[0] = uint8_t(cx & 0xff), o[1] = uint8_t(cx >> 8), o[2] = uint8_t(cy & 0xff), o[3] = uint8_t(cy >> 8);
        } else if (normals && hit) {
          const float z = float(mix(h) % 20001) / 10000.0f - 1.0f;
          const float phi = float(mix(h + 7) % 62832) / 10000.0f;
          const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
          encodeNormal({r * std::cos(phi), r * std::sin(phi), z}, norm.data() + k * nBytes + 4 * (uint64_t{j} * m + i));
        }
      }
    }
  }
  WriteOptions o;
  o.sync = false;
  o.layout.gutter = gutter;
  o.metadataJson = "{\"name\":\"convert fixture\",\"n\":" + std::to_string(n) + "}";
  Status s = writeFile(out, f, dist, normals ? std::span<const uint8_t>(norm) : std::span<const uint8_t>(), o);
  if (!s) {
    std::fprintf(stderr, "convert_check: %s\n", s.error().toString().c_str());
    return 1;
  }
  return 0;
}

bool sameField(const FieldDesc& a, const FieldDesc& b) {
  return std::memcmp(&a.sphere, &b.sphere, sizeof a.sphere) == 0 && a.positionScheme == b.positionScheme &&
         a.positionParam == b.positionParam && a.mapCount == b.mapCount && a.directionScheme == b.directionScheme &&
         a.mapResolution == b.mapResolution && a.frame == b.frame && a.distanceEncoding == b.distanceEncoding &&
         a.normalEncoding == b.normalEncoding;
}

int compare(int argc, char** argv) {
  if (argc < 4) return usage();
  int tolerance = 0;
  if (argc == 6 && std::string(argv[4]) == "--normal-tolerance")
    tolerance = std::atoi(argv[5]);
  else if (argc != 4)
    return usage();
  auto a = File::open(argv[2]);
  auto b = File::open(argv[3]);
  if (!a || !b) {
    std::fprintf(stderr, "convert_check: cannot open: %s\n", (!a ? a.error() : b.error()).toString().c_str());
    return 1;
  }
  int bad = 0;
  if (!sameField(a->field(), b->field())) {
    std::printf("field descriptions differ\n");
    bad = 1;
  }
  if (a->metadata() != b->metadata()) {
    std::printf("metadata differs\n");
    bad = 1;
  }
  if (bad) return 1;
  uint64_t distDiff = 0, normDiff = 0, normExact = 0, normTotal = 0;
  int worst = 0;
  for (uint32_t k = 0; k < a->field().mapCount; ++k) {
    auto da = a->mapData(Plane::kDistance, k), db = b->mapData(Plane::kDistance, k);
    if (!da || !db) return 1;
    for (size_t x = 0; x < da->size(); ++x) distDiff += (*da)[x] != (*db)[x];
    if (!a->hasNormals()) continue;
    auto na = a->mapData(Plane::kNormal, k), nb = b->mapData(Plane::kNormal, k);
    if (!na || !nb) return 1;
    for (size_t x = 0; x + 1 < na->size(); x += 2) {
      const int va = int16_t(uint16_t((*na)[x] | (*na)[x + 1] << 8));
      const int vb = int16_t(uint16_t((*nb)[x] | (*nb)[x + 1] << 8));
      const int d = std::abs(va - vb);
      worst = std::max(worst, d);
      normDiff += d > tolerance;
      normExact += d == 0;
      ++normTotal;
    }
  }
  std::printf("distance bytes differing: %llu\n", static_cast<unsigned long long>(distDiff));
  if (a->hasNormals())
    std::printf("normal components: %llu, exact %llu, beyond tolerance %llu, largest difference %d codes\n",
                static_cast<unsigned long long>(normTotal), static_cast<unsigned long long>(normExact),
                static_cast<unsigned long long>(normDiff), worst);
  return distDiff == 0 && normDiff == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string mode = argv[1];
  if (mode == "write") return write(argc, argv);
  if (mode == "compare") return compare(argc, argv);
  if (mode == "plain-exr") return plainExr(argc, argv);
  if (mode == "perturb-exr") return perturbExr(argc, argv);
  return usage();
}
