// The conformance suite: every vector under spec/conformance/ is its own test case, found by listing
// the folders when the test program starts (ctest lists the cases at test time, so a vector added
// without rebuilding still runs, and an empty folder fails VectorSetIsComplete).
//
//   valid/NAME.vff     opens under every checksum policy, validates with no error (and exactly the
//                      expected warnings), and decodes to NAME.expected.json (REFN, format 1.3,
//                      included: File::refinement()).
//   invalid/ID/*.vff   raises ID in the validator and is rejected by File::openMemory with ID (or, for
//                      the checks only the validator or a read makes, as its .expect.json records);
//                      libvff's whole observed behaviour equals the .expect.json.
#include <gtest/gtest.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "conformance.h"
#include "vff/vff.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff {
namespace {

const fs::path kDir = VFF_CONFORMANCE_DIR;

using conformance::readBytes;

json readJson(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in, nullptr, /*allow_exceptions=*/false);
}

std::string hex64(std::span<const uint8_t> b) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(XXH3_64bits(b.data(), b.size())));
  return buf;
}

// The .vff files under `sub`, recursively, sorted.
std::vector<fs::path> vectorFiles(const std::string& sub) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(kDir / sub, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && it->path().extension() == ".vff") out.push_back(it->path());
  std::sort(out.begin(), out.end());
  return out;
}

