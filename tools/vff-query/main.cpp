// vff-query: answers rays with a visibility field, from the shell.
//
//   vff-query bunny.vff --ray 0 0 5 0 0 -1                    one ray (repeatable); CSV on stdout
//   vff-query bunny.vff < rays.csv --format jsonl            CSV or JSON lines on stdin
//   vff-query bunny.vff -i rays.npy -o hits.npy              (N, 6) or (N, 8) float32 in, (N, 12) out
//   vff-query bunny.vff -i rays.csv --interpolated --visibility --rotate 0 1 0 0.5 --translate 2 0 0
//   vff-query scene.glb --mesh 2 --ray 0 0 5 0 0 -1          mesh 2's field of a glTF asset (mesh space)
//
// Every answer is the C++ batch query's (FieldQuery or Instance), split over threads in chunks;
// the answers do not depend on the thread count. A .npy input is read whole (file_bytes.h) and
// turned into rays chunk by chunk on the threads that answer them; a .npy output file is written by
// those threads too, each chunk's rows at their offset, so that no whole copy of the answers is
// ever made.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <new>
#include <utility>

#include "cli.h"
#include "file_bytes.h"
#include "gltf_field.h"
#include "npy.h"
#include "platform/parallel.h"
#include "rays.h"
#include "vff/vff.h"

namespace {

using namespace vff;
using namespace vff::query_tool;

constexpr const char* kProg = "vff-query";
constexpr size_t kChunk = 4096;  // rays per batch call on one thread (its rays and answers stay in L2)

struct Options {
  std::string field;
  int mesh = -1;  // --mesh: the mesh of a glTF asset whose field answers
  std::vector<std::vector<float>> rays;
  std::string input;
  std::string output = "-";
  std::string format;
  bool interpolated = false;
  bool refined = false;
  bool visibility = false;
  float tmin = 0.0f;
  float tmax = std::numeric_limits<float>::infinity();
  float intraBias = -1.0f;
  std::string rayOrigin = "on-object";
  std::vector<float> rotate, translate;
  float scale = 1.0f;
  unsigned threads = 0;
  std::string checksums = "all";
  bool noSites = false;
  std::string columns;
  bool timing = false;
};

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) { return cli::runGuarded(kProg, run, argc, argv); }

