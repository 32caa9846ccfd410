// The robustness suite: hostile variations of every valid conformance vector (one ctest case per
// vector, found by listing spec/conformance/valid/ when the program starts).
//
// Each vector is cut at prefix lengths and has single bytes changed (XOR 0xFF and XOR 0x01). Every
// variant goes through File::openMemory under each checksum policy (and, when it opens, every block,
// map and slice is read) and through vff::validate. Every outcome must be a success or an error with a
// file-problem code (2xxx..8xxx; never kOk in an error, never a 9xxx code), and:
//   - a truncated file fails to open with 2001 (shorter than the header) or 3002 (fileSize);
//   - the validator rejects every variant: each byte is header, section table, section bytes (all
//     checksummed) or padding (which must be zero);
//   - kVerifyAll rejects at open every change inside checksummed bytes (everything but padding);
//   - kLazy rejects at open every change to the header, the table or a non-plane section, and at open
//     or on first read every change to a plane's header, block index or blocks.
// By default the offsets are sampled: every byte of the header, table, non-plane sections, plane
// headers and block indexes; the first and last 16 bytes of each block and every 3rd byte between;
// the ends, middle and every 251st byte of each stretch of padding. Set VFF_ROBUSTNESS_EXHAUSTIVE=1
// to try every offset.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "conformance.h"
#include "vff/vff.h"

namespace fs = std::filesystem;

