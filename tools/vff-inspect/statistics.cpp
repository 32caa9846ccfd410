// statistics.cpp - hit ratio and distance histogram over the maps of the distance plane (all of
// them, or a partial result's range: its other maps are fillers, not the field's).
//
// Speed: the plane is read block by block (zero-copy views for stored blocks; compressed blocks are
// decoded into one reusable buffer, so a large zstd file does not fill the reader's cache). For the
// diameter encodings only a table of code counts is built per texel (256 or 65536 counters), and
// the codes are turned into distances once per code; unorm8-chord, whose distance depends on the
// texel's direction, decodes each hit with a per-texel cosine table.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <memory>
#include <new>

#include "inspect.h"
#include "vff/bc4.h"
#include "vff/direction.h"
#include "vff/encoding.h"
#include "vff/format.h"

namespace vff::inspect {

namespace {

// The bin of a hit distance: floor(d / 2R * bins), clamped to [0, bins - 1].
uint32_t binOf(double distance, double diameter, uint32_t bins) {
  const double f = distance / diameter * bins;
  if (!(f > 0)) return 0;
  return f >= bins ? bins - 1 : static_cast<uint32_t>(f);
}

}  // namespace

Result<DistanceStats> distanceStats(const File& file, uint32_t bins, bool skipBadBlocks, MapSpan maps) {
  const FieldDesc& field = file.field();
  const PlaneInfo& plane = file.plane(Plane::kDistance);
  const DistanceEncoding enc = field.distanceEncoding;
  const uint32_t m = field.mapResolution;
  const uint64_t texelsPerMap = uint64_t{m} * m;
  const float radius = field.sphere.radius;
  const double diameter = 2.0 * double(radius);

  DistanceStats st;
  if (enc != DistanceEncoding::kBit1) st.bins.assign(std::max(bins, 1u), 0);

  // unorm8 / unorm16 diameter: counts per code.
  std::vector<uint64_t> codeCounts;
  if (enc == DistanceEncoding::kUnorm8Diameter || enc == DistanceEncoding::kBc4Diameter) codeCounts.assign(256, 0);
  if (enc == DistanceEncoding::kUnorm16Diameter) codeCounts.assign(65536, 0);
  // unorm8 chord: cos(alpha) per texel.
  std::vector<float> cosAlpha;
  if (enc == DistanceEncoding::kUnorm8Chord) {
    cosAlpha.resize(texelsPerMap);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) cosAlpha[uint64_t{j} * m + i] = texelDirection(field.directionScheme, m, i, j).z;
  }
  const uint32_t miss = missCode(enc);