namespace {

void addOptions(CLI::App& app, Options& o) {
  cli::addVersionFlag(app, kProg);
  app.add_option("field", o.field,
                 "the .vff field to query (a regular file), or a glTF asset (.gltf, .glb) whose meshes carry fields "
                 "(VFF_visibility_field; see --mesh)")
      ->required();
  app.add_option("--mesh", o.mesh,
                 "glTF input: answer with the field of mesh I (rays in the mesh's own space; --rotate, --translate "
                 "and --scale still place it); needed when several meshes carry one")
      ->check(CLI::NonNegativeNumber)
      ->option_text("I");
  app.add_option("--ray", o.rays, "a ray: origin x y z, direction x y z (repeatable)")
      ->expected(6)
      ->allow_extra_args(false)
      ->option_text("OX OY OZ DX DY DZ");
  app.add_option("-i,--input", o.input,
                 "rays from a file: a .npy float32 array (N, 6) or (N, 8) (ox oy oz dx dy dz [tmin tmax]), or text "
                 "lines, CSV or JSON (- or nothing: standard input, when no --ray is given; a named pipe is read "
                 "as a stream, like standard input)");
  app.add_option("-o,--output", o.output, "where the answers go (- : standard output; a file is written atomically)")
      ->capture_default_str();
  app.add_option("--format", o.format, "answers as csv, jsonl or npy (default: npy for an output named *.npy, else csv)")
      ->check(CLI::IsMember({"csv", "jsonl", "npy"}));
  auto* interpolated =
      app.add_flag("--interpolated", o.interpolated, "interpolated reconstruction (default: the paper's nearest)");
  app.add_flag("--refined", o.refined,
               "refined reconstruction: the rays the maps are unsure of cast through the field's triangles (a field "
               "baked with vff-bake --refine)")
      ->excludes(interpolated);
  app.add_flag("--visibility", o.visibility, "add a column: the ray's visibility (0..1; 0 or 1 with nearest)");
  app.add_option("--tmin", o.tmin, "the rays' tmin, unless a ray gives its own")->capture_default_str();
  app.add_option("--tmax", o.tmax, "the rays' tmax, unless a ray gives its own (default: inf)");
  app.add_option("--ray-origin", o.rayOrigin,
                 "where rays from inside the bounding sphere start: on-object (its own surface: spec/geometry.md 7.3) or "
                 "off-object (the ground, another object: 7.4, which keeps contact shadows at short tmax)")
      ->capture_default_str()
      ->check(CLI::IsMember({"on-object", "off-object"}));
  app.add_option("--intra-bias", o.intraBias, "bias of on-object rays from inside the sphere, a fraction of R (default: the field's)");
  app.add_option("--rotate", o.rotate, "place the field: rotation about axis x y z by an angle in radians")
      ->expected(4)
      ->option_text("AX AY AZ RADIANS");
  app.add_option("--translate", o.translate, "place the field: translation x y z (after rotation and scale)")
      ->expected(3)
      ->option_text("X Y Z");
  app.add_option("--scale", o.scale, "place the field: uniform scale (> 0)")->check(CLI::PositiveNumber);
  app.add_option("-j,--threads", o.threads, "threads (0: all cores); the answers do not depend on it")
      ->capture_default_str();
  app.add_option("--checksums", o.checksums,
                 "which checksums of the field to verify: all (at open), lazy (each block when first decoded: the "
                 "query decodes every block, so all of them) or none (a field already validated)")
      ->check(CLI::IsMember({"all", "lazy", "none"}))
      ->capture_default_str();
  app.add_flag("--no-sites", o.noSites,
               "leave out the columns sample, i, j (which map and texel answered): finding them is a second "
               "pass of each lookup's first steps");
  app.add_option("--columns", o.columns,
                 "the output's columns, comma-separated, in this order (csv and npy): any of hit,t,x,y,z,nx,ny,nz,"
                 "inside,sample,i,j,visibility (default: all but visibility; fewer columns, less to write)")
      ->excludes("--no-sites")
      ->excludes("--visibility")
      ->option_text("LIST");
  app.add_flag("--timing", o.timing,
               "print to stderr the seconds spent reading, querying and writing, and the rays per second of the "
               "whole and of the batch calls alone on warm memory (run 3 more times; for benchmarks)");
}

// The bytes of an input, read whole: a regular file as FileBytes reads it, standard input ("-")
// and other files (pipes) as they come.
class Input {
 public:
  static Result<Input> open(const std::string& path) {
    Input in;
    if (path == "-") {
      auto bytes = cli::readStdin();
      if (!bytes) return std::move(bytes).error();
      in.owned_ = std::move(*bytes);
      return in;
    }
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
      auto file = FileBytes::read(fd, path);
      ::close(fd);
      if (!file) return std::move(file).error();
      in.file_ = std::move(*file);
      return in;
    }
    uint8_t buf[1 << 16];
    ssize_t n;
    while ((n = ::read(fd, buf, sizeof buf)) > 0) in.owned_.insert(in.owned_.end(), buf, buf + n);
    const int err = errno;
    ::close(fd);
    if (n < 0) return makeError(Code::kIoRead, path + ": " + std::strerror(err));
    return in;
  }
  std::span<const uint8_t> bytes() const {
    return file_.bytes().empty() ? std::span<const uint8_t>(owned_) : file_.bytes();
  }

 private:
  std::vector<uint8_t> owned_;
  FileBytes file_;
};

// Where the rays of a run come from: the rows of a .npy matrix, read in place (each chunk turned
// into rays by the thread that answers it), or rays already read.
struct RaySource {
  const uint8_t* rows = nullptr;  // the .npy rows (ox oy oz dx dy dz [tmin tmax]: '<f4'), when not null
  size_t cols = 0;
  std::span<const Ray> rays;  // else these
  size_t size = 0;
  float tmin = 0, tmax = 0;

