// gen_invalid.cpp - the invalid conformance vectors (gen_invalid.h), by validation ID range: 2xxx
// identity, 3xxx header, 4xxx section table and sections, 5xxx field description, 6xxx planes and
// blocks, 7xxx packed layout, 8xxx metadata, 85xx refinement (REFN, format 1.3).
#include "gen_invalid.h"

#include <bit>
#include <functional>
#include <span>
#include <utility>

#include "gen_reference.h"
#include "gen_vff.h"

namespace vff::gen {

namespace {

// Offsets of fields inside the FDSC and LAYT payloads.
constexpr uint64_t kFdscRadius = 12, kFdscScheme = 16, kFdscParam = 20, kFdscMapCount = 24, kFdscDirection = 28,
                   kFdscResolution = 32, kFdscFrame = 36, kFdscEncoding = 40, kFdscMiss = 44, kFdscNormals = 48;
constexpr uint64_t kLaytTarget = 0, kLaytTileSize = 8, kLaytSliceCount = 28;

// The valid vectors the mutations start from, and what each holds.
const char* const A = "u8d-stored";                     // FDSC, LAYT, DIST (1 block of 10 maps)
const char* const Z = "u8d-zstd-normals-meta";          // FDSC, LAYT, META (zstd), DIST, NORM (4 zstd blocks each)
const char* const S = "u8c-stored-normals-3d-gutter1";  // FDSC, LAYT, DIST, NORM (3 stored blocks each)
const char* const M = "u16d-stored-meta-slices";        // FDSC, LAYT, META (stored), DIST
const char* const B = "bit1-stored";
const char* const C = "bc4-zstd-normals-slices";  // FDSC, LAYT, DIST, NORM (bc4-diameter, zstd blocks)
const char* const H = "u8d-zstd-hits-med";        // FDSC, LAYT, DIST (1 zstd block, filter hits-med)
const char* const RF = "u8d-refined";                    // FDSC, LAYT, DIST, REFN (stored, 3 padding bytes)
const char* const RZ = "u8c-zstd-normals-meta-refined";  // FDSC, LAYT, META, DIST, NORM, REFN (zstd)
// The section tags, as short as the base names in the lists below.
constexpr uint32_t D = kTagDistance, F = kTagField, L = kTagLayout, T = kTagMetadata, NM = kTagNormal;

// The invalid vectors made so far, and the ways to make one.
class Mutations {
 public:
  explicit Mutations(const std::map<std::string, BuiltValid>& valid) : valid_(valid) {}

  const BuiltValid& valid(const std::string& name) const { return valid_.at(name); }
  std::vector<InvalidCase> take() { return std::move(out_); }