namespace vff {
namespace {

const fs::path kDir = VFF_CONFORMANCE_DIR;

using conformance::readBytes;

struct Vector {
  std::string name;
  fs::path path;
};
void PrintTo(const Vector& v, std::ostream* os) {
  *os << fs::relative(v.path, kDir).generic_string();
}

std::vector<Vector> listValid() {
  std::vector<Vector> out;
  std::error_code ec;
  for (fs::directory_iterator it(kDir / "valid", ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file() || it->path().extension() != ".vff") continue;
    std::string name = it->path().stem().string();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    out.push_back({name, it->path()});
  }
  std::sort(out.begin(), out.end(), [](const Vector& a, const Vector& b) { return a.name < b.name; });
  return out;
}

// What a byte of the original file is.
enum class Kind : uint8_t {
  kHeader,      // bytes 0..63
  kTable,       // the section table
  kSection,     // a non-plane section's stored bytes (FDSC, LAYT, META, unknown)
  kPlaneIndex,  // a plane section's header and block index
  kBlock,       // a block's stored bytes
  kPlaneGap,    // alignment padding inside a plane section (only the section checksum covers it)
  kPadding,     // between sections (no checksum covers it)
};
const char* kindName(Kind k) {
  static const char* kNames[] = {"header", "table", "section", "plane-index", "block", "plane-gap", "padding"};
  return kNames[size_t(k)];
}

struct Region {
  uint64_t begin, end;
  Kind kind;
};

// The file's regions, from the structure libvff reports for the intact file.
std::vector<Region> regionsOf(const File& f, std::span<const uint8_t> b) {
  std::vector<Region> r;
  uint64_t table = 0;
  for (int i = 7; i >= 0; --i) table = table << 8 | b[40 + size_t(i)];
  r.push_back({0, kHeaderSize, Kind::kHeader});
  r.push_back({table, table + f.info().sections.size() * kSectionEntrySize, Kind::kTable});
  for (const SectionInfo& s : f.info().sections) {
    const bool plane = s.tag == kTagDistance || s.tag == kTagNormal;
    if (!plane) {
      r.push_back({s.offset, s.offset + s.storedSize, Kind::kSection});
      continue;
    }
    const PlaneInfo& pi = f.plane(s.tag == kTagDistance ? Plane::kDistance : Plane::kNormal);
    uint64_t at = s.offset + kPlaneHeaderSize + pi.blocks.size() * kBlockEntrySize;
    r.push_back({s.offset, at, Kind::kPlaneIndex});
    for (const BlockInfo& blk : pi.blocks) {
      if (blk.offset > at) r.push_back({at, blk.offset, Kind::kPlaneGap});
      r.push_back({blk.offset, blk.offset + blk.storedSize, Kind::kBlock});
      at = blk.offset + blk.storedSize;
    }
    if (at < s.offset + s.storedSize) r.push_back({at, s.offset + s.storedSize, Kind::kPlaneGap});
  }
  std::sort(r.begin(), r.end(), [](const Region& a, const Region& c) { return a.begin < c.begin; });
  std::vector<Region> all;
  uint64_t pos = 0;
  for (const Region& x : r) {
    if (x.begin > pos) all.push_back({pos, x.begin, Kind::kPadding});
    if (x.end > x.begin) all.push_back(x);
    pos = std::max(pos, x.end);
  }
  if (pos < b.size()) all.push_back({pos, b.size(), Kind::kPadding});
  return all;
}

// The offsets to try in a region.
void sample(const Region& r, bool exhaustive, std::set<uint64_t>* out) {
  const uint64_t n = r.end - r.begin;
  const bool every = exhaustive || r.kind == Kind::kHeader || r.kind == Kind::kTable || r.kind == Kind::kSection ||
                     r.kind == Kind::kPlaneIndex || n <= 48;
  for (uint64_t i = 0; i < n; ++i) {
    bool take = every;
    if (!take && r.kind == Kind::kBlock) take = i < 16 || i + 16 >= n || i % 3 == 0;
    if (!take) take = i == 0 || i + 1 == n || i == n / 2 || i % 251 == 0;
    if (take) out->insert(r.begin + i);
  }
}

struct Outcome {
  Code open[3] = {};
  Code read[3] = {};
  bool validatorValid = true;
  std::vector<Code> validatorCodes;
};

bool hasCode(const std::vector<Code>& v, Code c) {
  return std::find(v.begin(), v.end(), c) != v.end();
}

// Runs one variant through the reader and the validator; checks the codes' classes.
Outcome run(std::span<const uint8_t> bytes, const std::string& what) {
  Outcome o;
  for (size_t p = 0; p < 3; ++p) {
    ReadOptions ro;
    ro.checksums = conformance::kPolicies[p];
    auto f = File::openMemory(bytes, ro);
    if (!f) {
      o.open[p] = f.error().code;
      EXPECT_NE(o.open[p], Code::kOk) << what << ": failed open with code 0";
      EXPECT_TRUE(conformance::isFileProblem(o.open[p]))
          << what << " (" << conformance::policyName(ro.checksums) << "): open: " << f.error().toString();
      continue;
    }
    const Error e = conformance::readEverything(*f);
    o.read[p] = e.code;
    if (e.code != Code::kOk) {
      EXPECT_TRUE(conformance::isFileProblem(e.code))
          << what << " (" << conformance::policyName(ro.checksums) << "): read: " << e.toString();
    }
  }
  const Report rep = validate(bytes);
  o.validatorValid = rep.valid();
  for (const Issue& i : rep.issues) {
    o.validatorCodes.push_back(i.code);
    EXPECT_TRUE(conformance::isFileProblem(i.code)) << what << ": validator: " << uint32_t(i.code) << " " << i.message;
  }
  return o;
}

class Robustness : public ::testing::TestWithParam<Vector> {};

TEST_P(Robustness, TruncationsAndByteChanges) {
  const std::vector<uint8_t> original = readBytes(GetParam().path);
  ASSERT_GE(original.size(), kHeaderSize);
  auto file = File::openMemory(original);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  const std::vector<Region> regions = regionsOf(*file, original);
  const char* env = std::getenv("VFF_ROBUSTNESS_EXHAUSTIVE");
  const bool exhaustive = env && *env && std::string(env) != "0";
  std::set<uint64_t> offsets;
  for (const Region& r : regions) sample(r, exhaustive, &offsets);
  // Every kind of structure present in the file is exercised.
  std::set<Kind> kinds;
  for (const Region& r : regions) kinds.insert(r.kind);
  for (Kind k : kinds) {
    EXPECT_TRUE(std::any_of(regions.begin(), regions.end(), [&](const Region& r) {
      return r.kind == k && offsets.lower_bound(r.begin) != offsets.end() && *offsets.lower_bound(r.begin) < r.end;
    })) << kindName(k);
  }

  // (a) Prefixes.
  std::set<uint64_t> lengths(offsets);
  for (uint64_t n = 0; n <= kHeaderSize; ++n) lengths.insert(n);
  lengths.insert(original.size() - 1);
  for (uint64_t n : lengths) {
    if (n >= original.size()) continue;
    const std::string what = "prefix of " + std::to_string(n) + " bytes";
    const Outcome o = run(std::span(original).first(n), what);
    const Code want = n < kHeaderSize ? Code::kTooSmall : Code::kFileSizeMismatch;
    for (size_t p = 0; p < 3; ++p) EXPECT_EQ(o.open[p], want) << what;
    EXPECT_FALSE(o.validatorValid) << what;
    EXPECT_TRUE(hasCode(o.validatorCodes, want)) << what;
    if (testing::Test::HasFailure()) return;
  }

  // (b) Single-byte changes.
  std::vector<uint8_t> work = original;
  size_t region = 0;
  for (uint64_t off : offsets) {
    while (regions[region].end <= off) ++region;
    const Kind kind = regions[region].kind;
    for (uint8_t mask : {uint8_t(0xFF), uint8_t(0x01)}) {
      work[off] = uint8_t(original[off] ^ mask);
      const std::string what = "byte " + std::to_string(off) + " (" + kindName(kind) + ") ^ " + std::to_string(mask);
      const Outcome o = run(work, what);
      work[off] = original[off];
      EXPECT_FALSE(o.validatorValid) << what << ": the validator accepts it";
      if (kind != Kind::kPadding) {
        EXPECT_NE(o.open[0], Code::kOk) << what << ": kVerifyAll opens it";
      } else {
        EXPECT_TRUE(hasCode(o.validatorCodes, Code::kPadding)) << what;
      }
      if (kind == Kind::kHeader || kind == Kind::kTable || kind == Kind::kSection) {
        EXPECT_NE(o.open[1], Code::kOk) << what << ": kLazy opens it";
      } else if (kind == Kind::kPlaneIndex || kind == Kind::kBlock) {
        EXPECT_TRUE(o.open[1] != Code::kOk || o.read[1] != Code::kOk) << what << ": kLazy opens and reads it";
      }
      if (testing::Test::HasFailure()) return;  // one variant's report is enough
    }
  }
  RecordProperty("offsets", int(offsets.size()));
  RecordProperty("prefixes", int(lengths.size()));
}

INSTANTIATE_TEST_SUITE_P(Vectors, Robustness, ::testing::ValuesIn(listValid()),
                         [](const ::testing::TestParamInfo<Vector>& i) { return i.param.name; });

TEST(Robustness, HasVectors) {
  EXPECT_FALSE(listValid().empty()) << "no .vff files under " << kDir / "valid";
}

}  // namespace
}  // namespace vff