  Ray row(size_t i) const {
    float r[8];
    const uint8_t* p = rows + i * cols * sizeof(float);
    // (memcpy: any alignment; of a constant size, so that it compiles to plain loads)
    if (cols == 8) {
      std::memcpy(r, p, 8 * sizeof(float));
      return Ray{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, r[6], r[7]};
    }
    std::memcpy(r, p, 6 * sizeof(float));
    return Ray{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, tmin, tmax};
  }
  // Rays [first, first + count) into `out` (unless read already: then a view of them); the index of
  // the first bad one (checkRay), if any.
  std::span<const Ray> get(size_t first, size_t count, Ray* out, std::optional<size_t>* bad) const {
    if (!rows) return rays.subspan(first, count);
    for (size_t k = 0; k < count; ++k) {
      out[k] = row(first + k);
      if (!*bad && !rayIsGood(out[k])) *bad = first + k;
    }
    return {out, count};
  }
};

// The .npy input's problem for a bad row, as an invalid-input message.
std::string badRowMessage(const RaySource& src, size_t i) {
  auto bad = checkRay(src.row(i));
  return "row " + std::to_string(i) + ", column " + std::to_string(bad->second) + ": " + bad->first;
}

// What answers the rays: a field in its own space, or an instance of it.
struct Target {
  const FieldQuery* field;
  std::optional<Instance> instance;
  void intersect(std::span<const Ray> r, std::span<QueryHit> h, const QueryOptions& qo) const {
    if (instance) instance->intersect(r, h, qo); else field->intersect(r, h, qo);
  }
  void sites(std::span<const Ray> r, std::span<LookupSite> s, const QueryOptions& qo) const {
    if (instance) instance->sites(r, s, qo); else field->sites(r, s, qo);
  }
  void visibility(std::span<const Ray> r, std::span<float> v, const QueryOptions& qo) const {
    if (instance) instance->visibility(r, v, qo); else field->visibility(r, v, qo);
  }
};

// Answers the rays in chunks of kChunk over `threads` threads (platform/parallel.h); each chunk's
// answers go to store(first, answers) from the thread that made them (the sites and visibilities
// only where `columns` have them). A chunk holding a bad .npy row is not answered; the index of the
// first bad row is returned.
template <class Store>
std::optional<size_t> answer(const Target& target, const RaySource& src, const QueryOptions& qo,
                             std::span<const Column> columns, unsigned threads, Store store) {
  const bool sites = needsSites(columns), visibility = hasColumn(columns, Column::kVisibility);
  std::atomic<size_t> firstBad{SIZE_MAX};
  parallel::parallelFor(src.size, kChunk, threads, [&](size_t b, size_t e) {
    const size_t n = e - b;
    thread_local std::vector<Ray> rays;
    thread_local std::vector<QueryHit> hits;
    thread_local std::vector<LookupSite> where;
    thread_local std::vector<float> vis;
    rays.resize(src.rows ? n : 0), hits.resize(n), where.resize(sites ? n : 0), vis.resize(visibility ? n : 0);
    std::optional<size_t> bad;
    const std::span<const Ray> in = src.get(b, n, rays.data(), &bad);
    if (bad) {
      for (size_t was = firstBad.load(); *bad < was && !firstBad.compare_exchange_weak(was, *bad);) {
      }
      return;
    }
    target.intersect(in, hits, qo);
    if (sites) target.sites(in, where, qo);
    if (visibility) target.visibility(in, vis, qo);
    store(b, Answers{hits, where, vis, columns});
  });
  if (firstBad.load() != SIZE_MAX) return firstBad.load();
  return std::nullopt;
}