  // Vector ID/NAME: valid vector `base` changed by `edit` (which re-seals what it means to).
  void add(uint32_t id, std::string name, const std::string& base, std::string mutation,
           const std::function<void(Vff&)>& edit) {
    auto it = valid_.find(base);
    if (it == valid_.end()) die("unknown base vector " + base);
    Vff v{it->second.bytes};
    edit(v);
    out_.push_back({id, std::move(name), base, std::move(mutation), std::move(v.b), it->second.zstd});
  }
  // add(), then every checksum re-sealed.
  void edit(uint32_t id, std::string name, const std::string& base, std::string what, std::function<void(Vff&)> e) {
    add(id, std::move(name), base, std::move(what), [e](Vff& v) {
      e(v);
      v.sealAll();
    });
  }
  // An edit of the FDSC payload (at offset p of the file), re-sealed.
  void fdsc(uint32_t id, std::string name, std::string what, std::function<void(Vff&, uint64_t)> edit,
            const std::string& base = A) {
    add(id, std::move(name), base, std::move(what), [edit](Vff& v) {
      edit(v, v.sec(kTagField));
      v.sealAll();
    });
  }
  // The u32 at offset `at` of the LAYT payload set to `value`, re-sealed.
  void layt(uint32_t id, std::string name, std::string what, uint64_t at, uint32_t value, const std::string& base = A) {
    edit(id, std::move(name), base, std::move(what), [at, value](Vff& f) { st32(f.b, f.sec(kTagLayout) + at, value); });
  }
  // The stored META of M rewritten as `text`.
  void meta(uint32_t id, std::string name, std::string what, std::string text) {
    add(id, std::move(name), M, std::move(what), [text](Vff& v) { v.replaceStored(kTagMetadata, text); });
  }
  // H's one distance block (the file's last bytes) as a hits-med stream changed by `change`, in a new
  // zstd frame: a stream that is not what a writer makes.
  void refilter(uint32_t id, std::string name, std::string what, std::function<void(Bytes&)> change) {
    add(id, std::move(name), H, std::move(what), [change](Vff& v) {
      Bytes stream =
          zstdContent(std::span<const uint8_t>(v.b).subspan(v.block(kTagDistance, 0), v.blockSize(kTagDistance, 0)));
      change(stream);
      v.replaceLastBlock(kTagDistance, zstdFrame(stream));
    });
  }
  // The raw bytes of `base`'s REFN (its last section, decoded when zstd) changed by `change`, then
  // written back with the same codec (a new zstd frame) and every checksum re-sealed.
  void refn(uint32_t id, std::string name, std::string what, std::function<void(Bytes&)> change,
            const std::string& base = RF) {
    add(id, std::move(name), base, std::move(what), [change](Vff& v) {
      const bool zstd = ld16(v.b, v.entry(kTagRefinement) + 32) == 1;
      const auto stored = std::span<const uint8_t>(v.b).subspan(v.sec(kTagRefinement), v.secSize(kTagRefinement));
      Bytes raw = zstd ? zstdContent(stored) : Bytes(stored.begin(), stored.end());
      change(raw);
      const Bytes out = zstd ? zstdFrame(raw) : raw;
      v.replaceLastSection(kTagRefinement, out, raw.size());
    });
  }

