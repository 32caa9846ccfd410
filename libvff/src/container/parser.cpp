#include "container/parser.h"
#include "refine/refine_section.h"

#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_getFrameHeader (exported by libzstd since 1.3)
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "codec/codec.h"
#include "container/json_text.h"
#include "container/le.h"

namespace vff::detail {
namespace {

std::string num(uint64_t v) { return std::to_string(v); }

// The deepest nesting of arrays/objects a META text may have (rule 8001).

class Parser {
 public:
  Parser(std::span<const uint8_t> bytes, const ParseOptions& opt, IssueSink& sink, ParsedFile* out)
      : b_(bytes), opt_(opt), sink_(sink), out_(out) {}

  bool run() {
    if (!header()) return false;
    if (!sectionTable()) return false;
    if (!fieldSection()) return false;
    if (!layoutSection()) return false;
    if (!planeSection(Plane::kDistance)) return false;
    if (!planeSection(Plane::kNormal)) return false;
    if (!metadataSection()) return false;
    if (!refinementSection()) return false;
    return usable_;
  }

 private:
  // Reports an issue; returns whether parsing may go on. Errors make the result unusable.
  bool report(Code code, uint32_t section, uint64_t offset, std::string msg,
              Severity sev = Severity::kError) {
    if (sev == Severity::kError) usable_ = false;
    return sink_.add(code, sev, section, offset, std::move(msg));
  }
  // Reports an error after which this parse cannot continue at all.
  bool fatal(Code code, uint32_t section, uint64_t offset, std::string msg) {
    report(code, section, offset, std::move(msg));
    return false;
  }

  bool header() {
    if (b_.size() < kHeaderSize)
      return fatal(Code::kTooSmall, 0, 0, "file is " + num(b_.size()) + " bytes, shorter than the 64-byte header");
    if (!std::equal(kMagic, kMagic + 8, b_.data())) return fatal(Code::kBadMagic, 0, 0, "not a .vff file (bad magic)");
    FileInfo& fi = out_->info;
    fi.versionMajor = loadU16(&b_[8]);
    fi.versionMinor = loadU16(&b_[10]);
    if (fi.versionMajor != kVersionMajor)
      return fatal(Code::kUnsupportedVersion, 0, 8,
                   "format version " + num(fi.versionMajor) + "." + num(fi.versionMinor) +
                       " is not supported (this reader reads major version 1)");
    const uint32_t headerSize = loadU32(&b_[12]);
    if (headerSize != kHeaderSize)
      return fatal(Code::kHeaderSize, 0, 12, "headerSize is " + num(headerSize) + ", expected 64");
    fi.fileSize = loadU64(&b_[16]);
    fi.incompatFeatures = loadU64(&b_[24]);
    fi.roCompatFeatures = loadU64(&b_[32]);
    if (uint64_t unknown = fi.incompatFeatures & ~kKnownIncompatFeatures; unknown != 0) {
      int bit = __builtin_ctzll(unknown);
      return fatal(Code::kUnknownIncompatFeature, 0, 24,
                   "incompatFeatures bit " + num(uint64_t(bit)) + " is not implemented by this reader");
    }
    if (fi.roCompatFeatures & ~kKnownRoCompatFeatures) {
      int bit = __builtin_ctzll(fi.roCompatFeatures & ~kKnownRoCompatFeatures);
      if (!report(Code::kRoCompatFeature, 0, 32,
                  "roCompatFeatures bit " + num(uint64_t(bit)) + " is unknown: the file may be read but not rewritten",
                  Severity::kWarning))
        return false;
    }
    if (fi.fileSize != b_.size()) {
      if (!report(Code::kFileSizeMismatch, 0, 16,
                  "header says the file is " + num(fi.fileSize) + " bytes, it is " + num(b_.size()) +
                      (b_.size() < fi.fileSize ? " (truncated)" : " (bytes appended)")))
        return false;
    }
    const uint64_t tableOffset = loadU64(&b_[40]);
    const uint32_t count = loadU32(&b_[48]);
    const uint16_t entrySize = loadU16(&b_[52]);
    fi.checksumAlgorithm = ChecksumAlgorithm(b_[54]);
    fi.headerChecksum = loadU64(&b_[56]);
    if (fi.checksumAlgorithm != ChecksumAlgorithm::kXxh3_64)
      return fatal(Code::kChecksumAlgorithm, 0, 54, "unknown checksumAlgorithm " + num(b_[54]));
    if (b_[55] != 0 && !report(Code::kHeaderReserved, 0, 55, "reserved header byte is not zero")) return false;
    if (entrySize != kSectionEntrySize)
      return fatal(Code::kSectionTable, 0, 52, "sectionEntrySize is " + num(entrySize) + ", expected 64");
    if (count == 0 || count > opt_.limits.maxSections)
      return fatal(Code::kSectionCount, 0, 48,
                   "sectionCount " + num(count) + " is outside [1, " + num(opt_.limits.maxSections) + "]");
    if (tableOffset < kHeaderSize || !inRange(tableOffset, uint64_t(count) * kSectionEntrySize, b_.size()))
      return fatal(Code::kSectionTable, 0, 40,
                   "section table at " + num(tableOffset) + " with " + num(count) + " entries lies outside the " +
                       num(b_.size()) + "-byte file");
    tableOffset_ = tableOffset;
    count_ = count;
    out_->covered.emplace_back(0, kHeaderSize);
    out_->covered.emplace_back(tableOffset, tableOffset + uint64_t(count) * kSectionEntrySize);
    Xxh3Stream h;
    h.update(b_.subspan(0, 56));
    h.update(b_.subspan(tableOffset, uint64_t(count) * kSectionEntrySize));
    if (h.digest() != fi.headerChecksum &&
        !report(Code::kHeaderChecksum, 0, 56, "header checksum does not match the header and section table"))
      return false;
    return true;
  }

