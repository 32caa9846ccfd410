// gen_valid.cpp - the valid conformance vectors (gen_valid.h).
#include "gen_valid.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <span>

#include "conformance.h"
#include "gen_reference.h"
#include "gen_vff.h"

namespace vff::gen {

namespace {

constexpr uint64_t kMaxValidBytes = 64 << 10;

FieldDesc makeField(DistanceEncoding enc, NormalEncoding normals, PositionScheme scheme, uint32_t param,
                    DirectionScheme dir, uint32_t m, Sphere sphere) {
  FieldDesc f;
  f.sphere = sphere;
  f.positionScheme = scheme;
  f.positionParam = param;
  f.mapCount = positionCount(scheme, param).value();
  f.directionScheme = dir;
  f.mapResolution = m;
  f.distanceEncoding = enc;
  f.normalEncoding = normals;
  return f;
}

WriteOptions makeOptions(Codec codec, LayoutTarget target, uint32_t gutter, uint32_t maxTextureSize,
                         uint32_t mapsPerBlock) {
  WriteOptions o;
  o.codec = codec;
  o.zstdLevel = kZstdLevel;
  o.mapsPerBlock = mapsPerBlock;
  o.layout.target = target;
  o.layout.gutter = gutter;
  o.layout.maxTextureSize = maxTextureSize;
  o.sync = false;
  return o;
}

}  // namespace

std::vector<ValidCase> validCases() {
  using DE = DistanceEncoding;
  using NE = NormalEncoding;
  using PS = PositionScheme;
  using DS = DirectionScheme;
  using LT = LayoutTarget;
  const Sphere unitish{{0, 0, 0}, 1.27f};  // 2R/254 = 0.01: unorm8-diameter codes decode to round numbers
  const Sphere u16{{0, 0, 0}, 32.767f};    // 2R/65534 = 0.001 for unorm16-diameter
  std::vector<ValidCase> v;
  v.push_back({"u8d-stored", "unorm8-diameter, stored, octa-hemi2 n=1 (10 maps of 8x8), one block, 2d-array",
               makeField(DE::kUnorm8Diameter, NE::kNone, PS::kOctaHemi2, 1, DS::kConcentricEqualArea, 8, unitish),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 2048, 0)});
  v.push_back({"u8d-zstd-normals-meta",
               "unorm8-diameter, zstd, oct-snorm16 normals, zstd metadata, octa-hemi2 n=2 (26 maps), hemi-octahedral, "
               "8 maps per block (last block 2)",
               makeField(DE::kUnorm8Diameter, NE::kOctSnorm16, PS::kOctaHemi2, 2, DS::kHemiOctahedral, 8,
                         {{0.5f, -1.0f, 2.0f}, 1.27f}),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 8), true});
  v.push_back(
      {"u8c-stored-normals-3d-gutter1",
       "unorm8-chord, stored, normals, 3d target, gutter 1, maxTextureSize 30 (3x3 tiles, 2 slices), "
       "4 maps per block",
       makeField(DE::kUnorm8Chord, NE::kOctSnorm16, PS::kOctaHemi2, 1, DS::kConcentricEqualArea, 8, {{0, 0, 0}, 2.0f}),
       makeOptions(Codec::kStored, LT::kTexture3D, 1, 30, 4)});
  v.push_back(
      {"u8c-zstd-meta-1map-per-block",
       "unorm8-chord, zstd, zstd metadata, ea-octa-grid n=3 (9 maps of 16x16), hemi-octahedral, one map per block",
       makeField(DE::kUnorm8Chord, NE::kNone, PS::kEqualAreaOctaGrid, 3, DS::kHemiOctahedral, 16,
                 {{-3.0f, 1.0f, 0.25f}, 4.0f}),
       makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 1), true});
  v.push_back({"u16d-stored-meta-slices",
               "unorm16-diameter, stored, stored metadata, fibonacci n=7, maxTextureSize 16 (2x2 tiles, 2 slices), "
               "3 maps per block",
               makeField(DE::kUnorm16Diameter, NE::kNone, PS::kSphericalFibonacci, 7, DS::kConcentricEqualArea, 8,
                         {{1.0f, 2.0f, 3.0f}, 32.767f}),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 16, 3), true});
  v.push_back(
      {"u16d-zstd-normals-gutter2",
       "unorm16-diameter, zstd, normals, fibonacci n=5 (5 maps of 16x16), gutter 2, maxTextureSize 40 "
       "(2x2 tiles, 2 slices)",
       makeField(DE::kUnorm16Diameter, NE::kOctSnorm16, PS::kSphericalFibonacci, 5, DS::kConcentricEqualArea, 16, u16),
       makeOptions(Codec::kZstd, LT::kTexture2DArray, 2, 40, 0)});
  v.push_back({"bit1-stored", "bit1, stored, octa-hemi2 n=2 (26 maps of 8x8), hemi-octahedral, one block",
               makeField(DE::kBit1, NE::kNone, PS::kOctaHemi2, 2, DS::kHemiOctahedral, 8, {{0, 0, 0}, 1.0f}),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 2048, 0)});
  v.push_back({"bit1-zstd-normals-meta-3d",
               "bit1, zstd, normals, zstd metadata, fibonacci n=6 (6 maps of 16x16), 3d target, maxTextureSize 32 "
               "(2x2 tiles, 2 slices), 5 maps per block (last block 1)",
               makeField(DE::kBit1, NE::kOctSnorm16, PS::kSphericalFibonacci, 6, DS::kConcentricEqualArea, 16,
                         {{0.0f, 0.0f, -0.5f}, 1.0f}),
               makeOptions(Codec::kZstd, LT::kTexture3D, 0, 32, 5), true});
  v.push_back({"u8d-zstd-hits-med",
               "format 1.1: unorm8-diameter, zstd with filter 1 hits-med, octa-hemi2 n=2 (26 maps of 16x16), one block",
               makeField(DE::kUnorm8Diameter, NE::kNone, PS::kOctaHemi2, 2, DS::kConcentricEqualArea, 16, unitish),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 26)});
  v.back().options.filter = Filter::kHitsMed;
  v.push_back({"bc4-zstd-normals-slices",
               "format 1.2: bc4-diameter, zstd, normals, octa-hemi2 n=2 (26 maps of 16x16), maxTextureSize 64 "
               "(4x4 tiles, 2 slices, the second with 6 unused tiles)",
               makeField(DE::kBc4Diameter, NE::kOctSnorm16, PS::kOctaHemi2, 2, DS::kConcentricEqualArea, 16, unitish),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 64, 0)});
  // Format 1.3: REFN (spec/format.md section 14). The first has 3 padding bytes after its 41 bytes of
  // unsure bits and 4 unused bits in the last of them; the second is compressed, after META and NORM.
  v.push_back({"u8d-refined",
               "format 1.3: unorm8-diameter, stored, ea-octa-grid n=3 (9 maps of 6x6), one block; REFN stored: "
               "margin 0.1875, the silhouette texels unsure (41 bytes of bits, 3 padding bytes), an octahedron "
               "(6 vertices, 8 triangles)",
               makeField(DE::kUnorm8Diameter, NE::kNone, PS::kEqualAreaOctaGrid, 3, DS::kConcentricEqualArea, 6,
                         unitish),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 2048, 0)});
  v.back().refined = true;
  v.back().margin = 0.1875f;
  v.push_back({"u8c-zstd-normals-meta-refined",
               "format 1.3: unorm8-chord, zstd, normals, zstd metadata, fibonacci n=7 (7 maps of 8x8), "
               "hemi-octahedral, 4 maps per block (last block 3); REFN zstd: margin 0, the silhouette texels "
               "unsure, an octahedron split once (18 vertices, 32 triangles)",
               makeField(DE::kUnorm8Chord, NE::kOctSnorm16, PS::kSphericalFibonacci, 7, DS::kHemiOctahedral, 8,
                         {{0.5f, -1.0f, 2.0f}, 2.0f}),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 4), true});
  v.back().refined = true;
  v.back().margin = 0.0f;
  v.back().meshLevel = 1;
  ValidCase unknownOptional = v[0];
  unknownOptional.name = "unknown-section-optional";
  unknownOptional.description = "u8d-stored plus an unknown section 'XTST' with flags 0 (a reader skips it)";
  unknownOptional.post = Post::kUnknownOptional;
  v.push_back(unknownOptional);
  ValidCase unknownCopySafe = v[4];
  unknownCopySafe.name = "unknown-section-copysafe";
  unknownCopySafe.description = "u16d-stored-meta-slices plus an unknown section 'XTSC' with flags COPY_SAFE";
  unknownCopySafe.post = Post::kUnknownCopySafe;
  v.push_back(unknownCopySafe);
  // META texts at the edges of RFC 8259 that rule 8001 accepts (spec/format.md section 9).
  const auto metaCase = [&](const char* name, const char* description, std::string text) {
    ValidCase c = v[4];
    c.name = name;
    c.description = description;
    c.post = Post::kMetaText;
    c.metaText = std::move(text);
    v.push_back(c);
  };
  metaCase("meta-whitespace", "u16d-stored-meta-slices with META ' \\t\\r\\n{\"a\" : [ 1 , 2 ] , \"b\" : { } }\\r\\n\\t ': "
           "whitespace before, inside and after the object",
           " \t\r\n{\"a\" : [ 1 , 2 ] , \"b\" : { } }\r\n\t ");
  metaCase("meta-any-magnitude", "u16d-stored-meta-slices with META numbers beyond binary64: 1e400, -1E+400, 1e-400 "
           "and a 30-digit integer",
           R"({"big":1e400,"negative":-1E+400,"tiny":1e-400,"long":123456789012345678901234567890})");
  metaCase("meta-escapes", "u16d-stored-meta-slices with META strings holding a surrogate pair escape, \\u0000, "
           "\\/ and raw UTF-8 of 2 and 4 bytes",
           "{\"pair\":\"\\ud83d\\ude00\",\"nul\":\"\\u0000\",\"slash\":\"\\/\",\"raw\":\"\xC3\xA9\xF0\x9F\x98\x80\"}");
  ValidCase roCompat = v[0];
  roCompat.name = "rocompat-bit0";
  roCompat.description = "u8d-stored with roCompatFeatures bit 0 set: readable, validator warning 3008";
  roCompat.post = Post::kRoCompat;
  v.push_back(roCompat);
  return v;
}