// "invalid/4003/layt-overlaps-fdsc.vff" -> "4003_layt_overlaps_fdsc" (gtest names: [A-Za-z0-9_]).
std::string caseName(const fs::path& p, bool withDir) {
  std::string s = (withDir ? p.parent_path().filename().string() + "_" : std::string()) + p.stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

struct Vector {
  std::string name;
  fs::path path;
};
void PrintTo(const Vector& v, std::ostream* os) {
  *os << fs::relative(v.path, kDir).generic_string();
}

std::vector<Vector> listVectors(const std::string& sub) {
  std::vector<Vector> out;
  for (const fs::path& p : vectorFiles(sub)) out.push_back({caseName(p, sub == "invalid"), p});
  return out;
}

fs::path sidecar(const fs::path& vff, const char* suffix) {
  return vff.parent_path() / (vff.stem().string() + suffix);
}

std::string rel(const fs::path& p) {
  return fs::relative(p, kDir).generic_string();
}

// ---- Valid vectors --------------------------------------------------------------------------------

bool closeTo(double got, double want, double tol) {
  return std::fabs(got - want) <= tol * std::max(1.0, std::fabs(want));
}

void checkField(const FieldDesc& f, const json& e) {
  EXPECT_EQ(f.sphere.center[0], e["sphere"]["center"][0].get<float>());
  EXPECT_EQ(f.sphere.center[1], e["sphere"]["center"][1].get<float>());
  EXPECT_EQ(f.sphere.center[2], e["sphere"]["center"][2].get<float>());
  EXPECT_EQ(f.sphere.radius, e["sphere"]["radius"].get<float>());
  EXPECT_EQ(positionSchemeName(f.positionScheme), e["positionScheme"]);
  EXPECT_EQ(f.positionParam, e["positionParam"]);
  EXPECT_EQ(f.mapCount, e["mapCount"]);
  EXPECT_EQ(directionSchemeName(f.directionScheme), e["directionScheme"]);
  EXPECT_EQ(f.mapResolution, e["mapResolution"]);
  EXPECT_EQ(frameConventionName(f.frame), e["frame"]);
  EXPECT_EQ(distanceEncodingName(f.distanceEncoding), e["distanceEncoding"]);
  EXPECT_EQ(missCode(f.distanceEncoding), e["missCode"]);
  EXPECT_EQ(normalEncodingName(f.normalEncoding), e["normalEncoding"]);
}

void checkLayoutDesc(const LayoutDesc& l, const json& e) {
  EXPECT_EQ(layoutTargetName(l.target), e["target"]);
  EXPECT_EQ(l.gutter, e["gutter"]);
  EXPECT_EQ(l.tileSize, e["tileSize"]);
  EXPECT_EQ(l.tilesPerRow, e["tilesPerRow"]);
  EXPECT_EQ(l.tilesPerColumn, e["tilesPerColumn"]);
  EXPECT_EQ(l.sliceWidth, e["sliceWidth"]);
  EXPECT_EQ(l.sliceHeight, e["sliceHeight"]);
  EXPECT_EQ(l.sliceCount, e["sliceCount"]);
  EXPECT_EQ(l.maxTextureSize, e["maxTextureSize"]);
  EXPECT_EQ(l.maxLayers, e["maxLayers"]);
}

// Every map's raw bytes (hash) and decoded values, then every packed slice.
void checkContent(const File& f, const json& e, bool decode) {
  const FieldDesc& fd = f.field();
  const uint32_t m = fd.mapResolution;
  ASSERT_EQ(e["maps"].size(), fd.mapCount);
  for (uint32_t k = 0; k < fd.mapCount; ++k) {
    SCOPED_TRACE("map " + std::to_string(k));
    const json& em = e["maps"][k];
    auto dist = f.mapData(Plane::kDistance, k);
    ASSERT_TRUE(dist.ok()) << dist.error().toString();
    EXPECT_EQ(hex64(*dist), em["distanceXxh3"]);
    std::span<const uint8_t> norm;
    if (f.hasNormals()) {
      auto n = f.mapData(Plane::kNormal, k);
      ASSERT_TRUE(n.ok()) << n.error().toString();
      EXPECT_EQ(hex64(*n), em["normalXxh3"]);
      norm = *n;
    }
    if (!decode) continue;
    ASSERT_EQ(em["distance"].size(), uint64_t(m) * m);
    for (uint32_t t = 0; t < m * m; ++t) {
      const uint32_t i = t % m, j = t / m;
      const Texel tx = decodeDistance(fd.distanceEncoding, loadCode(fd.distanceEncoding, *dist, m, i, j),
                                      fd.sphere.radius, texelDirection(fd.directionScheme, m, i, j).z);
      const json& want = em["distance"][t];
      if (fd.distanceEncoding == DistanceEncoding::kBit1) {
        EXPECT_EQ(tx.hit ? 1 : 0, want) << "texel " << t;
      } else if (want.is_null()) {
        EXPECT_FALSE(tx.hit) << "texel " << t << " should be a miss";
      } else {
        EXPECT_TRUE(tx.hit) << "texel " << t << " should be a hit";
        EXPECT_TRUE(closeTo(tx.distance, want.get<double>(), 2e-6))
            << "texel " << t << ": " << tx.distance << " vs " << want;
      }
      if (!f.hasNormals()) continue;
      const json& wn = em["normals"][t];
      if (!tx.hit) {
        EXPECT_TRUE(wn.is_null()) << "texel " << t;
        continue;
      }
      ASSERT_TRUE(wn.is_array()) << "texel " << t;
      const Vec3 n = decodeNormal(&norm[uint64_t(t) * 4]);
      EXPECT_NEAR(n.x, wn[0].get<double>(), 2e-6) << "texel " << t;
      EXPECT_NEAR(n.y, wn[1].get<double>(), 2e-6) << "texel " << t;
      EXPECT_NEAR(n.z, wn[2].get<double>(), 2e-6) << "texel " << t;
    }
  }
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (!e["slices"].contains(planeName(p))) {
      EXPECT_FALSE(f.plane(p).present);
      continue;
    }
    const json& want = e["slices"][planeName(p)];
    ASSERT_EQ(want.size(), f.layout().sliceCount);
    std::vector<uint8_t> slice(f.sliceBytes(p));
    for (uint32_t s = 0; s < f.layout().sliceCount; ++s) {
      Status st = f.readSlice(p, s, slice);
      ASSERT_TRUE(st.ok()) << st.error().toString();
      EXPECT_EQ(hex64(slice), want[s]) << planeName(p) << " slice " << s;
    }
  }
}

// REFN (format 1.3): File::refinement() against "refinement", which only a refined vector has.
void checkRefinement(const File& f, const json& e) {
  const RefinementView& r = f.refinement();
  if (!e.contains("refinement")) {
    EXPECT_TRUE(r.empty()) << "a refinement in a file without REFN";
    return;
  }
  const json& er = e["refinement"];
  ASSERT_FALSE(r.empty()) << "no refinement";
  EXPECT_EQ(r.margin, er["margin"].get<float>());
  EXPECT_EQ(r.unsureTexels, er["unsureTexels"]);
  ASSERT_EQ(r.unsure.size(), er["unsureBytes"]);
  EXPECT_EQ(hex64(r.unsure), er["unsureXxh3"]);
  const FieldDesc& fd = f.field();
  const uint64_t mm = uint64_t(fd.mapResolution) * fd.mapResolution;
  ASSERT_EQ(er["unsure"].size(), fd.mapCount);
  uint64_t count = 0;
  for (uint32_t k = 0; k < fd.mapCount; ++k) {
    json got = json::array();
    for (uint64_t t = 0; t < mm; ++t)
      if (r.isUnsure(k * mm + t)) got.push_back(t);
    EXPECT_EQ(got, er["unsure"][k]) << "the unsure texels of map " << k;
    count += got.size();
  }
  EXPECT_EQ(count, r.unsureTexels);
  ASSERT_EQ(r.positions.size(), 3 * er["vertexCount"].get<uint64_t>());
  ASSERT_EQ(r.indices.size(), 3 * er["triangleCount"].get<uint64_t>());
  // (little-endian hosts: the bytes as REFN stores them)
  EXPECT_EQ(hex64({reinterpret_cast<const uint8_t*>(r.positions.data()), r.positions.size() * 4}), er["positionsXxh3"]);
  EXPECT_EQ(hex64({reinterpret_cast<const uint8_t*>(r.indices.data()), r.indices.size() * 4}), er["indicesXxh3"]);
  for (size_t v = 0; v < r.positions.size() / 3; ++v)
    for (size_t a = 0; a < 3; ++a) EXPECT_EQ(r.positions[3 * v + a], er["positions"][v][a].get<float>()) << "vertex " << v;
  for (size_t t = 0; t < r.indices.size() / 3; ++t)
    for (size_t a = 0; a < 3; ++a) EXPECT_EQ(r.indices[3 * t + a], er["indices"][t][a]) << "triangle " << t;
}

