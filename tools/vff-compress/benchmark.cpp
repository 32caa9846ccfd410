// The compression benchmark (vff-compress --benchmark): one run, the same distance payload through
// every codec, side by side. Sizes are compared with the raw payload (mapCount x mapBytes); speeds
// are payload megabytes (10^6 bytes) per second on one thread, the best of --repeat runs, except the
// .vff compression, which uses the writer's threads (all cores) as vff-compress does.
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfThreading.h>
#include <lzma.h>
#include <zstd.h>

#include <Imath/half.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <unistd.h>

#include "cli.h"
#include "compress.h"
#include "convert.h"
#include "platform/parallel.h"

namespace vff::compress {

namespace {

using Clock = std::chrono::steady_clock;

// Best wall time of `repeat` runs of f.
double best(int repeat, const std::function<void()>& f) {
  double t = 1e30;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = Clock::now();
    f();
    t = std::min(t, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return t;
}

// A step that cannot fail on data the benchmark made itself; if it does, stop with the reason.
void must(const Status& st, const char* what) {
  if (st) return;
  cli::printError("vff-compress", std::string("benchmark: ") + what + ": " + st.error().toString());
  std::exit(cli::kExitRuntime);
}

struct Row {
  std::string codec;
  uint64_t bytes = 0;
  double compressSeconds = 0, decompressSeconds = 0;
  std::string note;
};

// Ours: the .vff writer with zstd -19 and hits-med; decoding block by block on one thread.
Row ours(const File& src, const std::vector<uint8_t>& dist, uint32_t g, int repeat, bool* exact) {
  WriteOptions w;
  w.codec = Codec::kZstd;
  w.zstdLevel = 19;
  w.filter = Filter::kHitsMed;
  w.mapsPerBlock = g;
  w.sync = false;
  std::vector<uint8_t> file;
  Row r;
  r.compressSeconds = best(1, [&] { file = writeMemory(src.field(), dist, {}, w).value(); });
  ReadOptions ro;
  ro.checksums = ChecksumPolicy::kNone;  // time the codec, not XXH3 (which runs at memory speed)
  auto f = File::openBuffer(file, ro).value();
  const PlaneInfo& pi = f.plane(Plane::kDistance);
  std::vector<uint8_t> out(dist.size());
  r.decompressSeconds = best(repeat, [&] {
    uint64_t at = 0;
    for (uint32_t b = 0; b < pi.blocks.size(); ++b) {
      must(f.decodeBlock(Plane::kDistance, b, std::span<uint8_t>(out).subspan(at, pi.blocks[b].rawSize)), "decode");
      at += pi.blocks[b].rawSize;
    }
  });
  *exact = out == dist;
  uint32_t filtered = 0;
  for (const BlockInfo& b : pi.blocks) filtered += b.filter == Filter::kHitsMed;
  r.bytes = f.info().sections.back().storedSize;  // the DIST section: block index and blocks
  for (const SectionInfo& s : f.info().sections)
    if (s.tag == kTagDistance) r.bytes = s.storedSize;
  r.codec = "vff zstd-19 + hits-med, G " + std::to_string(pi.mapsPerBlock) + " (" + cli::count(pi.blocks.size(), "block") +
            ")";
  r.note = std::to_string(filtered) + " of " + cli::count(pi.blocks.size(), "block") + " filtered; compress on " +
           cli::count(parallel::resolveThreads(w.threads), "thread");
  return r;
}

Row zstd19(const std::vector<uint8_t>& raw, int repeat, bool* exact) {
  std::vector<uint8_t> c(ZSTD_compressBound(raw.size())), out(raw.size());
  Row r;
  r.codec = "zstd -19 (one frame, whole payload)";
  r.compressSeconds = best(1, [&] { r.bytes = ZSTD_compress(c.data(), c.size(), raw.data(), raw.size(), 19); });
  r.decompressSeconds = best(repeat, [&] { ZSTD_decompress(out.data(), out.size(), c.data(), r.bytes); });
  *exact = out == raw;
  return r;
}

Row xz9(const std::vector<uint8_t>& raw, int repeat, bool* exact) {
  std::vector<uint8_t> c(lzma_stream_buffer_bound(raw.size())), out(raw.size());
  Row r;
  r.codec = "xz -9 (whole payload)";
  size_t n = 0;
  r.compressSeconds = best(1, [&] {
    n = 0;
    if (lzma_easy_buffer_encode(9, LZMA_CHECK_CRC64, nullptr, raw.data(), raw.size(), c.data(), &n, c.size()) != LZMA_OK)
      n = 0;
  });
  r.bytes = n;
  r.decompressSeconds = best(repeat, [&] {
    uint64_t limit = UINT64_MAX;
    size_t inPos = 0, outPos = 0;
    if (lzma_stream_buffer_decode(&limit, 0, nullptr, c.data(), &inPos, n, out.data(), &outPos, out.size()) != LZMA_OK)
      std::fill(out.begin(), out.end(), 0);
  });
  *exact = out == raw;
  return r;
}

// Reads every pixel of every part (Y FLOAT, miss HALF), as an application loading the export would.
void readExrPixels(const std::string& path) {
  Imf::MultiPartInputFile in(path.c_str());
  std::vector<float> y;
  std::vector<Imath::half> miss;
  for (int p = 0; p < in.parts(); ++p) {
    Imf::InputPart part(in, p);
    const Imath::Box2i dw = part.header().dataWindow();
    const size_t texels = size_t(dw.max.x - dw.min.x + 1) * size_t(dw.max.y - dw.min.y + 1);
    y.resize(texels);
    miss.resize(texels);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), dw));
    fb.insert("miss", Imf::Slice::Make(Imf::HALF, miss.data(), dw));
    part.setFrameBuffer(fb);
    part.readPixels(dw.min.y, dw.max.y);
  }
}