namespace {

std::string metadataFor(const ValidCase& c) {
  // Long and repetitive enough that zstd shrinks it (the writer stores a section that does not).
  std::string notes;
  for (int i = 0; i < 8; ++i) notes += "Conformance vector: a small precomputed visibility field. ";
  return R"({"conformance": {"vector": ")" + c.name + R"(", "generator": "vff-conformance-gen", "notes": ")" + notes +
         R"("}, "scene": {"shape": "sphere", "radiusOverR": 0.7, "offsetOverR": [0.1, -0.08, 0.12]}})";
}

const char* kUnknownPayload = "An unknown optional section: readers skip it, tools may copy it when COPY_SAFE.\n";

}  // namespace

BuiltValid buildValid(const ValidCase& c) {
  BuiltValid v;
  v.c = c;
  v.content = makeContent(c.field);
  WriteOptions wo = c.options;
  if (c.metadata) wo.metadataJson = metadataFor(c);
  if (c.refined) {
    v.refinement = makeRefinementSource(c.field, v.content, c.margin, c.meshLevel);
    wo.refinement = v.refinement.view();
  }
  auto bytes = writeMemory(c.field, v.content.distance, v.content.normals, wo);
  if (!bytes) die(c.name + ": writeMemory failed: " + bytes.error().toString());
  Vff f{std::move(*bytes)};
  const auto* payload = reinterpret_cast<const uint8_t*>(kUnknownPayload);
  const std::span<const uint8_t> unknown(payload, std::strlen(kUnknownPayload));
  switch (c.post) {
    case Post::kNone:
      break;
    case Post::kUnknownOptional:
      f.appendSection(fourcc('X', 'T', 'S', 'T'), 0, unknown);
      break;
    case Post::kUnknownCopySafe:
      f.appendSection(fourcc('X', 'T', 'S', 'C'), kSectionCopySafe, unknown);
      break;
    case Post::kRoCompat:
      st64(f.b, 32, 1);
      f.sealHeader();
      break;
    case Post::kMetaText:
      f.replaceStored(kTagMetadata, c.metaText);
      break;
  }
  v.bytes = std::move(f.b);
  v.layout = canonicalLayout(c.field, c.options.layout);
  auto check = computeLayout(c.field, c.options.layout);
  if (!check || !sameLayout(*check, v.layout))
    fail(c.name + ": libvff's computeLayout differs from the canonical rule");
  if (c.post == Post::kMetaText) v.metadata = c.metaText;
  else if (c.metadata) v.metadata = nlohmann::json::parse(wo.metadataJson).dump();
  v.zstd = c.options.codec == Codec::kZstd;
  return v;
}