class ValidVector : public ::testing::TestWithParam<Vector> {};

TEST_P(ValidVector, OpensValidatesAndDecodes) {
  const fs::path path = GetParam().path;
  const std::vector<uint8_t> bytes = readBytes(path);
  const json e = readJson(sidecar(path, ".expected.json"));
  ASSERT_TRUE(e.is_object()) << "missing or unreadable " << sidecar(path, ".expected.json");
  ASSERT_EQ(bytes.size(), e["fileSize"]);
  EXPECT_EQ(hex64(bytes), e["fileXxh3"]);

  const Report rep = validate(bytes);
  json warnings = json::array();
  for (const Issue& i : rep.issues) {
    if (i.severity == Severity::kError)
      ADD_FAILURE() << "validator error " << uint32_t(i.code) << " " << i.message;
    else
      warnings.push_back(uint32_t(i.code));
  }
  EXPECT_EQ(warnings, e["warnings"]);

  for (ChecksumPolicy policy : conformance::kPolicies) {
    SCOPED_TRACE(std::string("policy ") + conformance::policyName(policy));
    ReadOptions ro;
    ro.checksums = policy;
    auto f = File::openMemory(bytes, ro);
    ASSERT_TRUE(f.ok()) << f.error().toString();
    const FileInfo& info = f->info();
    EXPECT_EQ(info.versionMajor, e["versionMajor"]);
    EXPECT_EQ(info.versionMinor, e["versionMinor"]);
    EXPECT_EQ(info.fileSize, bytes.size());
    EXPECT_EQ(info.incompatFeatures, e["incompatFeatures"]);
    EXPECT_EQ(info.roCompatFeatures, e["roCompatFeatures"]);
    ASSERT_EQ(info.sections.size(), e["sections"].size());
    for (size_t i = 0; i < info.sections.size(); ++i) {
      const json& es = e["sections"][i];
      EXPECT_EQ(sectionTagName(info.sections[i].tag), es["tag"]);
      EXPECT_EQ(info.sections[i].flags, es["flags"]);
      EXPECT_EQ(codecName(info.sections[i].codec), es["codec"]);
      EXPECT_EQ(info.sections[i].known, es["known"]);
    }
    checkField(f->field(), e["field"]);
    checkLayoutDesc(f->layout(), e["layout"]);
    if (e["metadata"].is_null()) {
      EXPECT_TRUE(f->metadata().empty());
    } else if (e["metadata"].is_string()) {
      EXPECT_EQ(std::string(f->metadata()), e["metadata"].get<std::string>()) << "metadata is not the stored text";
    } else {
      EXPECT_EQ(json::parse(f->metadata(), nullptr, false), e["metadata"]);
      EXPECT_EQ(std::string(f->metadata()), e["metadata"].dump()) << "metadata is not in canonical form";
    }
    for (Plane p : {Plane::kDistance, Plane::kNormal}) {
      const PlaneInfo& pi = f->plane(p);
      if (!e["planes"].contains(planeName(p))) {
        EXPECT_FALSE(pi.present) << planeName(p);
        continue;
      }
      const json& ep = e["planes"][planeName(p)];
      ASSERT_TRUE(pi.present) << planeName(p);
      EXPECT_EQ(pi.mapBytes, ep["mapBytes"]);
      EXPECT_EQ(pi.mapsPerBlock, ep["mapsPerBlock"]);
      ASSERT_EQ(pi.blocks.size(), ep["blockCodecs"].size());
      for (size_t b = 0; b < pi.blocks.size(); ++b) EXPECT_EQ(codecName(pi.blocks[b].codec), ep["blockCodecs"][b]);
    }
    checkRefinement(*f, e);
    checkContent(*f, e, /*decode=*/policy == ChecksumPolicy::kVerifyAll);
  }
}