  // Not zero-filled: File::decodeBlock rejects a frame that cannot hold rawSize bytes before writing,
  // so a block that claims gigabytes costs address space, not memory.
  std::unique_ptr<uint8_t[]> scratch;
  uint64_t scratchSize = 0;
  for (uint32_t b = 0; b < plane.blocks.size(); ++b) {
    const BlockInfo& blk = plane.blocks[b];
    // The block's maps within `maps`; a block with none is not read.
    const uint32_t first = std::max(blk.firstMap, maps.begin);
    const uint32_t last = uint32_t(std::min<uint64_t>(uint64_t{blk.firstMap} + blk.mapCount, maps.end));
    if (first >= last) continue;
    const uint32_t mapsHere = last - first;
    std::span<const uint8_t> data;
    if (blk.codec == Codec::kStored) {
      auto view = file.blockData(Plane::kDistance, b);
      if (!view) {
        if (!skipBadBlocks) return std::move(view).error();
        ++st.unreadableBlocks;
        continue;
      }
      data = *view;
    } else {
      if (blk.rawSize > scratchSize) {
        scratch.reset(new (std::nothrow) uint8_t[blk.rawSize]);
        scratchSize = scratch ? blk.rawSize : 0;
        if (!scratch) return makeError(Code::kOutOfMemory, "cannot allocate a decoded block", kTagDistance, blk.offset);
      }
      Status s = file.decodeBlock(Plane::kDistance, b, std::span<uint8_t>(scratch.get(), blk.rawSize));
      if (!s) {
        if (!skipBadBlocks) return std::move(s).error();
        ++st.unreadableBlocks;
        continue;
      }
      data = std::span<const uint8_t>(scratch.get(), blk.rawSize);
    }
    const uint64_t mapBytes = distanceMapBytes(enc, m);
    if (data.size() >= uint64_t{blk.mapCount} * mapBytes)
      data = data.subspan(uint64_t{first - blk.firstMap} * mapBytes, uint64_t{mapsHere} * mapBytes);
    const uint64_t blockTexels = texelsPerMap * mapsHere;
    st.texels += blockTexels;

    switch (enc) {
      case DistanceEncoding::kUnorm8Diameter: {
        // Four sub-tables break the store-to-load dependency on runs of equal codes.
        std::array<std::array<uint32_t, 256>, 4> t{};
        size_t k = 0;
        for (; k + 4 <= data.size(); k += 4) {
          ++t[0][data[k]];
          ++t[1][data[k + 1]];
          ++t[2][data[k + 2]];
          ++t[3][data[k + 3]];
        }
        for (; k < data.size(); ++k) ++t[0][data[k]];
        for (int c = 0; c < 256; ++c) codeCounts[c] += uint64_t{t[0][c]} + t[1][c] + t[2][c] + t[3][c];
        break;
      }
      case DistanceEncoding::kUnorm16Diameter:
        for (size_t k = 0; k + 1 < data.size(); k += 2) ++codeCounts[data[k] | (uint32_t{data[k + 1]} << 8)];
        break;
      case DistanceEncoding::kBc4Diameter: {  // the codes the blocks decode to
        uint8_t codes[16];
        for (size_t k = 0; k + kBc4BlockBytes <= data.size(); k += kBc4BlockBytes) {
          decodeBc4Block(&data[k], codes);
          for (uint8_t c : codes) ++codeCounts[c];
        }
        break;
      }
      case DistanceEncoding::kUnorm8Chord:
        for (uint64_t k = 0; k < data.size(); ++k) {
          const uint32_t code = data[k];
          if (code == miss) {
            ++st.misses;
            continue;
          }
          const Texel t = decodeDistance(enc, code, radius, cosAlpha[k % texelsPerMap]);
          ++st.hits;
          ++st.bins[binOf(t.distance, diameter, bins)];
        }
        break;
      case DistanceEncoding::kBit1:
        if (texelsPerMap % 8 == 0) {
          uint64_t hits = 0;
          for (uint8_t byte : data) hits += static_cast<uint64_t>(std::popcount(byte));
          st.hits += hits;
          st.misses += blockTexels - hits;
        } else {
          for (uint32_t k = 0; k < mapsHere; ++k) {
            const auto map = data.subspan(k * mapBytes, mapBytes);
            for (uint32_t j = 0; j < m; ++j)
              for (uint32_t i = 0; i < m; ++i) {
                if (loadCode(enc, map, m, i, j) != 0)
                  ++st.hits;
                else
                  ++st.misses;
              }
          }
        }
        break;
      default:
        return makeError(Code::kDistanceEncoding, "unknown distance encoding", kTagField);
    }
  }

  // Turn code counts into hits, misses and bins.
  for (uint32_t c = 0; c < codeCounts.size(); ++c) {
    const uint64_t n = codeCounts[c];
    if (n == 0) continue;
    if (c == miss) {
      st.misses += n;
      continue;
    }
    const Texel t = decodeDistance(enc, c, radius, 1.0f);
    st.hits += n;
    st.bins[binOf(t.distance, diameter, bins)] += n;
  }
  return st;
}

std::optional<PartialInfo> partialInfo(const File& file) {
  const std::string_view text = file.metadata();
  const nlohmann::json meta = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (!meta.is_object() || !meta.contains("vff.partial")) return std::nullopt;
  PartialInfo info;
  const nlohmann::json& p = meta["vff.partial"];
  auto u32 = [&](const char* k) {
    return p.contains(k) && p[k].is_number_unsigned() && p[k].get<uint64_t>() <= UINT32_MAX;
  };
  if (!p.is_object() || !u32("mapBegin") || !u32("mapEnd") || !u32("mapCount")) return info;
  const uint32_t begin = p["mapBegin"], end = p["mapEnd"], count = p["mapCount"];
  if (begin < end && end <= count && count == file.field().mapCount) info = PartialInfo{{begin, end}, true};
  return info;
}

}  // namespace vff::inspect
