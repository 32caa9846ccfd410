#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <span>
#include <vector>

#include "compress.h"

namespace vff::compress {

namespace {

// One block of unorm8-diameter maps -> bc4-diameter maps, accounting the code changes.
void toBc4(std::span<const uint8_t> codes, uint32_t m, std::vector<uint8_t>* blocks, Bc4Report* r) {
  const size_t texels = size_t(m) * m, maps = codes.size() / texels;
  blocks->resize(maps * texels / 2);
  std::vector<uint8_t> back(texels);
  for (size_t k = 0; k < maps; ++k) {
    const auto src = codes.subspan(k * texels, texels);
    const std::span<uint8_t> dst(blocks->data() + k * texels / 2, texels / 2);
    encodeBc4Map(src, m, dst);
    decodeBc4Map(dst, m, back);
    for (size_t t = 0; t < texels; ++t) {
      if (src[t] == 255) continue;
      const uint32_t e = uint32_t(std::abs(int(back[t]) - int(src[t])));
      ++r->hits;
      r->changed += e != 0;
      r->maxError = std::max(r->maxError, e);
      r->sumSquared += double(e) * e;
    }
  }
}

// The refinement of `in`, set on the writer: as it is, or (remake) made again for the new maps from
// its triangles, with its margin.
Status keepRefinement(const File& in, const FieldDesc& field, std::span<const uint8_t> maps, bool remake, Writer* w,
                      RefinementReport* r) {
  const RefinementView& refinement = in.refinement();
  if (refinement.empty()) return {};
  r->present = true;
  r->unsureBefore = refinement.unsureTexels;
  r->unsureAfter = refinement.unsureTexels;
  if (!remake) return w->setRefinement(refinement);
  RefineOptions o;
  o.marginSpreads = refinement.margin / refineSpread(field);
  auto made = makeRefinement(field, maps, refinement.positions, refinement.indices, o);
  if (!made) return std::move(made).error();
  r->remade = true;
  r->unsureAfter = made->unsureTexels;
  return w->setRefinement(made->view());
}

}  // namespace

Status rewrite(const File& in, const std::string& out, const FieldDesc& field, const WriteOptions& options, bool bc4,
               Report* report) {
  const auto t0 = std::chrono::steady_clock::now();
  auto w = Writer::create(out, field, options);
  if (!w) return std::move(w).error();
  std::vector<uint8_t> converted, allConverted;  // with bc4 and a refinement: every new block, for makeRefinement
  const RefinementView& refinement = in.refinement();
  const bool remake = bc4 && !refinement.empty();
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (!in.plane(p).present) continue;
    for (uint32_t b = 0; b < in.plane(p).blocks.size(); ++b) {
      auto bytes = in.blockData(p, b);
      if (!bytes) return std::move(bytes).error();
      std::span<const uint8_t> maps = *bytes;
      if (bc4 && p == Plane::kDistance) {
        toBc4(maps, field.mapResolution, &converted, &report->bc4);
        maps = converted;
        if (remake) allConverted.insert(allConverted.end(), converted.begin(), converted.end());
      }
      if (Status st = w->writeMaps(p, maps); !st) return st;
    }
  }
  report->bc4.done = bc4;
  if (Status st = keepRefinement(in, field, allConverted, remake, &*w, &report->refinement); !st) return st;
  if (Status st = w->finish(); !st) return st;
  report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto back = File::open(out);
  if (!back) return std::move(back).error();
  report->fileBytes = back->bytes().size();
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    const PlaneInfo& pi = back->plane(p);
    PlaneReport& r = report->planes[size_t(p)];
    r.present = pi.present;
    r.rawBytes = pi.rawBytes;
    r.storedBytes = pi.storedBytes;
    for (const BlockInfo& b : pi.blocks) {
      r.blockStored.push_back(b.storedSize);
      r.filtered += b.filter != Filter::kNone;
      r.zstd += b.codec == Codec::kZstd;
    }
  }
  return {};
}

}  // namespace vff::compress