 private:
  const std::map<std::string, BuiltValid>& valid_;
  std::vector<InvalidCase> out_;
};

// 2xxx: identity; 3xxx: header.
void addIdentityAndHeader(Mutations& g) {
  g.add(2001, "empty", A, "a zero-byte file", [](Vff& v) { v.b.clear(); });
  g.add(2001, "header-63-bytes", A, "the first 63 bytes of the header", [](Vff& v) { v.b.resize(63); });
  g.add(2002, "magic-byte0", A, "magic byte 0 is 0x88 instead of 0x89", [](Vff& v) { v.b[0] = 0x88; });
  g.add(2003, "major-2", A, "versionMajor 2 (header re-sealed)", [](Vff& v) {
    st16(v.b, 8, 2);
    v.sealHeader();
  });
  g.add(2004, "incompat-bit3", A, "incompatFeatures bit 3 (unknown) set (header re-sealed)", [](Vff& v) {
    st64(v.b, 24, 8);
    v.sealHeader();
  });
  // 3xxx: header
  g.add(3001, "header-size-65", A, "headerSize 65 (header re-sealed)", [](Vff& v) {
    st32(v.b, 12, 65);
    v.sealHeader();
  });
  g.add(3002, "truncated-1", A, "the last byte cut off", [](Vff& v) { v.b.pop_back(); });
  g.add(3002, "appended-1", A, "one zero byte appended", [](Vff& v) { v.b.push_back(0); });
  g.add(3003, "reserved-byte55", A, "header byte 55 (reserved) is 1 (header re-sealed)", [](Vff& v) {
    v.b[55] = 1;
    v.sealHeader();
  });
  g.add(3004, "algorithm-0", A, "checksumAlgorithm 0 (header re-sealed)", [](Vff& v) {
    v.b[54] = 0;
    v.sealHeader();
  });
  g.add(3005, "checksum-flipped", A, "headerChecksum with bit 0 flipped", [](Vff& v) { v.b[56] ^= 1; });
  g.add(3005, "table-edit-unsealed", A, "DIST entry checksum changed, header checksum left stale",
        [&](Vff& v) { v.b[v.entry(D) + 40] ^= 1; });
  g.add(3006, "table-past-eof", A, "sectionTableOffset at the end of the file",
        [](Vff& v) { st64(v.b, 40, v.b.size()); });
  g.add(3007, "count-0", A, "sectionCount 0 (header re-sealed)", [](Vff& v) {
    st32(v.b, 48, 0);
    v.sealHeader();
  });
}

// 4xxx: section table and sections.
void addSections(Mutations& g) {
  g.add(4001, "dist-past-eof", A, "DIST storedSize/rawSize 4096 bytes longer than the file has", [&](Vff& v) {
    st64(v.b, v.entry(D) + 16, v.secSize(D) + 4096);
    st64(v.b, v.entry(D) + 24, v.secSize(D));
    v.sealHeader();
  });
  g.add(4002, "layt-misaligned", A, "LAYT moved 64 bytes down to offset 8128", [&](Vff& v) {
    const uint64_t off = v.sec(L);
    std::copy_n(v.b.begin() + std::ptrdiff_t(off), 64, v.b.begin() + std::ptrdiff_t(off - 64));
    std::fill_n(v.b.begin() + std::ptrdiff_t(off), 64, 0);
    st64(v.b, v.entry(L) + 8, off - 64);
    v.sealAll();
  });
  g.add(4003, "layt-overlaps-fdsc", A, "LAYT offset set to FDSC's (4096); the old LAYT bytes zeroed", [&](Vff& v) {
    std::fill_n(v.b.begin() + std::ptrdiff_t(v.sec(L)), 64, 0);
    st64(v.b, v.entry(L) + 8, v.sec(F));
    v.sealAll();
  });
  g.add(4004, "unknown-required", A, "an unknown section 'XREQ' with flags REQUIRED appended", [](Vff& v) {
    const uint8_t data[16] = {1, 2, 3, 4};
    v.appendSection(fourcc('X', 'R', 'E', 'Q'), kSectionRequired, data);
  });
  g.add(4005, "duplicate-layt", A, "a second LAYT section appended", [&](Vff& v) {
    const Bytes layt(v.b.begin() + std::ptrdiff_t(v.sec(L)), v.b.begin() + std::ptrdiff_t(v.sec(L) + 64));
    v.appendSection(kTagLayout, kSectionRequired, layt);
  });
  g.add(4006, "missing-dist", A, "the DIST entry and its bytes removed", [&](Vff& v) { v.removeSection(D); });
  g.add(4007, "layt-codec-7", A, "LAYT codec 7 (unknown)", [&](Vff& v) {
    st16(v.b, v.entry(L) + 32, 7);
    v.sealAll();
  });
  g.add(4008, "layt-checksum", A, "LAYT checksum with bit 0 flipped (header re-sealed)", [&](Vff& v) {
    v.b[v.entry(L) + 40] ^= 1;
    v.sealHeader();
  });
  g.add(4008, "dist-stale-after-block-edit", A,
        "a DIST block byte changed and its block checksum re-sealed, the section checksum left stale", [&](Vff& v) {
          v.b[v.block(D, 0) + 100] ^= 0x5A;
          v.sealBlocks();
          v.sealHeader();
        });
  g.add(4009, "entry-reserved", A, "DIST entry reserved u32 at +36 is 1", [&](Vff& v) {
    st32(v.b, v.entry(D) + 36, 1);
    v.sealAll();
  });
  g.add(4010, "fdsc-60-bytes", A, "FDSC storedSize and rawSize 60", [&](Vff& v) {
    st64(v.b, v.entry(F) + 16, 60);
    st64(v.b, v.entry(F) + 24, 60);
    v.sealAll();
  });
  g.add(4011, "meta-raw-size", Z, "zstd META with rawSize one more than its frame declares", [&](Vff& v) {
    st64(v.b, v.entry(T) + 24, ld64(v.b, v.entry(T) + 24) + 1);
    v.sealAll();
  });
  g.add(4012, "after-table", A, "a nonzero byte in the padding after the section table (no checksum covers it)",
        [](Vff& v) { v.b[1000] = 1; });
  g.add(4012, "in-plane-section", Z, "a nonzero byte between the DIST block index and the first block (re-sealed)",
        [&](Vff& v) {
          const uint64_t indexEnd = v.sec(D) + kPlaneHeaderSize + uint64_t(v.blockCount(D)) * kBlockEntrySize;
          if (v.block(D, 0) <= indexEnd) die("in-plane-section: no gap after the block index");
          v.b[indexEnd] = 1;
          v.sealAll();
        });
  g.add(4013, "layt-version-2", A, "LAYT sectionVersion 2", [&](Vff& v) {
    st16(v.b, v.entry(L) + 34, 2);
    v.sealAll();
  });
  g.add(4014, "meta-above-limit", Z, "zstd META with rawSize 64 MiB + 1, above the default section limit", [&](Vff& v) {
    st64(v.b, v.entry(T) + 24, (uint64_t{64} << 20) + 1);
    v.sealAll();
  });
}

// 5xxx: field description (each edit re-seals).
void addFieldDescription(Mutations& g) {
  g.fdsc(5001, "radius-nan", "sphere radius NaN", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscRadius, 0x7FC00000u); });
  g.fdsc(5002, "scheme-0", "positionScheme 0 (invalid)", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscScheme, 0); });
  g.fdsc(5003, "map-count-11", "mapCount 11 where octa-hemi2 n=1 yields 10",
         [](Vff& v, uint64_t p) { st32(v.b, p + kFdscMapCount, 11); });
  g.fdsc(5004, "direction-3", "directionScheme 3 (unknown)",
         [](Vff& v, uint64_t p) { st32(v.b, p + kFdscDirection, 3); });
  g.fdsc(
      5005, "bit1-resolution-12", "bit1 with mapResolution 12 (not a multiple of 8)",
      [](Vff& v, uint64_t p) { st32(v.b, p + kFdscResolution, 12); }, B);
  g.fdsc(5006, "frame-2", "frame convention 2 (unknown)", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscFrame, 2); });
  g.fdsc(5007, "encoding-6", "distanceEncoding 6 (unknown)",
         [](Vff& v, uint64_t p) { st32(v.b, p + kFdscEncoding, 6); });
  g.fdsc(
      5005, "bc4-resolution-18", "bc4-diameter with mapResolution 18 (not a multiple of 4)",
      [](Vff& v, uint64_t p) { st32(v.b, p + kFdscResolution, 18); }, C);
  g.fdsc(5008, "miss-code-0", "unorm8-diameter with missCode 0 (255 is reserved)",
         [](Vff& v, uint64_t p) { st32(v.b, p + kFdscMiss, 0); });
  g.fdsc(5009, "normal-encoding-2", "normalEncoding 2 (unknown)",
         [](Vff& v, uint64_t p) { st32(v.b, p + kFdscNormals, 2); });
  g.fdsc(5010, "reserved-52", "FDSC reserved u32 at 52 is 1", [](Vff& v, uint64_t p) { st32(v.b, p + 52, 1); });
  g.fdsc(5011, "payload-above-limit",
         "fibonacci n=1000, unorm16 4096x4096 maps with normals: 100 GB of payload, above the default 64 GiB",
         [](Vff& v, uint64_t p) {
           st32(v.b, p + kFdscScheme, uint32_t(PositionScheme::kSphericalFibonacci));
           st32(v.b, p + kFdscParam, 1000);
           st32(v.b, p + kFdscMapCount, 1000);
           st32(v.b, p + kFdscResolution, 4096);
           st32(v.b, p + kFdscEncoding, uint32_t(DistanceEncoding::kUnorm16Diameter));
           st32(v.b, p + kFdscMiss, 65535);
           st32(v.b, p + kFdscNormals, uint32_t(NormalEncoding::kOctSnorm16));
         });
}