namespace {

// Every map and packed slice of every plane, read back with libvff under each checksum policy.
void checkReadBack(const BuiltValid& v) {
  const std::string& n = v.c.name;
  for (ChecksumPolicy policy : conformance::kPolicies) {
    ReadOptions ro;
    ro.checksums = policy;
    auto f = File::openMemory(v.bytes, ro);
    if (!f) {
      fail(n + ": open failed: " + f.error().toString());
      continue;
    }
    if (!sameLayout(f->layout(), v.layout)) fail(n + ": the file's layout differs from the canonical layout");
    if (std::string(f->metadata()) != v.metadata) fail(n + ": metadata differs");
    const RefinementView& r = f->refinement();
    const Refinement& want = v.refinement;
    if (r.empty() != !v.c.refined || r.margin != want.margin || r.unsureTexels != want.unsureTexels ||
        !std::equal(r.unsure.begin(), r.unsure.end(), want.unsure.begin(), want.unsure.end()) ||
        !std::equal(r.positions.begin(), r.positions.end(), want.positions.begin(), want.positions.end()) ||
        !std::equal(r.indices.begin(), r.indices.end(), want.indices.begin(), want.indices.end()))
      fail(n + ": File::refinement() differs from the source refinement");
    for (Plane p : {Plane::kDistance, Plane::kNormal}) {
      if (p == Plane::kNormal && !f->hasNormals()) continue;
      const Bytes& src = p == Plane::kDistance ? v.content.distance : v.content.normals;
      const uint64_t mb = f->plane(p).mapBytes;
      for (uint32_t k = 0; k < v.c.field.mapCount; ++k) {
        auto d = f->mapData(p, k);
        if (!d || !std::equal(d->begin(), d->end(), src.begin() + std::ptrdiff_t(k * mb),
                              src.begin() + std::ptrdiff_t((k + 1) * mb)))
          fail(n + ": map " + std::to_string(k) + " of the " + planeName(p) + " plane reads back differently");
      }
      const auto slices = composeSlices(v.c.field, v.layout, v.content, p);
      Bytes buf(f->sliceBytes(p));
      for (uint32_t s = 0; s < slices.size(); ++s) {
        Status st = f->readSlice(p, s, buf);
        if (!st || buf != slices[s])
          fail(n + ": slice " + std::to_string(s) + " of the " + planeName(p) +
               " plane differs from the composed slice");
      }
    }
  }
}

// Every distance block is filtered, and its frame holds exactly the stream the spec defines.
void checkHitsMed(const BuiltValid& v, const Vff& file) {
  const std::string& n = v.c.name;
  const uint64_t mb = distanceMapBytes(v.c.field.distanceEncoding, v.c.field.mapResolution);
  const uint32_t g = ld32(v.bytes, file.sec(kTagDistance) + 8);
  for (uint32_t b = 0; b < file.blockCount(kTagDistance); ++b) {
    if (v.bytes[file.blockEntry(kTagDistance, b) + 21] != uint8_t(Filter::kHitsMed)) {
      fail(n + ": distance block " + std::to_string(b) + " is not filtered");
      continue;
    }
    const uint64_t first = uint64_t(b) * g * mb;
    const uint64_t size = std::min<uint64_t>(uint64_t(g) * mb, v.content.distance.size() - first);
    const auto raw = std::span<const uint8_t>(v.content.distance).subspan(first, size);
    const auto stored =
        std::span<const uint8_t>(v.bytes).subspan(file.block(kTagDistance, b), file.blockSize(kTagDistance, b));
    if (zstdContent(stored) != hitsMedStream(raw, v.c.field.mapResolution))
      fail(n + ": distance block " + std::to_string(b) + " does not hold the hits-med stream of its maps");
  }
  if (ld16(v.bytes, 10) != 1 || ld64(v.bytes, 24) != (kFeatureZstd | kFeatureFilters))
    fail(n + ": a filtered file must be version 1.1 with incompatFeatures zstd | filters");
}

// spec/format.md 7.4's writer rules, checked with the reference decoder: a miss decodes to 255,
// a hit to a code <= 254 near the code it was made from; libvff's loadCode agrees texel for texel.
void checkBc4(const BuiltValid& v) {
  const std::string& n = v.c.name;
  if (ld16(v.bytes, 10) != 2 || !(ld64(v.bytes, 24) & kFeatureBc4))
    fail(n + ": a bc4-diameter file must be version 1.2 with incompatFeatures bit 2");
  const uint32_t m = v.c.field.mapResolution;
  const uint64_t mb = distanceMapBytes(v.c.field.distanceEncoding, m);
  uint32_t worst = 0;
  for (uint32_t k = 0; k < v.c.field.mapCount; ++k) {
    const auto map = std::span<const uint8_t>(v.content.distance).subspan(k * mb, mb);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const uint32_t want = v.content.codes[(uint64_t(k) * m + j) * m + i];
        const uint32_t got = referenceBc4Code(map, m, i, j);
        if (got != loadCode(v.c.field.distanceEncoding, map, m, i, j))
          fail(n + ": libvff's loadCode differs from the reference BC4 decoder");
        if ((want == 255) != (got == 255)) fail(n + ": a BC4 block turned a miss into a hit or a hit into a miss");
        if (want != 255) worst = std::max(worst, uint32_t(std::abs(int(got) - int(want))));
      }
  }
  if (worst > 8) fail(n + ": a BC4 texel is " + std::to_string(worst) + " codes from the code it was made from");
}

