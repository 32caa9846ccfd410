#include "vff/validate.h"

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "codec/codec.h"
#include "platform/mapped_file.h"
#include "container/parser.h"
#include "vff/encoding.h"

namespace vff {

const char* severityName(Severity s) noexcept { return s == Severity::kWarning ? "warning" : "error"; }

bool Report::valid() const noexcept {
  return std::none_of(issues.begin(), issues.end(), [](const Issue& i) { return i.severity == Severity::kError; });
}

bool Report::has(Code code) const noexcept {
  return std::any_of(issues.begin(), issues.end(), [code](const Issue& i) { return i.code == code; });
}

namespace {

constexpr size_t kMaxIssues = 1000;  // a hostile file cannot make the report grow without bound

class CollectSink final : public detail::IssueSink {
 public:
  explicit CollectSink(Report* r) : report_(r) {}
  bool add(Code code, Severity severity, uint32_t section, uint64_t offset, std::string message) override {
    if (report_->issues.size() >= kMaxIssues) return false;
    report_->issues.push_back({code, severity, section, offset, std::move(message)});
    return true;
  }

 private:
  Report* report_;
};

// Every byte outside the structures must be zero.
void checkPadding(std::span<const uint8_t> bytes, std::vector<std::pair<uint64_t, uint64_t>> covered, Report* r) {
  std::sort(covered.begin(), covered.end());
  uint64_t pos = 0;
  const uint64_t end = bytes.size();
  auto gap = [&](uint64_t a, uint64_t b) {
    for (uint64_t i = a; i < b && i < end; ++i)
      if (bytes[i] != 0) {
        r->issues.push_back({Code::kPadding, Severity::kError, 0, i,
                             "padding byte at " + std::to_string(i) + " is not zero"});
        return;
      }
  };
  for (auto [a, b] : covered) {
    if (a > pos) gap(pos, a);
    pos = std::max(pos, b);
  }
  if (pos < end) gap(pos, end);
}

// Decodes every block of a plane; checks that normal texels of misses are zero. Block by block into
// one buffer (File::decodeBlock, not the File's cache): memory stays one block (at most
// ReadOptions::maxBlockBytes) however large the field, even a few KiB of zstd that decode to GiBs.
void checkPlane(const File& f, Plane p, Report* r) {
  const PlaneInfo& pi = f.plane(p);
  const uint32_t tag = p == Plane::kDistance ? kTagDistance : kTagNormal;
  const FieldDesc& fd = f.field();
  bool missReported = false;  // rule 6013 is reported once per plane; decoding goes on
  std::vector<uint8_t> block, distBlock;  // the block checked; for normals, the distance block of its maps
  uint32_t distIndex = UINT32_MAX;
  for (uint32_t bi = 0; bi < pi.blocks.size(); ++bi) {
    block.resize(pi.blocks[bi].rawSize);
    if (Status st = f.decodeBlock(p, bi, block); !st) {
      const Error& e = st.error();
      r->issues.push_back({e.code, Severity::kError, tag, e.offset, "block " + std::to_string(bi) + ": " + e.message});
      continue;
    }
    if (p != Plane::kNormal || missReported) continue;
    const BlockInfo& b = pi.blocks[bi];
    for (uint32_t k = 0; k < b.mapCount; ++k) {
      const PlaneInfo& di = f.plane(Plane::kDistance);
      const uint32_t map = b.firstMap + k, db = map / di.mapsPerBlock;
      if (db != distIndex) {
        distIndex = UINT32_MAX;
        distBlock.resize(di.blocks[db].rawSize);
        if (!f.decodeBlock(Plane::kDistance, db, distBlock)) break;  // reported with the distance plane
        distIndex = db;
      }
      const std::span<const uint8_t> dist =
          std::span<const uint8_t>(distBlock).subspan(uint64_t(map - di.blocks[db].firstMap) * di.mapBytes, di.mapBytes);
      const uint8_t* nm = block.data() + uint64_t(k) * pi.mapBytes;
      const uint32_t m = fd.mapResolution;
      for (uint32_t t = 0; t < m * m; ++t) {
        const uint32_t code = loadCode(fd.distanceEncoding, dist, m, t % m, t / m);
        const bool hit = decodeDistance(fd.distanceEncoding, code, 1.0f, 1.0f).hit;
        if (!hit && (nm[4 * t] | nm[4 * t + 1] | nm[4 * t + 2] | nm[4 * t + 3]) != 0) {
          r->issues.push_back({Code::kValueRange, Severity::kError, tag, kNoOffset,
                               "map " + std::to_string(b.firstMap + k) + " texel " + std::to_string(t) +
                                   " is a miss but its normal is not zero"});
          missReported = true;
          break;
        }
      }
    }
  }
}

}  // namespace

Report validate(std::span<const uint8_t> bytes, const ValidateOptions& options) {
  Report report;
  CollectSink sink(&report);
  detail::ParseOptions po;
  po.limits = options.limits;
  po.verifySectionChecksums = true;
  po.verifyPlaneChecksums = true;
  detail::ParsedFile parsed;
  const bool usable = detail::parseFile(bytes, po, sink, &parsed);
  if (report.issues.size() >= kMaxIssues) return report;
  if (!parsed.covered.empty() && parsed.fieldOk) checkPadding(bytes, parsed.covered, &report);
  if (!usable || !options.decodeBlocks) return report;
  // Structurally sound: decode everything through the public reader.
  ReadOptions ro = options.limits;
  ro.checksums = ChecksumPolicy::kNone;  // already verified above
  auto file = File::openMemory(bytes, ro);
  if (!file) {
    const Error& e = file.error();
    report.issues.push_back({e.code, Severity::kError, e.section, e.offset, e.message});
    return report;
  }
  checkPlane(*file, Plane::kDistance, &report);
  if (file->hasNormals()) checkPlane(*file, Plane::kNormal, &report);
  return report;
}

Report validateFile(const std::string& path, const ValidateOptions& options) {
  detail::MappedFile mf;
  Status st = mf.open(path);
  if (!st) {
    Report r;
    r.issues.push_back({st.error().code, Severity::kError, 0, kNoOffset, st.error().message});
    return r;
  }
  return validate(mf.bytes(), options);
}

}  // namespace vff