// 6xxx: planes and blocks (each edit re-seals unless it is about a checksum).
void addPlanesAndBlocks(Mutations& g) {
  g.edit(6001, "map-count", A, "DIST plane header mapCount 11", [&](Vff& v) { st32(v.b, v.sec(D), 11); });
  g.edit(6002, "encoding-without-norm", A, "FDSC normalEncoding oct-snorm16 without a NORM section",
         [&](Vff& v) { st32(v.b, v.sec(F) + kFdscNormals, 1); });
  g.edit(6003, "block-past-section", A, "DIST block 0 offset past the section end",
         [&](Vff& v) { st64(v.b, v.blockEntry(D, 0), v.secSize(D) + 64); });
  g.edit(6004, "block-misaligned", S, "DIST block 1 offset moved by 32 bytes",
         [&](Vff& v) { st64(v.b, v.blockEntry(D, 1), v.blockRel(D, 1) + 32); });
  g.edit(6005, "blocks-overlap", S, "DIST block 1 offset equal to block 0's",
         [&](Vff& v) { st64(v.b, v.blockEntry(D, 1), v.blockRel(D, 0)); });
  g.edit(6006, "raw-size", Z, "zstd DIST block 0 rawSize 64 bytes too large",
         [&](Vff& v) { st32(v.b, v.blockEntry(D, 0) + 16, ld32(v.b, v.blockEntry(D, 0) + 16) + 64); });
  g.edit(6007, "codec-2", A, "DIST block 0 codec 2 (unknown)", [&](Vff& v) { v.b[v.blockEntry(D, 0) + 20] = 2; });
  g.edit(6008, "filter-2", H, "DIST block 0 filter 2 (unknown)", [&](Vff& v) { v.b[v.blockEntry(D, 0) + 21] = 2; });
  g.edit(6008, "filter-on-stored-block", A, "DIST block 0 (stored) with filter 1 hits-med, filters bit set",
         [&](Vff& v) {
           v.b[v.blockEntry(D, 0) + 21] = 1;
           st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
         });
  g.edit(6008, "filter-on-normals", Z, "NORM block 0 (zstd) with filter 1 hits-med, filters bit set", [&](Vff& v) {
    v.b[v.blockEntry(NM, 0) + 21] = 1;
    st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
  });
  g.edit(6008, "filter-on-unorm16", "u16d-zstd-normals-gutter2",
         "unorm16-diameter DIST block 0 (zstd) with filter 1 hits-med, filters bit set", [&](Vff& v) {
           if (v.b[v.blockEntry(D, 0) + 20] != 1) die("filter-on-unorm16: DIST block 0 is not zstd");
           v.b[v.blockEntry(D, 0) + 21] = 1;
           st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
         });
  g.add(6009, "checksum-field", A, "DIST block 0 checksum bit 0 flipped (section and header re-sealed)", [&](Vff& v) {
    v.b[v.blockEntry(D, 0) + 24] ^= 1;
    v.sealSections();
    v.sealHeader();
  });
  g.add(6009, "data-unsealed", A, "a DIST block byte changed, block checksum left stale (section, header re-sealed)",
        [&](Vff& v) {
          v.b[v.block(D, 0) + 100] ^= 0x5A;
          v.sealSections();
          v.sealHeader();
        });
  g.edit(6010, "not-a-zstd-frame", Z, "zstd DIST block 0 with a broken frame magic (checksums re-sealed)",
         [&](Vff& v) { v.b[v.block(D, 0)] ^= 0xFF; });
  g.edit(6010, "trailing-byte", Z, "a zstd DIST block whose storedSize takes one padding byte after its frame",
         [&](Vff& v) {
           for (uint32_t i = 0; i + 1 < v.blockCount(D); ++i) {
             const uint64_t end = v.blockRel(D, i) + v.blockSize(D, i);
             if (v.b[v.blockEntry(D, i) + 20] == 1 && end % kBlockAlignment != 0) {
               st64(v.b, v.blockEntry(D, i) + 8, v.blockSize(D, i) + 1);
               return;
             }
           }
           die("trailing-byte: no zstd block with a gap after it");
         });
}