Row exr(const convert::FieldData& d, convert::ExrCompression c, const char* name, const std::string& path, int repeat) {
  convert::ExrWriteOptions o;
  o.compression = c;
  Row r;
  r.codec = std::string("OpenEXR ") + name + " (FLOAT Y + HALF miss per slice)";
  r.compressSeconds = best(1, [&] { must(convert::writeExr(path, d, o), "EXR export"); });
  r.bytes = std::filesystem::file_size(path);
  r.decompressSeconds = best(repeat, [&] { readExrPixels(path); });
  std::filesystem::remove(path);
  r.note = c == convert::ExrCompression::kDwaa ? "lossy" : "";
  return r;
}

// The filters we chose among (spec/format.md, "Why this filter"): each map's raw bytes (misses
// included) minus a prediction from its left (a), upper (b) and upper-left (c) neighbours, then
// zstd -19 per 256 KiB block like the writer; plus hits-med itself through the writer.
uint64_t candidateBytes(const std::vector<uint8_t>& raw, uint32_t m, int kind) {
  const uint64_t mapBytes = uint64_t(m) * m;
  const uint64_t block = std::max<uint64_t>(1, (256u << 10) / mapBytes) * mapBytes;
  std::vector<uint8_t> f(raw.size());
  for (uint64_t first = 0; first < raw.size(); first += mapBytes)
    for (uint32_t y = 0; y < m; ++y)
      for (uint32_t x = 0; x < m; ++x) {
        const uint8_t* p = &raw[first];
        const int a = x ? p[y * m + x - 1] : y ? p[(y - 1) * m + x] : 0;
        const int b = y ? p[(y - 1) * m + x] : a;
        const int c = x && y ? p[(y - 1) * m + x - 1] : b;
        const int pred = kind == 0 ? 0 : kind == 1 ? a : kind == 2 ? b : kind == 3 ? a + b - c
                                                                  : std::min(std::max(a, b), std::max(std::min(a, b), a + b - c));
        f[first + y * m + x] = uint8_t(p[y * m + x] - pred);
      }
  uint64_t total = 0;
  std::vector<uint8_t> out(ZSTD_compressBound(block));
  for (uint64_t at = 0; at < f.size(); at += block) {
    const size_t n = size_t(std::min<uint64_t>(block, f.size() - at));
    total += std::min<uint64_t>(n, ZSTD_compress(out.data(), out.size(), f.data() + at, n, 19));
  }
  return total;
}

void printCandidates(const std::vector<uint8_t>& raw, uint32_t m, uint64_t hitsMedBytes) {
  std::printf("  filter candidates, zstd -19 per 256 KiB block (stored size of the blocks):\n");
  const char* names[] = {"none (zstd alone)", "raw - left", "raw - up", "raw - gradient (a + b - c)", "raw - MED"};
  const uint64_t none = candidateBytes(raw, m, 0);
  for (int k = 0; k < 5; ++k) {
    const uint64_t bytes = k == 0 ? none : candidateBytes(raw, m, k);
    std::printf("    %-36s %12llu  %.3fx none\n", names[k], static_cast<unsigned long long>(bytes), double(bytes) / double(none));
  }
  std::printf("    %-36s %12llu  %.3fx none\n", "hits-med (mask + MED of hits)", static_cast<unsigned long long>(hitsMedBytes),
              double(hitsMedBytes) / double(none));
}

}  // namespace