INSTANTIATE_TEST_SUITE_P(Conformance, ValidVector, ::testing::ValuesIn(listVectors("valid")),
                         [](const ::testing::TestParamInfo<Vector>& i) { return i.param.name; });

// ---- Invalid vectors ------------------------------------------------------------------------------

class InvalidVector : public ::testing::TestWithParam<Vector> {};

TEST_P(InvalidVector, RaisesItsIdAndIsRejected) {
  const fs::path path = GetParam().path;
  const uint32_t id = uint32_t(std::stoul(path.parent_path().filename().string()));
  const std::vector<uint8_t> bytes = readBytes(path);
  const json e = readJson(sidecar(path, ".expect.json"));
  ASSERT_TRUE(e.is_object()) << "missing or unreadable " << sidecar(path, ".expect.json");
  ASSERT_EQ(e["id"], id);

  // The format's rules, independent of the recorded behaviour.
  const Report rep = validate(bytes);
  EXPECT_FALSE(rep.valid());
  bool raised = false;
  for (const Issue& i : rep.issues) {
    raised |= uint32_t(i.code) == id && i.severity == Severity::kError;
    EXPECT_TRUE(conformance::isFileProblem(i.code)) << "validator issue " << uint32_t(i.code);
  }
  EXPECT_TRUE(raised) << "the validator does not report " << id;
  for (ChecksumPolicy policy : conformance::kPolicies) {
    SCOPED_TRACE(std::string("policy ") + conformance::policyName(policy));
    ReadOptions ro;
    ro.checksums = policy;
    auto f = File::openMemory(bytes, ro);
    Error readError;
    if (!f) {
      EXPECT_NE(f.error().code, Code::kOk);
      EXPECT_TRUE(conformance::isFileProblem(f.error().code)) << f.error().toString();
    } else {
      readError = conformance::readEverything(*f);
      if (readError.code != Code::kOk) {
        EXPECT_TRUE(conformance::isFileProblem(readError.code)) << readError.toString();
      }
    }
    if (policy != ChecksumPolicy::kVerifyAll) continue;
    if (!conformance::isValidatorOnly(Code(id))) {
      ASSERT_FALSE(f.ok()) << "File::openMemory accepted the file";
      EXPECT_EQ(uint32_t(f.error().code), id) << f.error().toString();
    } else if (Code(id) == Code::kBlockDecode) {
      ASSERT_TRUE(f.ok()) << f.error().toString();  // blocks decode on first use
      EXPECT_EQ(readError.code, Code::kBlockDecode) << readError.toString();
    } else {
      ASSERT_TRUE(f.ok()) << f.error().toString();  // only the validator checks this
      EXPECT_EQ(readError.code, Code::kOk) << readError.toString();
    }
  }

  // The behaviour pinned when the vector was made (the whole cascade, KTX-CTS style).
  const json seen = conformance::observe(bytes);
  EXPECT_EQ(seen, e["observed"]) << "observed: " << seen.dump() << "\nrecorded: " << e["observed"].dump()
                                 << "\n(if libvff changed on purpose, regenerate: ninja vff-conformance-update)";
}

INSTANTIATE_TEST_SUITE_P(Conformance, InvalidVector, ::testing::ValuesIn(listVectors("invalid")),
                         [](const ::testing::TestParamInfo<Vector>& i) { return i.param.name; });

// ---- The vector set itself ------------------------------------------------------------------------