// The command line into `o`, and the checks between its options; an exit code where the run stops.
std::optional<int> parseCommandLine(int argc, char** argv, Options& o) {
  CLI::App app{
      "Answers rays with a visibility field: hit, t, point, normal, whether the hit was found from inside\n"
      "the bounding sphere and which map and texel answered, one line (or .npy row) per ray, in the order given. Rays come from --ray, from\n"
      "a .npy file, or as text lines (CSV: ox,oy,oz,dx,dy,dz[,tmin,tmax]; JSON: {\"origin\":[..],\n"
      "\"direction\":[..],\"tmin\":..,\"tmax\":..} or [6 or 8 numbers]) from a file or standard input.\n"
      "A bad line is reported as FILE:LINE:COLUMN (exit 3) after the rays before it are answered.\n"
      "Output columns: hit,t,x,y,z,nx,ny,nz,inside,sample,i,j[,visibility] (a miss: t inf, point nan; no\n"
      "normal: nan; inside: 1 for a hit found from inside the bounding sphere by the reversed ray of\n"
      "spec/geometry.md 7.3, 0 for every miss and every other hit; sample, i, j: the map and texel that\n"
      "answered, -1 without a lookup; --no-sites: left out;\n"
      "--columns: those named, in that order).\n\n"
      "A glTF asset answers with one mesh's field (--mesh): a field with an error or whose geometry does not\n"
      "match its mesh is refused (exit 3), a mesh without a field is a usage error naming those with one.\n\n"
      "  vff-query field.vff --ray 0 0 5 0 0 -1\n"
      "  vff-query field.vff -i rays.npy -o hits.npy --interpolated\n"
      "  vff-query scene.glb --mesh 1 --ray 0 0 5 0 0 -1\n",
      kProg};
  app.footer(cli::exitCodeHelp());
  addOptions(app, o);
  if (auto rc = cli::parse(app, kProg, argc, argv)) return *rc;
  if (!o.rays.empty() && !o.input.empty()) {
    cli::usageError(kProg, "--ray and --input exclude each other");
    return cli::kExitUsage;
  }
  if (std::isnan(o.tmin) || std::isnan(o.tmax)) {
    cli::usageError(kProg, std::isnan(o.tmin) ? "--tmin is not a number (nan)" : "--tmax is not a number (nan)");
    return cli::kExitUsage;
  }
  if (o.tmin > o.tmax) {
    cli::usageError(kProg, "--tmin is greater than --tmax");
    return cli::kExitUsage;
  }
  return std::nullopt;
}

// --format, or else what the output's name says.
OutputFormat outputFormat(const Options& o) {
  const bool toNpyName = o.output.size() > 4 && o.output.compare(o.output.size() - 4, 4, ".npy") == 0;
  return o.format == "npy"     ? OutputFormat::kNpy
         : o.format == "jsonl" ? OutputFormat::kJsonLines
         : o.format == "csv"   ? OutputFormat::kCsv
         : toNpyName           ? OutputFormat::kNpy
                               : OutputFormat::kCsv;
}

ReadOptions readOptions(const Options& o) {
  ReadOptions ro;
  ro.checksums = o.checksums == "none" ? ChecksumPolicy::kNone
                 : o.checksums == "lazy" ? ChecksumPolicy::kLazy
                                         : ChecksumPolicy::kVerifyAll;
  return ro;
}

// The field placed by --rotate, --translate and --scale, into *inst (left empty without them); an
// exit code for a rotation about no axis.
std::optional<int> placeField(const Options& o, const FieldQuery* q, std::optional<Instance>* inst) {
  if (o.rotate.empty() && o.translate.empty() && o.scale == 1.0f) return std::nullopt;
  const Vec3 axis = o.rotate.empty() ? Vec3{0, 0, 1} : Vec3{o.rotate[0], o.rotate[1], o.rotate[2]};
  if (axis.x == 0 && axis.y == 0 && axis.z == 0) {
    cli::usageError(kProg, "--rotate needs a non-zero axis");
    return cli::kExitUsage;
  }
  const Vec3 t = o.translate.empty() ? Vec3{} : Vec3{o.translate[0], o.translate[1], o.translate[2]};
  *inst = Instance{q, RigidTransform::fromAxisAngle(axis, o.rotate.empty() ? 0.0f : o.rotate[3], t, o.scale)};
  return std::nullopt;
}

// The rays of a run and what holds them: src reads them in place, from `rays` or from the .npy
// rows of `input`, so a RayInput stays where it was filled.
struct RayInput {
  std::vector<Ray> rays;
  std::optional<Input> input;
  RaySource src;
  std::optional<std::string> badInput;  // the diagnostic of a bad line, printed after the answers
  std::string label;                    // the input's name in messages
};

// The --ray options into *rays; an exit code for a bad one.
std::optional<int> rayArguments(const Options& o, std::vector<Ray>* rays) {
  for (size_t i = 0; i < o.rays.size(); ++i) {
    const auto& r = o.rays[i];
    if (r.size() != 6) {
      cli::usageError(kProg, "--ray number " + std::to_string(i + 1) + " has " + std::to_string(r.size()) +
                                 " numbers: it takes 6 (ox oy oz dx dy dz)");
      return cli::kExitUsage;
    }
    Ray ray{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, o.tmin, o.tmax};
    if (auto bad = checkRay(ray)) {
      cli::usageError(kProg, "--ray number " + std::to_string(i + 1) + ": " + bad->first);
      return cli::kExitUsage;
    }
    rays->push_back(ray);
  }
  return std::nullopt;
}