  struct KnownTag {
    uint32_t tag;
    uint32_t flags;
  };
  static constexpr KnownTag kKnown[] = {{kTagField, kSectionRequired},
                                        {kTagLayout, kSectionRequired},
                                        {kTagDistance, kSectionRequired},
                                        {kTagNormal, 0},
                                        {kTagMetadata, kSectionCopySafe},
                                        {kTagRefinement, 0}};

  bool sectionTable() {
    FileInfo& fi = out_->info;
    uint64_t prevEnd = tableOffset_ + uint64_t(count_) * kSectionEntrySize;
    bool anyZstd = false;
    for (uint32_t i = 0; i < count_; ++i) {
      const uint64_t at = tableOffset_ + uint64_t(i) * kSectionEntrySize;
      const uint8_t* e = &b_[at];
      SectionInfo s;
      s.tag = loadU32(e);
      s.flags = loadU32(e + 4);
      s.offset = loadU64(e + 8);
      s.storedSize = loadU64(e + 16);
      s.rawSize = loadU64(e + 24);
      s.codec = Codec(loadU16(e + 32));
      s.sectionVersion = loadU16(e + 34);
      s.checksum = loadU64(e + 40);
      const uint32_t tag = s.tag;
      bool usable = true;
      const KnownTag* known = nullptr;
      for (const KnownTag& k : kKnown)
        if (k.tag == tag) known = &k;
      s.known = known != nullptr;
      if (s.flags & ~kKnownSectionFlags) {
        if (!report(Code::kSectionReserved, tag, at + 4, "unknown section flag bits " + num(s.flags & ~kKnownSectionFlags)))
          return false;
      } else if (known && s.flags != known->flags) {
        if (!report(Code::kSectionReserved, tag, at + 4,
                    "flags are " + num(s.flags) + ", the spec gives " + num(known->flags) + " for this section"))
          return false;
      }
      if (loadU32(e + 36) != 0 || loadU64(e + 48) != 0 || loadU64(e + 56) != 0) {
        if (!report(Code::kSectionReserved, tag, at + 36, "reserved section-entry fields are not zero")) return false;
      }
      if (!known && (s.flags & kSectionRequired))
        return fatal(Code::kUnknownRequired, tag, at,
                     "section '" + sectionTagName(tag) + "' is marked required but is unknown to this reader");
      if (known && s.sectionVersion != 1) {
        usable = false;
        if (!report(Code::kSectionVersion, tag, at + 34, "sectionVersion " + num(s.sectionVersion) + " is not supported"))
          return false;
      }
      if (!inRange(s.offset, s.storedSize, b_.size())) {
        usable = false;
        if (!report(Code::kSectionBounds, tag, at + 8,
                    "section at " + num(s.offset) + " of " + num(s.storedSize) + " bytes ends past the " +
                        num(b_.size()) + "-byte file"))
          return false;
      }
      if (s.offset % kSectionAlignment != 0) {
        if (!report(Code::kSectionAlignment, tag, at + 8, "section offset " + num(s.offset) + " is not a multiple of 4096"))
          return false;
      }
      if (s.offset < prevEnd) {
        usable = false;
        if (!report(Code::kSectionOrder, tag, at + 8,
                    "section at " + num(s.offset) + " overlaps the preceding structure ending at " + num(prevEnd)))
          return false;
      }
      if (usable) prevEnd = s.offset + s.storedSize;
      const bool isPlane = tag == kTagDistance || tag == kTagNormal;
      if (s.codec != Codec::kStored && s.codec != Codec::kZstd) {
        usable = false;
        if (!report(Code::kSectionCodec, tag, at + 32, "unknown section codec " + num(uint16_t(s.codec)))) return false;
      } else if (isPlane && s.codec != Codec::kStored) {
        usable = false;
        if (!report(Code::kSectionCodec, tag, at + 32, "plane sections must be stored (their blocks carry codecs)"))
          return false;
      } else if (s.codec == Codec::kStored && s.rawSize != s.storedSize) {
        usable = false;
        if (!report(Code::kSectionSize, tag, at + 24,
                    "stored section has rawSize " + num(s.rawSize) + " != storedSize " + num(s.storedSize)))
          return false;
      }
      if (s.codec == Codec::kZstd) anyZstd = true;
      if (known && !isPlane && s.rawSize > opt_.limits.maxSectionBytes) {
        usable = false;
        if (!report(Code::kSectionLimit, tag, at + 24,
                    "section of " + num(s.rawSize) + " bytes exceeds the limit of " + num(opt_.limits.maxSectionBytes)))
          return false;
      }
      for (size_t j = 0; j < fi.sections.size(); ++j)
        if (fi.sections[j].tag == tag) {
          usable = false;
          if (!report(Code::kDuplicateSection, tag, at, "section '" + sectionTagName(tag) + "' appears twice"))
            return false;
          break;
        }
      const bool verify = isPlane ? opt_.verifyPlaneChecksums : opt_.verifySectionChecksums;
      if (usable && verify && xxh3(b_.subspan(s.offset, s.storedSize)) != s.checksum) {
        if (!report(Code::kSectionChecksum, tag, at + 40, "section checksum does not match its stored bytes"))
          return false;
      }
      // A plane section's coverage is its header, index and blocks (planeSection), so the padding
      // between blocks is checked too; other sections are covered whole.
      if (usable && !isPlane) out_->covered.emplace_back(s.offset, s.offset + s.storedSize);
      fi.sections.push_back(s);
      sectionUsable_.push_back(usable);
      sectionEntryAt_.push_back(at);
    }
    if (anyZstd && !(fi.incompatFeatures & kFeatureZstd)) {
      if (!report(Code::kFeatureBit, 0, 24, "a section uses zstd but incompatFeatures lacks the zstd bit")) return false;
    }
    for (uint32_t tag : {kTagField, kTagLayout, kTagDistance})
      if (find(tag) < 0)
        return fatal(Code::kMissingSection, tag, kNoOffset, "required section '" + sectionTagName(tag) + "' is missing");
    return true;
  }