TEST(Conformance, VectorSetIsComplete) {
  ASSERT_TRUE(fs::is_directory(kDir)) << kDir;
  const auto valid = vectorFiles("valid"), invalid = vectorFiles("invalid");
  EXPECT_FALSE(valid.empty()) << "no valid vectors under " << kDir / "valid";
  EXPECT_FALSE(invalid.empty()) << "no invalid vectors under " << kDir / "invalid";
  // Every file under valid/ and invalid/ is a vector or its sidecar, and each has its partner.
  std::set<std::string> onDisk;
  for (const char* sub : {"valid", "invalid"}) {
    std::error_code ec;
    for (fs::recursive_directory_iterator it(kDir / sub, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->is_directory()) {
        if (std::string(sub) == "invalid") {
          const std::string d = it->path().filename().string();
          const bool numeric = d.size() == 4 && std::all_of(d.begin(), d.end(), ::isdigit);
          EXPECT_TRUE(numeric && conformance::isFileProblem(Code(std::stoul(d))) &&
                      std::string(codeName(Code(std::stoul(d)))) != "unknown")
              << rel(it->path()) << " is not named after a file-problem validation ID";
          EXPECT_FALSE(fs::is_empty(it->path())) << rel(it->path()) << " is empty";
        }
        continue;
      }
      const fs::path& p = it->path();
      onDisk.insert(rel(p));
      const std::string name = p.filename().string();
      const char* side = std::string(sub) == "valid" ? ".expected.json" : ".expect.json";
      if (p.extension() == ".vff") {
        EXPECT_TRUE(fs::exists(sidecar(p, side))) << rel(p) << " has no " << side;
      } else if (name.size() > std::strlen(side) && name.ends_with(side)) {
        const fs::path v = p.parent_path() / (name.substr(0, name.size() - std::strlen(side)) + ".vff");
        EXPECT_TRUE(fs::exists(v)) << rel(p) << " has no .vff";
      } else {
        ADD_FAILURE() << rel(p) << " is neither a vector nor its sidecar";
      }
    }
  }
  // The manifest lists exactly these files, with their hashes.
  const json manifest = readJson(kDir / "manifest.json");
  ASSERT_TRUE(manifest.is_object()) << "missing or unreadable manifest.json";
  std::set<std::string> listed;
  for (const auto& [name, entry] : manifest["files"].items()) {
    listed.insert(name);
    if (onDisk.count(name)) {
      EXPECT_EQ(hex64(readBytes(kDir / name)), entry["xxh3"]) << name;
    }
  }
  EXPECT_EQ(listed, onDisk);
}

// Every file-problem ID that libvff defines has vectors, except the ones a file cannot raise as an
// error (README.md lists them).
TEST(Conformance, EveryFileProblemIdHasVectors) {
  const std::map<uint32_t, const char*> kNotAnError = {
      {uint32_t(Code::kRoCompatFeature), "a warning: valid/rocompat-bit0.vff covers it"}};
  std::string missing;
  for (uint32_t id = 2000; id < 9000; ++id) {
    if (std::string(codeName(Code(id))) == "unknown" || kNotAnError.count(id)) continue;
    if (!fs::is_directory(kDir / "invalid" / std::to_string(id))) missing += " " + std::to_string(id);
  }
  EXPECT_TRUE(missing.empty()) << "validation IDs without an invalid vector:" << missing;
}

// The committed vectors are exactly what the generator makes now. A different libzstd may compress
// differently: then the files that depend on zstd output are not compared (a note says so).
TEST(Conformance, RegeneratedBytesMatch) {
  const fs::path tmp = fs::temp_directory_path() / ("vff-conformance-regen-" + std::to_string(::getpid()));
  fs::remove_all(tmp);
  const std::string cmd = std::string("\"") + VFF_CONFORMANCE_GEN + "\" \"" + tmp.string() + "\"";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const json committed = readJson(kDir / "manifest.json"), fresh = readJson(tmp / "manifest.json");
  ASSERT_TRUE(committed.is_object() && fresh.is_object());
  const bool sameZstd = committed["zstdVersion"] == fresh["zstdVersion"];
  if (!sameZstd)
    std::printf("note: the vectors were made with zstd %s, this build has %s: zstd-dependent files are not compared\n",
                committed["zstdVersion"].dump().c_str(), fresh["zstdVersion"].dump().c_str());
  std::set<std::string> names;
  for (const auto& [name, entry] : committed["files"].items()) names.insert(name);
  for (const auto& [name, entry] : fresh["files"].items()) names.insert(name);
  int compared = 0;
  for (const std::string& name : names) {
    const bool inCommitted = committed["files"].contains(name), inFresh = fresh["files"].contains(name);
    if (!inCommitted || !inFresh || !fs::exists(kDir / name) || !fs::exists(tmp / name)) {
      ADD_FAILURE() << name << (inCommitted ? " is no longer generated" : " is new: regenerate the vectors");
      continue;
    }
    if (!sameZstd && committed["files"][name]["zstd"].get<bool>()) continue;
    ++compared;
    EXPECT_TRUE(readBytes(kDir / name) == readBytes(tmp / name)) << name << " differs from the generator's output";
  }
  if (sameZstd) {
    EXPECT_TRUE(readBytes(kDir / "manifest.json") == readBytes(tmp / "manifest.json"));
  }
  EXPECT_GT(compared, 0);
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace vff