// The rays of --input (or standard input): a .npy matrix, read in place, or text lines, parsed up
// to the first bad one (whose diagnostic waits in in->badInput). An exit code where none can be read.
std::optional<int> inputRays(const Options& o, RayInput* in) {
  const std::string path = o.input.empty() ? "-" : o.input;
  in->label = path == "-" ? "<stdin>" : path;
  auto opened = Input::open(path);
  if (!opened) return cli::reportError(kProg, in->label, opened.error());
  in->input.emplace(std::move(*opened));
  const std::span<const uint8_t> bytes = in->input->bytes();
  if (bytes.size() >= 6 && std::memcmp(bytes.data(), "\x93NUMPY", 6) == 0) {
    NpyMatrix m;
    std::optional<std::string> e = readNpyMatrix(bytes, &m);
    if (!e && m.cols != 6 && m.cols != 8)
      e = "expected shape (N, 6) or (N, 8), found (" + std::to_string(m.rows) + ", " + std::to_string(m.cols) + ")";
    if (e) {
      cli::printError(kProg, in->label + ": " + *e);
      return cli::kExitInvalidFile;
    }
    in->src.rows = m.data.data();
    in->src.cols = size_t(m.cols);
    in->src.size = size_t(m.rows);
    return std::nullopt;
  }
  ParsedRays parsed = parseRayLines({reinterpret_cast<const char*>(bytes.data()), bytes.size()}, o.tmin, o.tmax);
  in->rays = std::move(parsed.rays);
  if (parsed.error)
    in->badInput = in->label + ":" + std::to_string(parsed.error->line) + ":" + std::to_string(parsed.error->column) +
                   ": " + parsed.error->message;
  return std::nullopt;
}

// The rays of the run, from --ray or an input, into *in; an exit code where there are none to answer.
std::optional<int> readRays(const Options& o, RayInput* in) {
  in->src.tmin = o.tmin, in->src.tmax = o.tmax;
  if (auto rc = o.rays.empty() ? inputRays(o, in) : rayArguments(o, &in->rays)) return rc;
  if (!in->src.rows) in->src.rays = in->rays, in->src.size = in->rays.size();
  return std::nullopt;
}

// The output's columns: --columns, or the default set; an exit code for a bad list.
std::optional<int> chooseColumns(const Options& o, OutputFormat format, std::vector<Column>* columns) {
  *columns = defaultColumns(!o.noSites, o.visibility);
  if (o.columns.empty()) return std::nullopt;
  if (auto bad = parseColumns(o.columns, columns)) {
    cli::usageError(kProg, "--columns: " + *bad);
    return cli::kExitUsage;
  }
  if (format == OutputFormat::kJsonLines) {
    cli::usageError(kProg, "--columns applies to csv and npy answers (JSON lines name their keys)");
    return cli::kExitUsage;
  }
  return std::nullopt;
}

// How a run answers: its target, rays, query options, columns and threads.
struct Run {
  const Target& target;
  const RayInput& in;
  const QueryOptions& qo;
  std::span<const Column> columns;
  unsigned threads;
};

// Answers straight into the .npy output file: each thread formats its chunks' rows and writes them
// at their offset (no whole copy of the answers is made). An exit code on failure.
std::optional<int> answerIntoNpyFile(const Run& r, const std::string& output) {
  auto out = cli::AtomicFile::create(output);
  if (!out) return cli::reportError(kProg, "", out.error());
  const size_t cols = r.columns.size();
  const std::vector<uint8_t> header = npyMatrixHeader(r.in.src.size, cols);
  std::atomic<bool> failed{false};
  std::optional<Error> writeError;
  auto failWith = [&](Status st) {
    if (!failed.exchange(true)) writeError = st.error();  // (the first failure only)
  };
  if (Status st = out->writeAt(0, header); !st) failWith(st);
  const std::optional<size_t> badRow =
      answer(r.target, r.in.src, r.qo, r.columns, r.threads, [&](size_t first, const Answers& a) {
        if (failed) return;
        thread_local std::vector<float> rowBuffer;
        rowBuffer.resize(a.hits.size() * cols);
        answerRows(a, rowBuffer.data());
        const auto* bytes = reinterpret_cast<const uint8_t*>(rowBuffer.data());
        if (Status st = out->writeAt(header.size() + first * cols * sizeof(float), {bytes, rowBuffer.size() * sizeof(float)});
            !st)
          failWith(st);
      });
  if (writeError) return cli::reportError(kProg, "", *writeError);
  if (badRow) {
    cli::printError(kProg, r.in.label + ": " + badRowMessage(r.in.src, *badRow));
    return cli::kExitInvalidFile;
  }
  if (Status st = out->commit(); !st) return cli::reportError(kProg, "", st.error());
  return std::nullopt;
}