// REFN (format 1.3): the last section, flags 0, with the vector's codec; its raw bytes are exactly
// what the reference encoder makes from the source, and the reference decoder (both written from
// spec/format.md section 14) reads the source back from them.
void checkRefinement(const BuiltValid& v, const Vff& file) {
  const std::string& n = v.c.name;
  if (ld16(v.bytes, 10) != 3) fail(n + ": a file with REFN must be version 1.3");
  if (file.indexOf(kTagRefinement) != int(file.count()) - 1) fail(n + ": REFN is not the last section");
  const uint64_t e = file.entry(kTagRefinement);
  if (ld32(v.bytes, e + 4) != 0) fail(n + ": REFN flags are not 0");
  const uint16_t codec = ld16(v.bytes, e + 32);
  if (codec != uint16_t(v.c.options.codec)) fail(n + ": REFN is not written with the vector's codec");
  if (codec == 1 && !(ld64(v.bytes, 24) & kFeatureZstd)) fail(n + ": a zstd REFN without the zstd feature bit");
  const auto stored = std::span<const uint8_t>(v.bytes).subspan(file.sec(kTagRefinement), file.secSize(kTagRefinement));
  const Bytes raw = codec == 1 ? zstdContent(stored) : Bytes(stored.begin(), stored.end());
  if (raw.size() != ld64(v.bytes, e + 24)) fail(n + ": REFN rawSize differs from its content");
  if (raw != referenceRefinementBytes(v.c.field, v.refinement))
    fail(n + ": REFN's bytes differ from the reference encoding of the source");
  ReferenceRefinement ref;
  std::string why;
  if (const uint32_t id = referenceDecodeRefinement(v.c.field, raw, &ref, &why); id != 0)
    fail(n + ": the reference decoder rejects REFN with " + std::to_string(id) + ": " + why);
  else if (ref.margin != v.refinement.margin || ref.unsureTexels != v.refinement.unsureTexels ||
           ref.unsure != v.refinement.unsure || ref.positions != v.refinement.positions ||
           ref.indices != v.refinement.indices)
    fail(n + ": the reference decoder reads REFN differently from the source");
  const uint64_t texels = uint64_t(v.c.field.mapCount) * v.c.field.mapResolution * v.c.field.mapResolution;
  if (v.refinement.unsureTexels == 0 || v.refinement.unsureTexels >= texels)
    fail(n + ": the refinement needs both sure and unsure texels");
}

}  // namespace