// 6xxx, continued: hits-med streams that are not what a writer makes, feature bits, a reserved byte and
// a normal where the distance is a miss.
void addFiltersAndFeatures(Mutations& g) {
  const uint64_t hMaskBytes = g.valid(H).content.distance.size() / 8;
  g.refilter(6010, "hits-med-missing-residual", "hits-med stream without its last residual",
             [](Bytes& s) { s.pop_back(); });
  g.refilter(6010, "hits-med-extra-residual", "hits-med stream with one residual more than the mask has hits",
             [](Bytes& s) { s.push_back(0); });
  g.refilter(6010, "hits-med-hit-decodes-to-miss",
             "the first residual changed so that the first hit decodes to 255, the miss code", [&](Bytes& s) {
               const Bytes& raw = g.valid(H).content.distance;
               const uint32_t m = g.valid(H).c.field.mapResolution;
               for (uint32_t t = 0; t < m * m; ++t)
                 if (raw[t] != 255) {
                   s[hMaskBytes] = uint8_t(255 - hitsMedPrediction(raw.data(), m, t % m, t / m, 0));
                   return;
                 }
               die("hits-med-hit-decodes-to-miss: map 0 has no hit");
             });
  g.refilter(6010, "hits-med-frame-too-large",
             "the zstd frame declares rawSize + rawSize/8 + 1 bytes, one more than any hits-med stream of the block",
             [&](Bytes& s) { s.resize(g.valid(H).content.distance.size() + hMaskBytes + 1, 0); });
  g.edit(6012, "filter-without-feature-bit", H, "a filtered block, incompatFeatures filters bit (1) clear",
         [&](Vff& v) { st64(v.b, 24, kFeatureZstd); });
  g.edit(6011, "reserved", A, "DIST block entry reserved byte 22 is 1",
         [&](Vff& v) { v.b[v.blockEntry(D, 0) + 22] = 1; });
  g.edit(6012, "zstd-without-feature-bit", Z, "zstd sections and blocks, incompatFeatures zstd bit clear",
         [&](Vff& v) { st64(v.b, 24, 0); });
  g.edit(6012, "bc4-without-feature-bit", C, "bc4-diameter field, incompatFeatures bit 2 (bc4) clear",
         [&](Vff& v) { st64(v.b, 24, ld64(v.b, 24) & ~kFeatureBc4); });
  g.edit(6008, "filter-on-bc4", C, "bc4-diameter DIST block 0 (zstd) with filter 1 hits-med, filters bit set",
         [&](Vff& v) {
           if (v.b[v.blockEntry(D, 0) + 20] != 1) die("filter-on-bc4: DIST block 0 is not zstd");
           v.b[v.blockEntry(D, 0) + 21] = 1;
           st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
         });
  g.edit(6013, "normal-of-miss", S, "a nonzero normal at a texel whose distance is a miss", [&](Vff& v) {
    const uint64_t dist = v.block(D, 0), norm = v.block(NM, 0);
    for (uint32_t t = 0; t < 64; ++t)
      if (v.b[dist + t] == 255) {
        v.b[norm + 4 * t + 3] = 0x40;
        return;
      }
    die("normal-of-miss: map 0 has no miss");
  });
}