  int find(uint32_t tag) const {
    const auto& v = out_->info.sections;
    for (size_t i = 0; i < v.size(); ++i)
      if (v[i].tag == tag) return int(i);
    return -1;
  }

  // The raw bytes of a non-plane section (decompressed if needed); false if unusable.
  bool sectionBytes(int idx, std::vector<uint8_t>* raw) {
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    if (!sectionUsable_[size_t(idx)]) return false;
    auto stored = b_.subspan(s.offset, s.storedSize);
    if (s.codec == Codec::kZstd) {  // before allocating rawSize bytes
      if (Status st = checkZstdFrame(stored, s.rawSize, Code::kSectionDecode); !st) {
        report(Code::kSectionDecode, s.tag, s.offset, st.error().message);
        return false;
      }
    }
    raw->resize(s.rawSize);
    Status st = decompress(s.codec, stored, *raw, Code::kSectionDecode);
    if (!st) {
      report(Code::kSectionDecode, s.tag, s.offset, st.error().message);
      return false;
    }
    return true;
  }

  bool fieldSection() {
    const int idx = find(kTagField);
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    if (s.rawSize != kFieldDescSize)
      return fatal(Code::kSectionSize, kTagField, sectionEntryAt_[size_t(idx)] + 24,
                   "FDSC is " + num(s.rawSize) + " bytes, expected 64");
    std::vector<uint8_t> raw;
    if (!sectionBytes(idx, &raw)) {  // already reported
      usable_ = false;
      return false;
    }
    const uint8_t* p = raw.data();
    // Offsets in messages point into the file when the section is stored.
    const uint64_t base = s.codec == Codec::kStored ? s.offset : kNoOffset;
    const auto at = [&](uint64_t o) { return base == kNoOffset ? kNoOffset : base + o; };
    FieldDesc& f = out_->field;
    f.sphere.center[0] = loadF32(p);
    f.sphere.center[1] = loadF32(p + 4);
    f.sphere.center[2] = loadF32(p + 8);
    f.sphere.radius = loadF32(p + 12);
    f.positionScheme = PositionScheme(loadU32(p + 16));
    f.positionParam = loadU32(p + 20);
    f.mapCount = loadU32(p + 24);
    f.directionScheme = DirectionScheme(loadU32(p + 28));
    f.mapResolution = loadU32(p + 32);
    f.frame = FrameConvention(loadU32(p + 36));
    f.distanceEncoding = DistanceEncoding(loadU32(p + 40));
    const uint32_t miss = loadU32(p + 44);
    f.normalEncoding = NormalEncoding(loadU32(p + 48));
    bool ok = true;
    if (loadU32(p + 52) != 0 || loadU64(p + 56) != 0) {
      if (!report(Code::kFieldReserved, kTagField, at(52), "reserved FDSC fields are not zero")) return false;
    }
    Status st = checkFieldDesc(f);
    if (!st) {
      ok = false;
      static constexpr std::pair<Code, uint64_t> kWhere[] = {
          {Code::kSphere, 0},           {Code::kPositionScheme, 16}, {Code::kMapCount, 24},
          {Code::kDirectionScheme, 28}, {Code::kMapResolution, 32},  {Code::kFrameConvention, 36},
          {Code::kDistanceEncoding, 40}, {Code::kNormalEncoding, 48}};
      uint64_t o = 0;
      for (auto [c, off] : kWhere)
        if (c == st.error().code) o = off;
      if (!report(st.error().code, kTagField, at(o), st.error().message)) return false;
    } else if (miss != missCode(f.distanceEncoding)) {
      ok = false;
      if (!report(Code::kMissCode, kTagField, at(44),
                  "missCode is " + num(miss) + ", " + distanceEncodingName(f.distanceEncoding) + " reserves " +
                      num(missCode(f.distanceEncoding))))
        return false;
    }
    if (ok && f.distanceEncoding == DistanceEncoding::kBc4Diameter && !(out_->info.incompatFeatures & kFeatureBc4)) {
      // The file is still readable; a reader that does not know bc4 would only fail later (rule 5007).
      if (!report(Code::kFeatureBit, 0, 24,
                  "the distance encoding is bc4-diameter but the bc4 feature bit (incompatFeatures bit 2) is clear"))
        return false;
    }
    if (ok) {
      const ReadOptions& lim = opt_.limits;
      uint64_t payload = 0;
      const uint64_t perMap = distanceMapBytes(f.distanceEncoding, f.mapResolution) +
                              normalMapBytes(f.normalEncoding, f.mapResolution);
      if (f.mapCount > lim.maxMaps) {
        ok = false;
        if (!report(Code::kMapCount, kTagField, at(24),
                    "mapCount " + num(f.mapCount) + " exceeds the reader's limit of " + num(lim.maxMaps)))
          return false;
      } else if (f.mapResolution > lim.maxMapResolution) {
        ok = false;
        if (!report(Code::kMapResolution, kTagField, at(32),
                    "mapResolution " + num(f.mapResolution) + " exceeds the reader's limit of " + num(lim.maxMapResolution)))
          return false;
      } else if (!mulOk(perMap, f.mapCount, &payload) || payload > lim.maxPayloadBytes) {
        ok = false;
        if (!report(Code::kDecodedLimit, kTagField, at(24),
                    "the field declares " + num(payload) + " payload bytes, above the reader's limit of " +
                        num(lim.maxPayloadBytes)))
          return false;
      }
    }
    out_->fieldOk = ok;
    if (!ok) {
      usable_ = false;
      return false;  // nothing after FDSC can be interpreted without it
    }
    return true;
  }