int benchmark(const std::vector<std::string>& files, int repeat, const std::string& tmpDir, bool candidates) {
  Imf::setGlobalThreadCount(0);  // OpenEXR on the calling thread only: per-core figures
  for (const std::string& path : files) {
    auto f = File::open(path);
    if (!f) return cli::reportError("vff-compress", path, f.error());
    const FieldDesc& fd = f->field();
    if (fd.distanceEncoding != DistanceEncoding::kUnorm8Diameter && fd.distanceEncoding != DistanceEncoding::kUnorm8Chord) {
      cli::printError("vff-compress", path + ": the benchmark needs an 8-bit distance encoding, not " +
                                          distanceEncodingName(fd.distanceEncoding));
      return cli::kExitUnsupported;
    }
    convert::FieldData d;
    d.field = fd;
    d.field.normalEncoding = NormalEncoding::kNone;  // the distance payload only
    d.layout = f->layout();
    for (uint32_t b = 0; b < f->plane(Plane::kDistance).blocks.size(); ++b) {
      auto bytes = f->blockData(Plane::kDistance, b);
      if (!bytes) return cli::reportError("vff-compress", path, bytes.error());
      d.distance.insert(d.distance.end(), bytes->begin(), bytes->end());
    }
    const std::vector<uint8_t>& raw = d.distance;
    std::printf("%s: %s of %ux%u %s, distance payload %s\n", path.c_str(), cli::count(fd.mapCount, "map").c_str(), fd.mapResolution,
                fd.mapResolution, distanceEncodingName(fd.distanceEncoding), cli::formatBytes(raw.size()).c_str());
    std::vector<Row> rows;
    bool exact[4] = {};
    const uint32_t g1m = std::max<uint32_t>(1, uint32_t((1u << 20) / f->plane(Plane::kDistance).mapBytes));
    rows.push_back(ours(*f, raw, 0, repeat, &exact[0]));
    rows.push_back(ours(*f, raw, std::min(g1m, fd.mapCount), repeat, &exact[1]));
    rows.push_back(zstd19(raw, repeat, &exact[2]));
    rows.push_back(xz9(raw, repeat, &exact[3]));
    const std::string tmp =
        (std::filesystem::path(tmpDir) / ("vff-compress-bench-" + std::to_string(::getpid()) + ".exr")).string();
    rows.push_back(exr(d, convert::ExrCompression::kZip, "ZIP", tmp, repeat));
    rows.push_back(exr(d, convert::ExrCompression::kPiz, "PIZ", tmp, repeat));
    rows.push_back(exr(d, convert::ExrCompression::kDwaa, "DWAA", tmp, repeat));
    for (int i = 0; i < 4; ++i)
      if (!exact[i]) {
        cli::printError("vff-compress", rows[size_t(i)].codec + " did not decode to the payload");
        return cli::kExitRuntime;
      }
    const double zstdBytes = double(rows[2].bytes);
    const double mb = double(raw.size()) / 1e6;
    std::printf("  %-52s %12s %8s %8s %12s %14s  %s\n", "codec", "bytes", "ratio", "vs zstd", "compr MB/s",
                "decompr MB/s", "note");
    for (const Row& r : rows)
      std::printf("  %-52s %12llu %8.2f %8.3f %12.1f %14.1f  %s\n", r.codec.c_str(),
                  static_cast<unsigned long long>(r.bytes), double(raw.size()) / double(r.bytes),
                  double(r.bytes) / zstdBytes, mb / r.compressSeconds, mb / r.decompressSeconds, r.note.c_str());
    const Row& o = rows[0];
    if (candidates) printCandidates(raw, fd.mapResolution, o.bytes);
    std::printf("  targets: size %.3fx zstd -19 (<= 0.8: %s); decompression %.0f MB/s on one core (>= 1000: %s)\n\n",
                double(o.bytes) / zstdBytes, double(o.bytes) <= 0.8 * zstdBytes ? "met" : "NOT met",
                mb / o.decompressSeconds, mb / o.decompressSeconds >= 1000 ? "met" : "NOT met");
  }
  return cli::kExitSuccess;
}

}  // namespace vff::compress