// 7xxx: packed layout; 8xxx: metadata (stored META rewritten).
void addLayoutAndMetadata(Mutations& g) {
  g.layt(7001, "target-0", "LAYT target 0 (invalid)", kLaytTarget, 0);
  g.layt(7002, "tile-size", "LAYT tileSize 9 for 8x8 maps without gutter", kLaytTileSize, 9);
  g.layt(7003, "slice-count", "LAYT sliceCount 2 where 1 holds every map", kLaytSliceCount, 2);
  g.layt(7004, "reserved-40", "LAYT reserved u32 at 40 is 1", 40, 1);
  g.layt(7001, "bc4-target-3d", "bc4-diameter field with LAYT target 2 (3d)", kLaytTarget, 2, C);
  g.edit(7002, "bc4-gutter-1", C, "bc4-diameter field with LAYT gutter 1 and tileSize 18", [&](Vff& f) {
    st32(f.b, f.sec(kTagLayout) + 4, 1);
    st32(f.b, f.sec(kTagLayout) + kLaytTileSize, 18);
  });
  g.meta(8001, "invalid-utf8", "metadata with the invalid UTF-8 sequence C3 28 in a string", "{\"a\":\"\xC3\x28\"}");
  g.meta(8001, "too-deep", "metadata nesting 65 levels (the reader's limit is 64)",
         "{\"a\":" + std::string(64, '[') + std::string(64, ']') + "}");
  g.meta(8001, "trailing-nul", "metadata '{\"a\":1}' followed by a NUL byte and 'garbage'",
         std::string("{\"a\":1}\0garbage", 15));
  g.meta(8001, "trailing-zeros", "metadata '{\"a\":1}' followed by four zero bytes (META has no padding)",
         std::string("{\"a\":1}\0\0\0\0", 11));
  g.meta(8001, "trailing-value", "metadata '{\"a\":1}{}' (a second value after the first)", "{\"a\":1}{}");
  g.meta(8001, "byte-order-mark", "metadata '{\"a\":1}' after a UTF-8 byte-order mark EF BB BF",
         "\xEF\xBB\xBF{\"a\":1}");
  g.meta(8001, "lone-high-surrogate", "metadata '{\"a\":\"\\ud800\"}' (a high surrogate escape alone)",
         R"({"a":"\ud800"})");
  g.meta(8001, "lone-low-surrogate", "metadata '{\"a\":\"\\udc00\\ud800\"}' (a low surrogate escape first)",
         R"({"a":"\udc00\ud800"})");
  g.meta(8002, "array", "metadata '[1,2]' (valid JSON, not an object)", "[1,2]");
}