  bool layoutSection() {
    const int idx = find(kTagLayout);
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    if (s.rawSize != kLayoutDescSize) {
      usable_ = false;
      return report(Code::kSectionSize, kTagLayout, sectionEntryAt_[size_t(idx)] + 24,
                    "LAYT is " + num(s.rawSize) + " bytes, expected 64");
    }
    std::vector<uint8_t> raw;
    if (!sectionBytes(idx, &raw)) return usable_ = false, true;
    const uint8_t* p = raw.data();
    const uint64_t base = s.codec == Codec::kStored ? s.offset : kNoOffset;
    const auto at = [&](uint64_t o) { return base == kNoOffset ? kNoOffset : base + o; };
    LayoutDesc& l = out_->layout;
    l.target = LayoutTarget(loadU32(p));
    l.gutter = loadU32(p + 4);
    l.tileSize = loadU32(p + 8);
    l.tilesPerRow = loadU32(p + 12);
    l.tilesPerColumn = loadU32(p + 16);
    l.sliceWidth = loadU32(p + 20);
    l.sliceHeight = loadU32(p + 24);
    l.sliceCount = loadU32(p + 28);
    l.maxTextureSize = loadU32(p + 32);
    l.maxLayers = loadU32(p + 36);
    if (std::any_of(p + 40, p + 64, [](uint8_t c) { return c != 0; })) {
      if (!report(Code::kLayoutReserved, kTagLayout, at(40), "reserved LAYT fields are not zero")) return false;
    }
    Status st = checkLayout(l, out_->field);
    if (!st) {
      usable_ = false;
      const uint64_t o = st.error().code == Code::kLayoutTarget ? 0 : st.error().code == Code::kLayoutTile ? 4 : 12;
      return report(st.error().code, kTagLayout, at(o), st.error().message);
    }
    out_->layoutOk = true;
    return true;
  }

