// convert_check: writes the inputs of the vff-convert tests and compares fields.
//
//   convert_check write OUT ENCODING [--normals] [--n N] [--m M] [--gutter G] [--radius R] [--meta JSON]
//       OUT: octa-hemi2 n (default 1: 10 maps) of M x M (default 8) texels, concentric directions,
//       deterministic pseudo-random codes covering every code value of 8-bit encodings (and the
//       ends of unorm16: 0, 1, 65533, 65534, 65535), about 1 in 8 texels a miss; with --normals,
//       at hits random unit normals or raw random oct-snorm16 codes (half each), zero at misses. Metadata
//       {"name":"convert fixture","n":N}, or JSON.
//   convert_check plain-exr OUT [FIELD]
//       a 4x4 single-part EXR (channel Y) without the vff.field attribute, or with FIELD as its text.
//   convert_check perturb-exr IN OUT
//       copies a FLOAT EXR from vff-convert, multiplying every finite non-zero Y by 1.0001.
//   convert_check compare A B [--normal-tolerance K]
//       exit 0 when A and B have the same field description and metadata, byte-identical distance
//       maps, and normal codes that differ by at most K (default 0) per component. Prints what differs.
//   convert_check texels A B [--max-steps S] [--max-flips N] [--min-agreement P] [--max-mean-error E]
//       A and B with the same sphere, positions and map size, any encodings (B's not bit1 unless A is
//       too, or A's distances are ignored): prints the hits that became misses and the misses that
//       became hits, the share of texels whose hit/miss agree, the largest |dB - dA| over texels that
//       hit in both in steps of B's encoding (and in R), the mean |dB - dA| in R, and the hit texels
//       whose normal bytes differ. Exit 1 when a bound is broken: largest error > S steps, more than
//       N flips, agreement below P percent, mean error above E R.
//   convert_check downsample SRC DST RULE
//       DST (M' x M') made from SRC (M x M) by --map-size with RULE (min, majority, centre, tent):
//       recomputes every DST texel from the SRC texels by the rule as tools/vff-convert/README.md
//       states it (each SRC texel weighted by its offset from the DST texel's centre), encodes it in
//       DST's encoding, and compares codes and normals exactly. Exit 1 on any difference.
//   convert_check meta FILE
//       prints the META text as stored (canonical JSON), or nothing.
//   convert_check xxh3 FILE
//       prints the XXH3-64 of the file's bytes as 16 lowercase hex digits.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace {

using namespace vff;
using test::hashMix;

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
               "                           [--meta JSON]\n"
               "       convert_check compare A B [--normal-tolerance K]\n"
               "       convert_check texels A B [--max-steps S] [--max-flips N] [--min-agreement P]\n"
               "                            [--max-mean-error E]\n"
               "       convert_check downsample SRC DST min|majority|centre|tent\n"
               "       convert_check meta FILE | xxh3 FILE\n");
  return 2;
}

int write(int argc, char** argv) {
  if (argc < 4) return usage();
  const std::string out = argv[2], enc = argv[3];
  bool normals = false;
  uint32_t n = 1, m = 8, gutter = 0;
  float radius = 1.5f;
  std::string metaText;
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
    else if (a + 1 < argc && opt == "--meta")
      metaText = argv[++a];
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
        const uint32_t h = hashMix(uint32_t(t) * 2654435761u + 12345u);
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
          const auto cx = static_cast<uint16_t>(int32_t(hashMix(h + 1) % 65535) - 32767);
          const auto cy = static_cast<uint16_t>(int32_t(hashMix(h + 2) % 65535) - 32767);
          uint8_t* o = norm.data() + k * nBytes + 4 * (uint64_t{j} * m + i);
          o[0] = uint8_t(cx & 0xff), o[1] = uint8_t(cx >> 8), o[2] = uint8_t(cy & 0xff), o[3] = uint8_t(cy >> 8);
        } else if (normals && hit) {
          const float z = float(hashMix(h) % 20001) / 10000.0f - 1.0f;
          const float phi = float(hashMix(h + 7) % 62832) / 10000.0f;
          const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
          encodeNormal({r * std::cos(phi), r * std::sin(phi), z}, norm.data() + k * nBytes + 4 * (uint64_t{j} * m + i));
        }
      }
    }
  }
  WriteOptions o;
  o.sync = false;
  o.layout.gutter = gutter;
  o.metadataJson = metaText.empty() ? "{\"name\":\"convert fixture\",\"n\":" + std::to_string(n) + "}" : metaText;
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