// 85xx: REFN (format 1.3), changed inside its raw bytes (re-compressed when zstd) and re-sealed.
void addRefinement(Mutations& g) {
  const FieldDesc& f = g.valid(RF).c.field;
  const uint64_t texels = uint64_t(f.mapCount) * f.mapResolution * f.mapResolution;
  const uint64_t unsureBytes = (texels + 7) / 8;
  if (texels % 8 == 0 || unsureBytes % 4 == 0) die(std::string(RF) + ": needs unused bits and padding after them");
  // Offsets inside REFN's raw bytes: the positions start after the bits and padding; the indices end it.
  const auto positionsAt = [](const Bytes& raw) { return raw.size() - 12 * uint64_t(ld32(raw, 4)) - 12 * uint64_t(ld32(raw, 8)); };
  const auto setF32 = [](Bytes& raw, uint64_t at, float value) { st32(raw, at, std::bit_cast<uint32_t>(value)); };

  g.refn(8501, "header-size-63", "REFN headerSize 63", [](Bytes& r) { st32(r, 0, 63); });
  g.refn(8501, "vertex-count-2", "REFN vertexCount 2 (the section's size left as it was)", [](Bytes& r) { st32(r, 4, 2); });
  g.refn(8501, "triangle-count-0", "REFN triangleCount 0 (the section's size left as it was)",
         [](Bytes& r) { st32(r, 8, 0); });
  g.refn(8501, "margin-negative", "REFN margin -0.1875", [&](Bytes& r) { setF32(r, 12, -0.1875f); });
  g.refn(8501, "margin-nan", "REFN margin NaN", [](Bytes& r) { st32(r, 12, 0x7FC00000u); });
  g.refn(8501, "margin-infinity", "REFN margin +infinity", [](Bytes& r) { st32(r, 12, 0x7F800000u); });
  g.refn(8501, "reserved-byte-20", "REFN header byte 20 (reserved) is 1", [](Bytes& r) { r[20] = 1; });
  g.refn(8501, "reserved-byte-63", "REFN header byte 63 (reserved) is 1", [](Bytes& r) { r[63] = 1; });
  g.refn(8501, "raw-size-plus-4", "4 zero bytes appended to REFN: rawSize 64 + U + P + 12V + 12T + 4",
         [](Bytes& r) { r.insert(r.end(), 4, 0); });
  g.refn(8501, "raw-size-minus-4", "REFN's last 4 bytes (the last index) cut off: rawSize 64 + U + P + 12V + 12T - 4",
         [](Bytes& r) { r.resize(r.size() - 4); });
  g.refn(8501, "header-60-bytes", "REFN cut to 60 bytes, less than its header", [](Bytes& r) { r.resize(60); });
  g.add(8501, "bit1-field", B,
        "a REFN section (margin 0.1875, the silhouette texels, an octahedron) appended to a bit1 field, "
        "versionMinor 3",
        [&](Vff& v) {
          const BuiltValid& base = g.valid(B);
          const Refinement r = makeRefinementSource(base.c.field, base.content, 0.1875f, 0);
          v.appendSection(kTagRefinement, 0, referenceRefinementBytes(base.c.field, r));
          st16(v.b, 10, 3);
          v.sealHeader();
        });
  g.refn(
      8501, "zstd-vertex-count-2", "zstd REFN with vertexCount 2 (re-compressed)", [](Bytes& r) { st32(r, 4, 2); },
      RZ);

  g.refn(8502, "count-plus-1", "REFN unsureTexels one more than the bits set",
         [](Bytes& r) { st32(r, 16, ld32(r, 16) + 1); });
  g.refn(8502, "bit-past-last-texel",
         "the bit of texel " + std::to_string(texels) + " set, past the last texel (" + std::to_string(texels - 1) +
             "); unsureTexels unchanged",
         [&](Bytes& r) { r[64 + texels / 8] = uint8_t(r[64 + texels / 8] | 1u << (texels % 8)); });
  g.refn(8502, "padding-byte", "REFN's last padding byte (before the positions) is 1",
         [&](Bytes& r) { r[positionsAt(r) - 1] = 1; });
  g.refn(
      8502, "zstd-count-minus-1", "zstd REFN with unsureTexels one less than the bits set (re-compressed)",
      [](Bytes& r) { st32(r, 16, ld32(r, 16) - 1); }, RZ);

  g.refn(8503, "index-out-of-range", "REFN's last index is vertexCount",
         [](Bytes& r) { st32(r, r.size() - 4, ld32(r, 4)); });
  g.refn(8503, "vertex-outside-sphere",
         "REFN vertex 0 at C + (1.0002 R, 0, 0), beyond the sphere's tolerance (1 + 1e-4) R + 1e-6", [&](Bytes& r) {
           const uint64_t p = positionsAt(r);
           setF32(r, p, float(double(f.sphere.center[0]) + 1.0002 * double(f.sphere.radius)));
           setF32(r, p + 4, f.sphere.center[1]);
           setF32(r, p + 8, f.sphere.center[2]);
         });
  g.refn(8503, "position-nan", "REFN: the y of vertex 2 is NaN",
         [&](Bytes& r) { st32(r, positionsAt(r) + 12 * 2 + 4, 0x7FC00000u); });
  g.refn(8503, "position-infinity", "REFN: the z of vertex 5 is +infinity",
         [&](Bytes& r) { st32(r, positionsAt(r) + 12 * 5 + 8, 0x7F800000u); });
  g.refn(
      8503, "zstd-index-out-of-range", "zstd REFN whose first index is vertexCount (re-compressed)",
      [&](Bytes& r) { st32(r, positionsAt(r) + 12 * uint64_t(ld32(r, 4)), ld32(r, 4)); }, RZ);

  // The section table and codec, for REFN.
  g.edit(4009, "refn-copy-safe", RF, "REFN flags 2 (COPY_SAFE) where the spec gives 0",
         [&](Vff& v) { st32(v.b, v.entry(kTagRefinement) + 4, kSectionCopySafe); });
  g.edit(4011, "refn-raw-size", RZ, "zstd REFN with rawSize 4 more than its frame declares", [&](Vff& v) {
    if (ld16(v.b, v.entry(kTagRefinement) + 32) != 1) die("refn-raw-size: REFN is not zstd");
    st64(v.b, v.entry(kTagRefinement) + 24, ld64(v.b, v.entry(kTagRefinement) + 24) + 4);
  });
}

}  // namespace