  // What one plane's block-index walk carries from one entry to the next.
  struct BlockWalk {
    uint64_t expected = 0;       // the canonical offset of the next block in the section
    bool limitReported = false;  // kDecodedLimit: once per plane (every block but the last has one size)
  };

  // Entry `bi` of a plane's block index (spec/format.md section 8): its bounds, order, sizes,
  // codec, filter and checksum, recorded in pi.blocks[bi]. Returns false when the parse stops (the
  // verdict of report()); *usable says whether the block can be read.
  bool blockEntry(Plane plane, const SectionInfo& s, std::span<const uint8_t> sec, uint32_t bi, PlaneInfo& pi,
                  BlockWalk& walk, bool* usable) {
    const uint32_t tag = plane == Plane::kDistance ? kTagDistance : kTagNormal;
    const uint64_t at = kPlaneHeaderSize + uint64_t(bi) * kBlockEntrySize;
    const uint8_t* e = &sec[at];
    BlockInfo& blk = pi.blocks[bi];
    const uint64_t rel = loadU64(e);
    blk.storedSize = loadU64(e + 8);
    blk.rawSize = loadU32(e + 16);
    blk.codec = Codec(e[20]);
    blk.filter = Filter(e[21]);
    blk.checksum = loadU64(e + 24);
    blk.firstMap = bi * pi.mapsPerBlock;
    blk.mapCount = std::min(pi.mapsPerBlock, out_->field.mapCount - blk.firstMap);
    blk.offset = s.offset + rel;
    const uint64_t where = s.offset + at;
    const FieldDesc& f = out_->field;
    const uint64_t mapBytes = pi.mapBytes;
    bool ok = true;
    if (loadU16(e + 22) != 0) {
      if (!report(Code::kBlockReserved, tag, where + 22, "reserved block-entry bytes are not zero")) return false;
    }
    if (!inRange(rel, blk.storedSize, sec.size())) {
      ok = false;
      if (!report(Code::kBlockBounds, tag, where,
                  "block " + num(bi) + " at " + num(rel) + " of " + num(blk.storedSize) + " bytes ends past the section"))
        return false;
    } else if (rel % kBlockAlignment != 0) {
      ok = false;
      if (!report(Code::kBlockAlignment, tag, where, "block " + num(bi) + " offset " + num(rel) + " is not a multiple of 64"))
        return false;
    } else if (rel != walk.expected) {
      ok = false;
      if (!report(Code::kBlockOrder, tag, where,
                  "block " + num(bi) + " starts at " + num(rel) + ", the canonical position is " + num(walk.expected)))
        return false;
    }
    if (uint64_t(blk.rawSize) != uint64_t(blk.mapCount) * mapBytes) {
      ok = false;
      if (!report(Code::kBlockRawSize, tag, where + 16,
                  "block " + num(bi) + " rawSize " + num(blk.rawSize) + " should be " + num(uint64_t(blk.mapCount) * mapBytes)))
        return false;
    } else if (blk.rawSize > opt_.limits.maxBlockBytes && !walk.limitReported) {
      // Before anything is decoded: a valid zstd frame of a few KiB can really expand to 4 GiB.
      walk.limitReported = true;  // once per plane: every block but the last has the same rawSize
      if (!report(Code::kDecodedLimit, tag, where + 16,
                  "block " + num(bi) + " of " + num(pi.blocks.size()) + " decodes to " + num(blk.rawSize) +
                      " bytes, above the reader's limit of " + num(opt_.limits.maxBlockBytes) +
                      " bytes per block (ReadOptions::maxBlockBytes)"))
        return false;
    }
    if (blk.codec != Codec::kStored && blk.codec != Codec::kZstd) {
      ok = false;
      if (!report(Code::kBlockCodec, tag, where + 20, "block " + num(bi) + " has unknown codec " + num(e[20])))
        return false;
    } else if (blk.codec == Codec::kStored && blk.storedSize != blk.rawSize) {
      ok = false;
      if (!report(Code::kBlockCodec, tag, where + 8,
                  "stored block " + num(bi) + " has storedSize " + num(blk.storedSize) + " != rawSize " + num(blk.rawSize)))
        return false;
    } else if (blk.codec == Codec::kZstd && !(out_->info.incompatFeatures & kFeatureZstd)) {
      if (!report(Code::kFeatureBit, tag, where + 20, "block " + num(bi) + " uses zstd but the zstd feature bit is clear"))
        return false;
    }
    if (blk.filter != Filter::kNone) {
      if (blk.filter != Filter::kHitsMed) {
        ok = false;
        if (!report(Code::kBlockFilter, tag, where + 21, "block " + num(bi) + " has unknown filter " + num(e[21])))
          return false;
      } else if (!filterApplies(blk.filter, plane, f)) {
        ok = false;
        if (!report(Code::kBlockFilter, tag, where + 21,
                    "block " + num(bi) + " uses filter hits-med, which applies only to distance planes with an "
                    "8-bit encoding, not to this " + std::string(planeName(plane)) + " plane of " +
                    (plane == Plane::kDistance ? distanceEncodingName(f.distanceEncoding)
                                               : normalEncodingName(f.normalEncoding))))
          return false;
      } else if (blk.codec != Codec::kZstd) {
        ok = false;
        if (!report(Code::kBlockFilter, tag, where + 21,
                    "block " + num(bi) + " uses filter hits-med with codec " + codecName(blk.codec) +
                        "; a filtered block must use zstd"))
          return false;
      } else if (!(out_->info.incompatFeatures & kFeatureFilters)) {
        if (!report(Code::kFeatureBit, tag, where + 21,
                    "block " + num(bi) + " uses a filter but the filters feature bit (incompatFeatures bit 1) is clear"))
          return false;
      }
    }
    if (ok && opt_.verifyPlaneChecksums &&
        xxh3(sec.subspan(rel, blk.storedSize)) != blk.checksum) {
      if (!report(Code::kBlockChecksum, tag, where + 24, "block " + num(bi) + " checksum does not match its stored bytes"))
        return false;
    }
    if (ok) {
      out_->covered.emplace_back(blk.offset, blk.offset + blk.storedSize);
      pi.storedBytes += blk.storedSize;
      walk.expected = alignUp(rel + blk.storedSize, kBlockAlignment);
    }
    *usable = ok;
    return true;
  }