// Answers into memory, then writes them formatted (CSV, JSON lines, or .npy to standard output).
std::optional<int> answerFormatted(const Run& r, OutputFormat format, const std::string& output) {
  const RaySource& src = r.in.src;
  const bool sites = needsSites(r.columns), visibility = hasColumn(r.columns, Column::kVisibility);
  std::vector<QueryHit> hits(src.size);
  std::vector<LookupSite> where(sites ? src.size : 0);
  std::vector<float> vis(visibility ? src.size : 0);
  const std::optional<size_t> badRow =
      answer(r.target, src, r.qo, r.columns, r.threads, [&](size_t first, const Answers& a) {
        std::copy(a.hits.begin(), a.hits.end(), hits.begin() + ptrdiff_t(first));
        std::copy(a.sites.begin(), a.sites.end(), where.begin() + ptrdiff_t(first));
        std::copy(a.visibility.begin(), a.visibility.end(), vis.begin() + ptrdiff_t(first));
      });
  if (badRow) {
    cli::printError(kProg, r.in.label + ": " + badRowMessage(src, *badRow));
    return cli::kExitInvalidFile;
  }
  const std::vector<uint8_t> out = formatAnswers({hits, where, vis, r.columns}, format);
  if (auto st = cli::writeFileAtomic(output, out); !st) return cli::reportError(kProg, "", st.error());
  return std::nullopt;
}

using Clock = std::chrono::steady_clock;

// When each stage of a run began, and when it ended.
struct Stages {
  Clock::time_point open, read, query, end;
};

// --timing: the stages' seconds and the end-to-end rate, beside the baselines it compares with, on
// the same rays already in memory as vff::Ray, warm (best of 3 each), over the same threads in the
// same chunks: the batch calls as a library caller makes them, every answer kept in an array of all
// of them; and the batch calls alone, each chunk's answers dropped (a bound no caller reaches: its
// answers never leave the cache). Intersect only: no lookup sites, no visibility. The field as a
// library caller (and the Python module) opens it: File::open's mapping, not this tool's copy.
// (A glTF asset's field, `payload`, has no file of its own to map: it is opened from its bytes.)
std::optional<int> printTiming(const Options& o, const Run& r, const std::optional<Instance>& inst, const Stages& at,
                               std::span<const uint8_t> payload) {
  auto sec = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  const RaySource& src = r.in.src;
  const double n = double(src.size) / 1e6;
  auto mappedFile = payload.empty() ? File::open(o.field, readOptions(o)) : File::openMemory(payload, readOptions(o));
  if (!mappedFile) return cli::reportError(kProg, o.field, mappedFile.error());
  auto mapped = FieldQuery::fromFile(*mappedFile);
  if (!mapped) return cli::reportError(kProg, o.field, mapped.error());
  std::optional<Instance> mappedInstance;
  if (inst) mappedInstance = Instance{&*mapped, inst->transform};
  const Target baseline{&*mapped, mappedInstance};
  std::vector<Ray> held(src.rows ? src.size : 0);
  for (size_t i = 0; i < held.size(); ++i) held[i] = src.row(i);
  const std::span<const Ray> warmRays = src.rows ? std::span<const Ray>(held) : src.rays;
  const RaySource warm{nullptr, 0, warmRays, src.size, o.tmin, o.tmax};
  std::vector<QueryHit> kept(src.size);
  const Column hitColumns[] = {Column::kHit, Column::kT};
  double batch = 1e30, keptBatch = 1e30;
  for (int k = 0; k < 3; ++k) {
    auto b0 = Clock::now();
    parallel::parallelFor(src.size, kChunk, r.threads, [&](size_t first, size_t end) {
      baseline.intersect(warmRays.subspan(first, end - first), std::span(kept).subspan(first, end - first), r.qo);
    });
    keptBatch = std::min(keptBatch, sec(b0, Clock::now()));
    b0 = Clock::now();
    answer(baseline, warm, r.qo, hitColumns, r.threads, [](size_t, const Answers&) {});
    batch = std::min(batch, sec(b0, Clock::now()));
  }
  std::fprintf(stderr,
               "vff-query: timing: %s, %s, %s: field %.4f s, read %.4f s, query and write %.4f s, total %.4f s "
               "(%.1f Mrays/s); batch, answers kept, warm: %.4f s (%.1f Mrays/s); batch alone, warm: %.4f s (%.1f Mrays/s)\n",
               cli::count(src.size, "ray").c_str(), cli::count(r.threads, "thread").c_str(), o.refined ? "refined" : o.interpolated ? "interpolated" : "nearest", sec(at.open, at.read), sec(at.read, at.query),
               sec(at.query, at.end), sec(at.open, at.end), n / std::max(1e-9, sec(at.open, at.end)), keptBatch,
               n / std::max(1e-9, keptBatch), batch, n / std::max(1e-9, batch));
  return std::nullopt;
}