// Every plane of a file decoded into memory (map-major), for the checks below.
struct Planes {
  std::optional<File> file;
  std::vector<uint8_t> distance, normals;
};
bool loadPlanes(const char* path, Planes* p) {
  auto f = File::open(path);
  if (!f) {
    std::fprintf(stderr, "convert_check: %s: %s\n", path, f.error().toString().c_str());
    return false;
  }
  for (Plane pl : {Plane::kDistance, Plane::kNormal}) {
    if (!f->plane(pl).present) continue;
    std::vector<uint8_t>& out = pl == Plane::kDistance ? p->distance : p->normals;
    for (uint32_t b = 0; b < f->plane(pl).blocks.size(); ++b) {
      auto bytes = f->blockData(pl, b);
      if (!bytes) return false;
      out.insert(out.end(), bytes->begin(), bytes->end());
    }
  }
  p->file.emplace(std::move(*f));
  return true;
}

// Texel (k, i, j) of a plane: hit and distance.
Texel texelOf(const FieldDesc& f, const std::vector<uint8_t>& dist, uint32_t k, uint32_t i, uint32_t j) {
  const uint64_t bytes = distanceMapBytes(f.distanceEncoding, f.mapResolution);
  const uint32_t code = loadCode(f.distanceEncoding, {dist.data() + k * bytes, bytes}, f.mapResolution, i, j);
  return decodeDistance(f.distanceEncoding, code, f.sphere.radius,
                        texelDirection(f.directionScheme, f.mapResolution, i, j).z);
}