  bool planeSection(Plane plane) {
    const uint32_t tag = plane == Plane::kDistance ? kTagDistance : kTagNormal;
    const int idx = find(tag);
    const FieldDesc& f = out_->field;
    PlaneInfo& pi = out_->planes[size_t(plane)];
    if (plane == Plane::kNormal) {
      const bool want = f.normalEncoding != NormalEncoding::kNone;
      if (want != (idx >= 0)) {
        usable_ = false;
        return report(Code::kPlanePresence, kTagNormal, kNoOffset,
                      want ? "the field has a normal encoding but no NORM section"
                           : "NORM section present but the field's normalEncoding is none");
      }
      if (idx < 0) return true;
    }
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    if (!sectionUsable_[size_t(idx)]) {
      usable_ = false;
      return true;
    }
    bool planeOk = true;
    // Where the plane cannot be walked, its bytes are not padding: cover the whole section.
    struct CoverOnFailure {
      ParsedFile* out;
      const SectionInfo& s;
      const bool& ok;
      ~CoverOnFailure() {
        if (!ok) out->covered.emplace_back(s.offset, s.offset + s.storedSize);
      }
    } cover{out_, s, planeOk};
    const uint64_t mapBytes = plane == Plane::kDistance ? distanceMapBytes(f.distanceEncoding, f.mapResolution)
                                                        : normalMapBytes(f.normalEncoding, f.mapResolution);
    auto sec = b_.subspan(s.offset, s.storedSize);
    if (sec.size() < kPlaneHeaderSize) {
      usable_ = planeOk = false;
      return report(Code::kPlaneHeader, tag, s.offset, "plane section is shorter than its 32-byte header");
    }
    const uint32_t mapCount = loadU32(&sec[0]);
    const uint32_t hdrMapBytes = loadU32(&sec[4]);
    const uint32_t g = loadU32(&sec[8]);
    const uint32_t blockCount = loadU32(&sec[12]);
    if (std::any_of(&sec[16], &sec[32], [](uint8_t c) { return c != 0; })) {
      if (!report(Code::kPlaneHeader, tag, s.offset + 16, "reserved plane-header bytes are not zero")) return false;
    }
    if (mapCount != f.mapCount || hdrMapBytes != mapBytes || g == 0 || g > mapCount ||
        blockCount != (uint64_t(mapCount) + g - 1) / g || uint64_t(g) * mapBytes > 0xFFFFFFFFull) {
      usable_ = planeOk = false;
      return report(Code::kPlaneHeader, tag, s.offset,
                    "plane header (mapCount " + num(mapCount) + ", mapBytes " + num(hdrMapBytes) +
                        ", mapsPerBlock " + num(g) + ", blockCount " + num(blockCount) +
                        ") is inconsistent with the field (mapCount " + num(f.mapCount) + ", mapBytes " +
                        num(mapBytes) + ")");
    }
    const uint64_t indexEnd = kPlaneHeaderSize + uint64_t(blockCount) * kBlockEntrySize;
    if (indexEnd > sec.size()) {
      usable_ = planeOk = false;
      return report(Code::kBlockBounds, tag, s.offset + 12,
                    "block index of " + num(blockCount) + " entries runs past the section end");
    }
    out_->covered.emplace_back(s.offset, s.offset + indexEnd);
    pi.mapBytes = uint32_t(mapBytes);
    pi.mapsPerBlock = g;
    pi.rawBytes = uint64_t(mapCount) * mapBytes;
    pi.blocks.resize(blockCount);
    BlockWalk walk{alignUp(indexEnd, kBlockAlignment)};
    for (uint32_t bi = 0; bi < blockCount; ++bi) {
      bool blockOk = false;
      if (!blockEntry(plane, s, sec, bi, pi, walk, &blockOk)) return false;
      planeOk = planeOk && blockOk;
    }
    if (planeOk && blockCount > 0) {
      const BlockInfo& last = pi.blocks.back();
      const uint64_t end = last.offset - s.offset + last.storedSize;
      if (end != sec.size()) {
        planeOk = false;
        if (!report(Code::kBlockOrder, tag, s.offset + end,
                    num(sec.size() - end) + " bytes follow the last block inside the section"))
          return false;
      }
    }
    if (!planeOk) {
      usable_ = false;
      return true;
    }
    pi.present = true;
    return true;
  }

