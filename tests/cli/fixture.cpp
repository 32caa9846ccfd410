// fixture: writes the input files of the CLI tests into a folder, with the library's own writer.
//
//   vff_cli_fixture DIR        (DIR is created if needed)
//
//   known.vff    10 maps of 4x4 unorm8-diameter, R = 1.5, every map the same: texel t holds code
//                17 t for t < 15 and a miss at t = 15 -> 150 hits of 160 (0.9375); with 2 histogram
//                bins, codes 0..119 (80 hits) fall in [0, R) and 136..238 (70 hits) in [R, 2R].
//                4 maps per block (3 blocks: 4, 4, 2). Metadata {"name":"known","note":"cli fixture"}.
//   small.vff    10 maps of 8x8 unorm8-diameter, synthetic codes (tests/common/synthetic_field.h)
//   zstd.vff     26 maps of 8x8 unorm16-diameter + oct-snorm16 normals, zstd blocks
//   chord.vff    10 maps of 8x8 unorm8-chord, hemi-octahedral directions
//   bit1.vff     10 maps of 8x8 bit1
//   big.vff      4226 maps of 64x64 unorm8-diameter + oct-snorm16 normals, all misses, stored:
//                payload 17309696 + 69238784 bytes (the paper's configuration); removed after the
//                tests by a cleanup fixture
//   corrupt.vff  small.vff with one byte inside its first distance block flipped
//   truncated.vff  the first 5000 bytes of small.vff
//   not-vff.txt  a text file
//   empty.vff    zero bytes
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace {

using namespace vff;

bool check(const Status& s, const std::string& what) {
  if (!s) std::fprintf(stderr, "vff_cli_fixture: %s: %s\n", what.c_str(), s.error().toString().c_str());
  return s.ok();
}

bool writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) std::fprintf(stderr, "vff_cli_fixture: cannot write %s\n", path.c_str());
  return static_cast<bool>(out);
}

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

WriteOptions quick() {
  WriteOptions o;
  o.sync = false;
  return o;
}

bool writeKnown(const std::string& dir) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 1, 4);
  std::vector<uint8_t> d(uint64_t{f.mapCount} * 16);
  for (size_t k = 0; k < d.size(); ++k) {
    const uint32_t t = k % 16;
    d[k] = t < 15 ? static_cast<uint8_t>(17 * t) : 255;
  }
  WriteOptions o = quick();
  o.mapsPerBlock = 4;
  o.metadataJson = R"({"note":"cli fixture","name":"known"})";
  return check(writeFile(dir + "/known.vff", f, d, {}, o), "known.vff");
}

bool writeSynthetic(const std::string& path, const FieldDesc& f, const WriteOptions& o) {
  const std::vector<uint8_t> d = test::syntheticDistance(f);
  std::vector<uint8_t> n;
  if (f.normalEncoding != NormalEncoding::kNone) n = test::syntheticNormals(f, d);
  return check(writeFile(path, f, d, n, o), path);
}

// 4226 maps of 64x64 with normals, streamed in chunks so that the payload never sits in memory.
bool writeBig(const std::string& path) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16, 32, 64);
  auto w = Writer::create(path, f, quick());
  if (!check(w.ok() ? Status{} : Status{w.error()}, path)) return false;
  constexpr uint32_t kChunk = 128;
  const std::vector<uint8_t> dist(uint64_t{kChunk} * 64 * 64, 255), norm(uint64_t{kChunk} * 64 * 64 * 4, 0);
  for (uint32_t done = 0; done < f.mapCount; done += kChunk) {
    const uint32_t n = std::min(kChunk, f.mapCount - done);
    if (!check(w->writeMaps(Plane::kDistance, std::span(dist).first(uint64_t{n} * 64 * 64)), path)) return false;
  }
  for (uint32_t done = 0; done < f.mapCount; done += kChunk) {
    const uint32_t n = std::min(kChunk, f.mapCount - done);
    if (!check(w->writeMaps(Plane::kNormal, std::span(norm).first(uint64_t{n} * 64 * 64 * 4)), path)) return false;
  }
  return check(w->finish(), path);
}

bool writeCorrupt(const std::string& dir) {
  std::vector<uint8_t> bytes = readBytes(dir + "/small.vff");
  auto file = File::openMemory(bytes);
  if (!check(file.ok() ? Status{} : Status{file.error()}, "small.vff")) return false;
  const uint64_t at = file->plane(Plane::kDistance).blocks.at(0).offset + 5;
  bytes[at] ^= 0x5A;
  return writeBytes(dir + "/corrupt.vff", bytes);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: vff_cli_fixture DIR\n");
    return 1;
  }
  const std::string dir = argv[1];
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "vff_cli_fixture: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
    return 1;
  }
  bool ok = writeKnown(dir);

  ok = ok && writeSynthetic(dir + "/small.vff",
                            test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 1, 8), quick());
  WriteOptions z = quick();
  z.codec = Codec::kZstd;
  z.zstdLevel = 3;
  z.mapsPerBlock = 8;
  ok = ok && writeSynthetic(dir + "/zstd.vff",
                            test::smallField(DistanceEncoding::kUnorm16Diameter, NormalEncoding::kOctSnorm16, 2, 8), z);
  FieldDesc chord = test::smallField(DistanceEncoding::kUnorm8Chord, NormalEncoding::kNone, 1, 8);
  chord.directionScheme = DirectionScheme::kHemiOctahedral;
  ok = ok && writeSynthetic(dir + "/chord.vff", chord, quick());
  ok = ok && writeSynthetic(dir + "/bit1.vff", test::smallField(DistanceEncoding::kBit1, NormalEncoding::kNone, 1, 8),
                            quick());
  ok = ok && writeBig(dir + "/big.vff");
  ok = ok && writeCorrupt(dir);
  if (ok) {
    std::vector<uint8_t> small = readBytes(dir + "/small.vff");
    small.resize(std::min<size_t>(small.size(), 5000));
    ok = writeBytes(dir + "/truncated.vff", small);
  }
  const std::string text = "This is a plain text file, not a visibility field.\nIt is long enough to hold a header.\n";
  ok = ok && writeBytes(dir + "/not-vff.txt", std::vector<uint8_t>(text.begin(), text.end()));
  ok = ok && writeBytes(dir + "/empty.vff", {});
  return ok ? 0 : 1;
}