int texels(int argc, char** argv) {
  if (argc < 4) return usage();
  double maxSteps = -1, minAgreement = -1, maxMean = -1;
  long long maxFlips = -1;
  for (int a = 4; a + 1 < argc; a += 2) {
    const std::string opt = argv[a];
    if (opt == "--max-steps") maxSteps = std::atof(argv[a + 1]);
    else if (opt == "--max-flips") maxFlips = std::atoll(argv[a + 1]);
    else if (opt == "--min-agreement") minAgreement = std::atof(argv[a + 1]);
    else if (opt == "--max-mean-error") maxMean = std::atof(argv[a + 1]);
    else return usage();
  }
  Planes A, B;
  if (!loadPlanes(argv[2], &A) || !loadPlanes(argv[3], &B)) return 1;
  const FieldDesc &fa = A.file->field(), &fb = B.file->field();
  if (std::memcmp(&fa.sphere, &fb.sphere, sizeof fa.sphere) != 0 || fa.positionScheme != fb.positionScheme ||
      fa.positionParam != fb.positionParam || fa.mapResolution != fb.mapResolution ||
      fa.directionScheme != fb.directionScheme) {
    std::printf("the fields differ in sphere, positions or map size\n");
    return 1;
  }
  const uint32_t m = fa.mapResolution;
  const bool distances =
      fa.distanceEncoding != DistanceEncoding::kBit1 && fb.distanceEncoding != DistanceEncoding::kBit1;
  const bool normals = !A.normals.empty() && !B.normals.empty();
  uint64_t hitToMiss = 0, missToHit = 0, both = 0, total = 0, normalDiff = 0;
  double worstSteps = 0, worstR = 0, sumR = 0;
  for (uint32_t k = 0; k < fa.mapCount; ++k)
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        ++total;
        const Texel ta = texelOf(fa, A.distance, k, i, j), tb = texelOf(fb, B.distance, k, i, j);
        hitToMiss += ta.hit && !tb.hit;
        missToHit += !ta.hit && tb.hit;
        if (!ta.hit || !tb.hit) continue;
        ++both;
        const size_t n = (size_t(k) * m * m + size_t(j) * m + i) * 4;
        if (normals && !std::equal(A.normals.begin() + ptrdiff_t(n), A.normals.begin() + ptrdiff_t(n + 4),
                                   B.normals.begin() + ptrdiff_t(n)))
          ++normalDiff;
        if (!distances) continue;
        const double e = std::fabs(double(tb.distance) - double(ta.distance));
        const float step = quantizationStep(fb.distanceEncoding, fb.sphere.radius,
                                            texelDirection(fb.directionScheme, m, i, j).z);
        worstSteps = std::max(worstSteps, e / double(step));
        worstR = std::max(worstR, e / double(fa.sphere.radius));
        sumR += e / double(fa.sphere.radius);
      }
  const double agreement = 100.0 * double(total - hitToMiss - missToHit) / double(std::max<uint64_t>(total, 1));
  const double meanR = both ? sumR / double(both) : 0.0;
  std::printf("texels %llu, hits in both %llu, hit->miss %llu, miss->hit %llu, agreement %.3f%%\n",
              static_cast<unsigned long long>(total), static_cast<unsigned long long>(both),
              static_cast<unsigned long long>(hitToMiss), static_cast<unsigned long long>(missToHit), agreement);
  if (distances)
    std::printf("max error %.4f steps of %s (%.6f R), mean %.6f R\n", worstSteps,
                distanceEncodingName(fb.distanceEncoding), worstR, meanR);
  if (normals) std::printf("hit texels with other normal bytes: %llu\n", static_cast<unsigned long long>(normalDiff));
  bool ok = true;
  if (maxSteps >= 0 && worstSteps > maxSteps) ok = false;
  if (maxFlips >= 0 && hitToMiss + missToHit > uint64_t(maxFlips)) ok = false;
  if (minAgreement >= 0 && agreement < minAgreement) ok = false;
  if (maxMean >= 0 && meanR > maxMean) ok = false;
  if (!ok) std::printf("a bound is broken\n");
  return ok ? 0 : 1;
}