  bool metadataSection() {
    const int idx = find(kTagMetadata);
    if (idx < 0) return true;
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    std::vector<uint8_t> raw;
    if (!sectionBytes(idx, &raw)) return usable_ = false, true;
    std::string text(raw.begin(), raw.end());
    const JsonTextCheck check = checkJsonText(text, kMaxJsonDepth);
    if (!check.problem.empty()) {
      usable_ = false;
      return report(Code::kMetadataJson, kTagMetadata, s.offset, "metadata is not valid UTF-8 JSON: " + check.problem);
    }
    if (!check.isObject) {
      usable_ = false;
      return report(Code::kMetadataNotObject, kTagMetadata, s.offset, "metadata JSON is not an object");
    }
    out_->metadata = std::move(text);
    return true;
  }

  // REFN, format.md section 14 (rules 8501-8503), once the field description is known.
  bool refinementSection() {
    const int idx = find(kTagRefinement);
    if (idx < 0 || !out_->fieldOk) return true;
    const SectionInfo& s = out_->info.sections[size_t(idx)];
    std::vector<uint8_t> raw;
    if (!sectionBytes(idx, &raw)) return usable_ = false, true;
    RefinementView view;
    if (Status st = parseRefinement(out_->field, raw, &view); !st) {
      usable_ = false;
      const Error& e = st.error();
      // A stored section's problem is at its byte; a compressed one's at the section.
      const uint64_t at = s.codec == Codec::kStored ? s.offset + e.offset : s.offset;
      return report(e.code, kTagRefinement, at, e.message);
    }
    out_->refinementRaw = std::move(raw);  // (the buffer moves with it: the view stays valid)
    out_->refinement = view;
    return true;
  }