std::vector<InvalidCase> invalidCases(const std::map<std::string, BuiltValid>& valid) {
  Mutations g(valid);
  addIdentityAndHeader(g);
  addSections(g);
  addFieldDescription(g);
  addPlanesAndBlocks(g);
  addFiltersAndFeatures(g);
  addLayoutAndMetadata(g);
  addRefinement(g);
  std::vector<InvalidCase> out = g.take();
  // The reference decoder of REFN (gen_reference.h, from the spec's text) raises each 85xx vector's ID.
  for (const InvalidCase& c : out) {
    if (c.id / 100 != 85) continue;
    const Vff v{c.bytes};
    const uint64_t e = v.entry(kTagRefinement);
    const auto stored = std::span<const uint8_t>(v.b).subspan(v.sec(kTagRefinement), v.secSize(kTagRefinement));
    const Bytes raw = ld16(v.b, e + 32) == 1 ? zstdContent(stored) : Bytes(stored.begin(), stored.end());
    ReferenceRefinement ref;
    std::string why;
    const uint32_t id = referenceDecodeRefinement(valid.at(c.base).c.field, raw, &ref, &why);
    if (id != c.id)
      fail("invalid/" + std::to_string(c.id) + "/" + c.name + ": the reference REFN decoder gives " +
           std::to_string(id) + (id ? " (" + why + ")" : ""));
  }
  return out;
}

}  // namespace vff::gen