int downsample(int argc, char** argv) {
  if (argc != 5) return usage();
  const std::string rule = argv[4];
  if (rule != "min" && rule != "majority" && rule != "centre" && rule != "tent") return usage();
  Planes S, D;
  if (!loadPlanes(argv[2], &S) || !loadPlanes(argv[3], &D)) return 1;
  const FieldDesc &fs = S.file->field(), &fd = D.file->field();
  const uint32_t m = fs.mapResolution, nm = fd.mapResolution;
  if (fs.mapCount != fd.mapCount || nm == 0 || m % nm != 0) {
    std::printf("DST is not a map-size reduction of SRC\n");
    return 1;
  }
  const int64_t f = m / nm;
  const uint64_t dBytes = distanceMapBytes(fd.distanceEncoding, nm);
  const bool normals = !S.normals.empty();
  uint64_t checked = 0, codeDiff = 0, normalDiff = 0, hits = 0;
  for (uint32_t k = 0; k < fd.mapCount; ++k)
    for (uint32_t j = 0; j < nm; ++j)
      for (uint32_t i = 0; i < nm; ++i) {
        // Every source texel (x, y) by its offset from the new texel's centre, doubled so that it is
        // an integer: ox = 2 (x + 1/2) - 2 f (i + 1/2), in source texels.
        bool hit = false;
        float distance = 0;
        int64_t pick = -1, pickD2 = 0;  // the source texel whose normal the new texel takes
        double hitW = 0, missW = 0, sum = 0;
        for (uint32_t y = 0; y < m; ++y)
          for (uint32_t x = 0; x < m; ++x) {
            const int64_t ox = std::llabs(int64_t(2 * x + 1) - f * int64_t(2 * i + 1));
            const int64_t oy = std::llabs(int64_t(2 * y + 1) - f * int64_t(2 * j + 1));
            const bool inside = ox < f && oy < f;  // the source texel lies in the new texel
            double w = 0;
            if (rule == "tent")
              w = ox < 2 * f && oy < 2 * f ? double(2 * f - ox) * double(2 * f - oy) : 0.0;  // (1-|dx|/f)(1-|dy|/f)
            else if (rule == "centre")
              w = ox <= 1 && oy <= 1 ? 1.0 : 0.0;  // the texel at the centre, or the 2 x 2 around it
            else
              w = inside ? 1.0 : 0.0;
            if (w == 0) continue;
            const Texel t = texelOf(fs, S.distance, k, x, y);
            if (rule == "min") {
              if (t.hit && (!hit || t.distance < distance)) {
                hit = true;
                distance = t.distance;
                pick = int64_t(y) * m + x;
              }
              continue;
            }
            if (!t.hit) {
              missW += w;
              continue;
            }
            hitW += w;
            sum += w * double(t.distance);
            if (pick < 0 || ox * ox + oy * oy < pickD2) {
              pick = int64_t(y) * m + x;
              pickD2 = ox * ox + oy * oy;
            }
          }
        if (rule != "min") {
          hit = pick >= 0 && hitW >= missW;  // ties are hits
          distance = hit ? float(sum / hitW) : 0.0f;
        }
        const uint32_t want = encodeDistance(fd.distanceEncoding, hit, distance, fd.sphere.radius,
                                             texelDirection(fd.directionScheme, nm, i, j).z);
        const uint32_t got = loadCode(fd.distanceEncoding, {D.distance.data() + k * dBytes, dBytes}, nm, i, j);
        ++checked;
        hits += hit;
        codeDiff += want != got;
        if (normals) {
          uint8_t zero[4] = {0, 0, 0, 0};
          const uint8_t* w = hit ? S.normals.data() + (uint64_t(k) * m * m + uint64_t(pick)) * 4 : zero;
          const uint8_t* g = D.normals.data() + (uint64_t(k) * nm * nm + uint64_t(j) * nm + i) * 4;
          normalDiff += !std::equal(w, w + 4, g);
        }
      }
  std::printf("texels checked %llu (hits %llu), codes differing %llu, normals differing %llu\n",
              static_cast<unsigned long long>(checked), static_cast<unsigned long long>(hits),
              static_cast<unsigned long long>(codeDiff), static_cast<unsigned long long>(normalDiff));
  return codeDiff == 0 && normalDiff == 0 ? 0 : 1;
}

int meta(int argc, char** argv) {
  if (argc != 3) return usage();
  auto f = File::open(argv[2]);
  if (!f) return 1;
  std::printf("%.*s\n", int(f->metadata().size()), f->metadata().data());
  return 0;
}

int xxh3(int argc, char** argv) {
  if (argc != 3) return usage();
  std::ifstream in(argv[2], std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.eof() && !in) return 1;
  std::printf("%016llx\n", static_cast<unsigned long long>(XXH3_64bits(bytes.data(), bytes.size())));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string mode = argv[1];
  if (mode == "write") return write(argc, argv);
  if (mode == "compare") return compare(argc, argv);
  if (mode == "plain-exr") return plainExr(argc, argv);
  if (mode == "perturb-exr") return perturbExr(argc, argv);
  if (mode == "texels") return texels(argc, argv);
  if (mode == "downsample") return downsample(argc, argv);
  if (mode == "meta") return meta(argc, argv);
  if (mode == "xxh3") return xxh3(argc, argv);
  return usage();
}