void checkValid(const BuiltValid& v) {
  const std::string& n = v.c.name;
  if (v.bytes.size() >= kMaxValidBytes) fail(n + ": " + std::to_string(v.bytes.size()) + " bytes, above 64 KiB");
  Report rep = validate(v.bytes);
  if (!rep.valid())
    for (const Issue& i : rep.issues) fail(n + ": validator: " + codeName(i.code) + ": " + i.message);
  checkReadBack(v);
  const Vff file{v.bytes};
  if (v.c.options.codec == Codec::kZstd) {
    bool anyZstdBlock = false;
    for (uint32_t tag : {kTagDistance, kTagNormal})
      if (file.indexOf(tag) >= 0)
        for (uint32_t b = 0; b < file.blockCount(tag); ++b) anyZstdBlock |= v.bytes[file.blockEntry(tag, b) + 20] == 1;
    if (!anyZstdBlock) fail(n + ": a zstd vector without any zstd block");
    if (v.c.metadata && ld16(v.bytes, file.entry(kTagMetadata) + 32) != 1) fail(n + ": metadata was not compressed");
  }
  if (v.c.refined) {
    checkRefinement(v, file);
  } else if (file.indexOf(kTagRefinement) >= 0) {
    fail(n + ": REFN in a vector that is not refined");
  }
  if (v.c.options.filter == Filter::kHitsMed) {
    checkHitsMed(v, file);
  } else if (v.c.field.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    checkBc4(v);
  } else if (ld16(v.bytes, 10) != (v.c.refined ? 3 : 0)) {
    fail(n + ": a file without 1.1, 1.2 or 1.3 features must be version 1.0");
  }
  if (v.content.hits == 0 || v.content.misses == 0) fail(n + ": the content needs both hits and misses");
}

}  // namespace vff::gen