  std::span<const uint8_t> b_;
  const ParseOptions& opt_;
  IssueSink& sink_;
  ParsedFile* out_;
  uint64_t tableOffset_ = 0;
  uint32_t count_ = 0;
  std::vector<bool> sectionUsable_;
  std::vector<uint64_t> sectionEntryAt_;
  bool usable_ = true;
};

}  // namespace

Status checkZstdFrame(std::span<const uint8_t> stored, uint64_t rawSize, Code failCode) {
  ZSTD_frameHeader h{};
  const size_t r = ZSTD_getFrameHeader(&h, stored.data(), stored.size());
  if (ZSTD_isError(r) || r != 0 || h.frameType != ZSTD_frame) return makeError(failCode, "not a zstd frame");
  if (h.frameContentSize == ZSTD_CONTENTSIZE_UNKNOWN)
    return makeError(failCode, "zstd frame does not declare its content size");
  if (h.frameContentSize != rawSize)
    return makeError(failCode, "zstd frame declares " + num(h.frameContentSize) + " bytes, expected " + num(rawSize));
  uint64_t pos = h.headerSize, most = 0;
  for (bool last = false; !last;) {
    if (stored.size() - pos < 3) return makeError(failCode, "zstd frame ends inside a block header");
    const uint32_t bh = uint32_t(stored[pos]) | uint32_t(stored[pos + 1]) << 8 | uint32_t(stored[pos + 2]) << 16;
    pos += 3;
    last = (bh & 1) != 0;
    const uint32_t type = (bh >> 1) & 3, size = bh >> 3;  // 0 raw, 1 RLE, 2 compressed, 3 reserved
    if (type == 3 || size > h.blockSizeMax) return makeError(failCode, "zstd frame holds a malformed block");
    const uint64_t body = type == 1 ? 1 : size;
    if (stored.size() - pos < body) return makeError(failCode, "zstd frame ends inside a block");
    pos += body;
    most += type == 2 ? h.blockSizeMax : size;
  }
  if (h.checksumFlag) pos += 4;
  if (pos != stored.size()) return makeError(failCode, "stored bytes are not exactly one zstd frame");
  if (most < rawSize)
    return makeError(failCode, "zstd frame declares " + num(rawSize) + " bytes but its blocks hold at most " + num(most));
  return {};
}

bool parseFile(std::span<const uint8_t> bytes, const ParseOptions& options, IssueSink& sink, ParsedFile* out) {
  Parser p(bytes, options, sink, out);
  return p.run();
}

}  // namespace vff::detail