int run(int argc, char** argv) {
  Options o;
  if (auto rc = parseCommandLine(argc, argv, o)) return *rc;
  const OutputFormat format = outputFormat(o);

  // The field first: a field that cannot be read answers nothing. Read whole into memory of its
  // own (file_bytes.h), which the File and the query borrow.
  Stages at;
  at.open = Clock::now();
  const bool gltf = cli::isGltfInput(o.field);
  if (!gltf && o.mesh >= 0) {
    cli::usageError(kProg, "--mesh chooses a field of a glTF asset (.gltf, .glb), not of " + o.field);
    return cli::kExitUsage;
  }
  std::optional<FileBytes> fieldBytes;
  std::vector<uint8_t> payload;  // a glTF asset's field: the .vff bytes of the chosen mesh's
  if (gltf) {
    if (auto rc = gltfFieldBytes(o.field, o.mesh, &payload)) return *rc;
  } else {
    auto read = FileBytes::read(o.field);
    if (!read) return cli::reportError(kProg, o.field, read.error());
    fieldBytes.emplace(std::move(*read));
  }
  auto file = File::openMemory(gltf ? std::span<const uint8_t>(payload) : fieldBytes->bytes(), readOptions(o));
  if (!file) return cli::reportError(kProg, o.field, file.error());
  auto q = FieldQuery::fromFile(*file);
  if (!q) return cli::reportError(kProg, o.field, q.error());
  if (o.refined && !q->refined()) {
    cli::usageError(kProg, "--refined needs a refined field (vff-bake --refine); " + o.field + " has no REFN section");
    return cli::kExitUsage;
  }
  std::optional<Instance> inst;
  if (auto rc = placeField(o, &*q, &inst)) return *rc;

  at.read = Clock::now();
  RayInput in;
  if (auto rc = readRays(o, &in)) return *rc;

  QueryOptions qo;
  qo.reconstruction = o.refined        ? Reconstruction::kRefined
                      : o.interpolated ? Reconstruction::kInterpolated
                                       : Reconstruction::kNearest;
  qo.intraBias = o.intraBias;
  qo.origin = o.rayOrigin == "off-object" ? RayOrigin::kOffObject : RayOrigin::kOnObject;
  std::vector<Column> columns;
  if (auto rc = chooseColumns(o, format, &columns)) return *rc;
  const Target target{&*q, inst};
  const Run r{target, in, qo, columns, parallel::resolveThreads(o.threads)};
  at.query = Clock::now();
  if (auto rc = format == OutputFormat::kNpy && o.output != "-" ? answerIntoNpyFile(r, o.output)
                                                                  : answerFormatted(r, format, o.output))
    return *rc;
  at.end = Clock::now();
  if (o.timing)
    if (auto rc = printTiming(o, r, inst, at, payload)) return *rc;
  if (in.badInput) {
    cli::printError(kProg, *in.badInput);
    return cli::kExitInvalidFile;
  }
  return cli::kExitSuccess;
}

}  // namespace
