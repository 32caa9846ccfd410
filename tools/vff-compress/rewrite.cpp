#include <chrono>

#include "compress.h"

namespace vff::compress {

Status rewrite(const File& in, const std::string& out, const WriteOptions& options, Report* report) {
  const auto t0 = std::chrono::steady_clock::now();
  auto w = Writer::create(out, in.field(), options);
  if (!w) return std::move(w).error();
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (!in.plane(p).present) continue;
    for (uint32_t b = 0; b < in.plane(p).blocks.size(); ++b) {
      auto bytes = in.blockData(p, b);
      if (!bytes) return std::move(bytes).error();
      if (Status st = w->writeMaps(p, *bytes); !st) return st;
    }
  }
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
