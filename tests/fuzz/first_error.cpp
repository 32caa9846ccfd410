// vff_fuzz_first_error FILE|FOLDER...: for each file (folders walked recursively, in sorted order),
// what libvff makes of it under each checksum policy, one line "PATH<TAB>A<TAB>B<TAB>C" (verify-all,
// lazy, none), each "error ID" or "ok HASH": the reference side of the JavaScript decoder's
// differential test (tests/fuzz/js/differential.mjs), which computes the same line with web/src and
// compares. (Without verified checksums, damaged files reach the structure checks and decoders.)
//
// The reading is what an application does: File::openMemory (payload limited to kMaxPayloadBytes
// so that a hostile header cannot make either side allocate much), then every distance map in
// order, then every normal map. The first error ends it; its ID is printed. When
// everything decodes, HASH is the XXH3-64 (hex) of the decoded planes: every distance map's texels
// as little-endian float32 (the distance; 1 for a bit1 hit; the quiet NaN 0x7fc00000 for a miss),
// then every normal map's stored bytes, then (where the slices hold at most kMaxSliceTexels texels
// in all) every composed slice of the distance plane and then of the normal plane.
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "input_files.h"
#include "vff/vff.h"

namespace {

namespace fs = std::filesystem;

constexpr uint64_t kMaxPayloadBytes = uint64_t{256} << 20;  // differential.mjs passes the same
constexpr uint32_t kMissBits = 0x7fc00000u;
constexpr uint64_t kMaxSliceTexels = uint64_t{1} << 24;  // differential.mjs uses the same

// The cosine each texel's chord scales with (unorm8-chord), as decodeDistance takes it.
std::vector<float> texelCosines(const vff::FieldDesc& f) {
  const uint32_t m = f.mapResolution;
  std::vector<float> c(size_t(m) * m);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) c[size_t(j) * m + i] = std::max(vff::texelDirection(f.directionScheme, m, i, j).z, 0.0f);
  return c;
}

// "error ID" or "ok HASH" for one file's bytes.
std::string outcome(const std::vector<uint8_t>& bytes, vff::ChecksumPolicy policy) {
  vff::ReadOptions o;
  o.maxPayloadBytes = kMaxPayloadBytes;
  o.checksums = policy;
  vff::Result<vff::File> f = vff::File::openMemory(bytes, o);
  if (!f) return "error " + std::to_string(uint32_t(f.error().code));
  const vff::FieldDesc& fd = f->field();
  const uint32_t m = fd.mapResolution;
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  std::vector<float> cosines;
  if (fd.distanceEncoding == vff::DistanceEncoding::kUnorm8Chord) cosines = texelCosines(fd);
  std::vector<uint32_t> values(size_t(m) * m);
  std::string result;
  for (uint32_t k = 0; k < fd.mapCount && result.empty(); ++k) {
    auto map = f->mapData(vff::Plane::kDistance, k);
    if (!map) {
      result = "error " + std::to_string(uint32_t(map.error().code));
      break;
    }
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const size_t t = size_t(j) * m + i;
        const uint32_t code = vff::loadCode(fd.distanceEncoding, *map, m, i, j);
        const vff::Texel x = vff::decodeDistance(fd.distanceEncoding, code, fd.sphere.radius, cosines.empty() ? 1.0f : cosines[t]);
        const float v = fd.distanceEncoding == vff::DistanceEncoding::kBit1 ? 1.0f : x.distance;
        uint32_t bits = kMissBits;
        if (x.hit) std::memcpy(&bits, &v, 4);
        values[t] = bits;  // (a little-endian machine: the bytes are the file's order)
      }
    XXH3_64bits_update(state, values.data(), values.size() * 4);
  }
  if (f->plane(vff::Plane::kNormal).present)
    for (uint32_t k = 0; k < fd.mapCount && result.empty(); ++k) {
      auto map = f->mapData(vff::Plane::kNormal, k);
      if (!map) {
        result = "error " + std::to_string(uint32_t(map.error().code));
        break;
      }
      XXH3_64bits_update(state, map->data(), map->size());
    }
  const vff::LayoutDesc& l = f->layout();
  if (result.empty() && uint64_t(l.sliceWidth) * l.sliceHeight * l.sliceCount <= kMaxSliceTexels)
    for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal}) {
      if (!f->plane(p).present || !result.empty()) continue;
      std::vector<uint8_t> slice(f->sliceBytes(p));
      for (uint32_t s = 0; s < l.sliceCount && result.empty(); ++s) {
        if (vff::Status st = f->readSlice(p, s, slice); !st) {
          result = "error " + std::to_string(uint32_t(st.error().code));
          break;
        }
        XXH3_64bits_update(state, slice.data(), slice.size());
      }
    }
  if (result.empty()) {
    char buf[24];
    std::snprintf(buf, sizeof buf, "ok %016llx", static_cast<unsigned long long>(XXH3_64bits_digest(state)));
    result = buf;
  }
  XXH3_freeState(state);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  std::string missing;
  const std::vector<fs::path> files = vff::fuzz::inputFiles(argc, argv, &missing);
  if (!missing.empty()) {
    std::fprintf(stderr, "vff_fuzz_first_error: %s: no such file or folder\n", missing.c_str());
    return 2;
  }
  for (const fs::path& p : files) {
    const std::vector<uint8_t> bytes = vff::fuzz::fileBytes(p);
    std::printf("%s", p.c_str());
    for (vff::ChecksumPolicy c : {vff::ChecksumPolicy::kVerifyAll, vff::ChecksumPolicy::kLazy, vff::ChecksumPolicy::kNone})
      std::printf("\t%s", outcome(bytes, c).c_str());
    std::printf("\n");
  }
  return files.empty() ? 1 : 0;
}
