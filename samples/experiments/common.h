// common.h - what the experiments share: small vector maths, the per-pixel random numbers, the
// world (object on a ground plane, camera), the G-buffer of primary hits, the two tracers (exact
// Embree and visibility field), the tiled renderer, images and the result table.
//
// Conventions. World space is y-up; the ground plane is y = 0 and is intersected analytically (it
// is never in a field). The object stands on the plane: world = object + translation (scale 1, no
// rotation), so object and world normals coincide. Every distance the experiments choose (AO range,
// offsets, lights) is a multiple of the object's bounding-sphere radius R.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include "vff/bake/baker.h"
#include "vff/bake/mesh.h"
#include "vff/query.h"
#include "vff/sdf/sdf_field.h"

namespace vffx {

using vff::Vec3;

// ---- Vector maths -------------------------------------------------------------------------------
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator*(float s, Vec3 a) { return a * s; }
inline Vec3 mul(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) {
  const float l = length(a);
  return l > 0 ? a * (1.0f / l) : Vec3{0, 1, 0};
}
inline Vec3 toVec(const float* p) { return {p[0], p[1], p[2]}; }
inline constexpr float kPi = 3.14159265358979f;

// ---- Random numbers -----------------------------------------------------------------------------
// PCG32. Every pixel seeds its own generator from (x, y, stream), so an image does not depend on
// the thread count or tile order, and the exact and field renders of one experiment draw exactly
// the same rays (their difference is the field's error, not Monte Carlo noise).
class Rng {
 public:
  Rng(uint32_t x, uint32_t y, uint32_t stream);
  uint32_t nextU32();
  float next01();  // [0, 1)

 private:
  uint64_t state_ = 0, inc_ = 1;
};

// Cosine-weighted direction around unit normal n (u1, u2 in [0,1)).
Vec3 cosineDirection(Vec3 n, float u1, float u2);
// Uniform point on the unit sphere.
Vec3 uniformSphere(float u1, float u2);
// A unit vector b, c completing n to an orthonormal frame.
void orthonormalBasis(Vec3 n, Vec3* b, Vec3* c);

// ---- Threads ------------------------------------------------------------------------------------
// Runs fn(begin, end) over [0, count) in chunks handed out to `threads` workers (0: hardware):
// timedParallelFor without the time.
void parallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                 const std::function<void(uint64_t, uint64_t)>& fn);
// parallelFor, timed for a benchmark: the seconds from the moment every worker has started (they
// wait for each other) to the moment the last one finishes. Starting and joining the threads is
// left out: a fixed cost per pass, it would weigh ten times more on the field's batch passes (a
// few ms in vff-experiments bench) than on Embree's, and so favour the slower query.
double timedParallelFor(uint64_t count, uint64_t chunk, unsigned threads,
                        const std::function<void(uint64_t, uint64_t)>& fn);
unsigned resolveThreads(unsigned threads);

// ---- World --------------------------------------------------------------------------------------
struct Camera {
  Vec3 eye, forward, right, up;  // right/up scaled to the half extent of the image plane at distance 1
  Vec3 rayDirection(float px, float py, int width, int height) const;  // pixel coords, y down
};

struct World {
  vff::bake::Mesh objectMesh;  // as loaded (object space)
  vff::bake::Mesh worldMesh;   // standing on the plane (world space)
  vff::RigidTransform transform;
  vff::Sphere objectSphere;    // minimal enclosing sphere, object space (what the bake uses)
  Vec3 center;                 // its centre in world space
  float radius = 0;            // R
  Camera camera;
};

// Loads the mesh (errors name the file), stands it on the plane, aims the camera.
vff::Result<World> makeWorld(const std::string& meshPath);
// The same for a mesh in memory (checked: vff::bake::checkMesh).
World makeWorld(vff::bake::Mesh mesh);

// ---- Exact tracer (Embree 3, the object's triangles in world space) ------------------------------
struct ExactHit {
  bool hit = false;
  float t = 0;
  Vec3 normal;     // interpolated vertex normal when the mesh has normals, else geometric; unit
  Vec3 geometric;  // unit geometric normal
};

class ExactTracer {
 public:
  static vff::Result<ExactTracer> create(const vff::bake::Mesh& mesh);
  ExactTracer(ExactTracer&&) noexcept;
  ExactTracer& operator=(ExactTracer&&) noexcept;
  ~ExactTracer();

  bool occluded(const vff::Ray& ray) const;  // rtcOccluded1
  ExactHit intersect(const vff::Ray& ray) const;  // rtcIntersect1
  uint64_t memoryBytes() const;  // Embree's peak allocation (BVH and buffers)
  RTCDevice device() const;      // its Embree device and scene, for other forms of ray casts
  RTCScene scene() const;

  struct Impl;

 private:
  ExactTracer() = default;
  std::unique_ptr<Impl> impl_;
};

// ---- Field tracer (baked in memory with vff::bake, queried through vff::Instance) ---------------
struct FieldConfig {
  uint32_t n = 32;   // octa-hemi2 parameter: 2(2n^2+2n+1) maps
  uint32_t mapSize = 64;
  std::string name() const;  // "4226x64x64"
};

struct BakedQuery {
  FieldConfig config;           // of a bake (the map count and size of a loaded file)
  std::string name;             // in file names: "4226x64x64", or a loaded file's name without .vff
  std::string description;      // in the table: the name, or "file.vff (4226x32x32 unorm8-diameter)"
  vff::bake::BakedField baked;  // owns the maps the query borrows
  vff::Refinement refinement;   // refineQuery: owns the refinement the query borrows
  vff::FieldQuery query;
  vff::Instance instance;       // the field placed in the world
  double bakeSeconds = 0;
  double payloadMiB() const { return double(query.payloadBytes()) / 1048576.0; }
};

// A buffer of n rays for one pixel's batch (one per thread, reused).
inline std::span<vff::Ray> rayBuffer(size_t n) {
  thread_local std::vector<vff::Ray> rays;
  rays.resize(n);
  return rays;
}

// The unoccluded share of every ray: the exact answer (0 or 1) when field is null, else the
// field's visibility(): 0 or 1 (not occluded()) for kNearest, a fraction for kInterpolated. A
// field answers them with one batch call, as a renderer would. The result lives until the
// thread's next call.
inline std::span<const float> openShares(const ExactTracer& exact, const BakedQuery* field, const vff::QueryOptions& qo,
                                         std::span<const vff::Ray> rays) {
  thread_local std::vector<float> out;
  out.resize(rays.size());
  if (field) {
    field->instance.visibility(rays, out, qo);
  } else {
    for (size_t i = 0; i < rays.size(); ++i) out[i] = exact.occluded(rays[i]) ? 0.0f : 1.0f;
  }
  return out;
}

// openShares through the signed distance field instead (sdf_field.h): one batch call per pixel, as
// the field's; 0 or 1 per ray, or the cone estimate when `so` asks for it.
inline std::span<const float> openShares(const SdfField& sdf, const SdfTraceOptions& so, std::span<const vff::Ray> rays) {
  thread_local std::vector<float> out;
  out.resize(rays.size());
  sdf.visibility(rays, out, so);
  return out;
}

// Bakes one configuration (unorm8-diameter) of the object and places it like the world's object.
vff::Result<std::unique_ptr<BakedQuery>> bakeQuery(const World& world, const vff::bake::Scene& scene,
                                                   const FieldConfig& config, bool normals, unsigned threads);
// Loads a field file (--field) of the world's object: every block decoded into memory, queried like a
// bake. The file must describe the same object: its sphere must be the mesh's minimal enclosing
// sphere (what bakeQuery uses), within 1e-5 R, and when META names the source geometry's hash
// (vff.source.geometryHash, kept by vff-convert; older files: the mesh hash vff.source.xxh3) it must
// be the loaded mesh's. Errors: those of File::open;
// kInvalidArgument naming the mismatch (the caller exits 3); kUnsupported when `normals` are
// needed and the file has none.
// Adds a refinement of the world's object (vff/refine.h) to a baked field: its query then answers
// Reconstruction::kRefined.
vff::Status refineQuery(const World& world, BakedQuery* q, const vff::RefineOptions& options);
vff::Result<std::unique_ptr<BakedQuery>> loadQuery(const World& world, const std::string& path, bool normals);
// Parses "4226x64x64" (or "n32m64"): maps must be an octa-hemi2 count.
bool parseFieldConfig(const std::string& text, FieldConfig* out);
struct Options;
// The one field configuration of a benchmark or the scene experiment: the first --config, else
// `fallback`; a usage error (printed, its exit code returned) when it does not parse.
std::optional<int> singleConfig(const Options& o, const std::string& fallback, FieldConfig* out);

// ---- Primary visibility (G-buffer) --------------------------------------------------------------
enum class PixelKind : uint8_t { kBackground, kPlane, kObject };

struct GSample {
  PixelKind kind = PixelKind::kBackground;
  Vec3 point;    // world
  Vec3 normal;   // geometric, facing the camera
  Vec3 shadingNormal;  // interpolated when the mesh has normals, facing the camera
  Vec3 viewDir;  // unit, camera -> point
  uint32_t instance = ~0u;  // the scene experiment's: the object hit (its instance id), ~0u for none
};

struct GBuffer {
  int width = 0, height = 0;
  std::vector<GSample> pixels;
  const GSample& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

// One primary ray through each pixel centre: the nearer of the plane and the object (exact).
GBuffer traceGBuffer(const World& world, const ExactTracer& exact, int size, unsigned threads);

// ---- Images -------------------------------------------------------------------------------------
struct Image {
  int width = 0, height = 0;
  std::vector<Vec3> rgb;  // linear, nominally [0, 1]
  Vec3& at(int x, int y) { return rgb[size_t(y) * size_t(width) + size_t(x)]; }
  const Vec3& at(int x, int y) const { return rgb[size_t(y) * size_t(width) + size_t(x)]; }
};

// Renders every pixel with shade(x, y, sample, rng) in 16x16 tiles on `threads` workers; the
// result does not depend on the thread count. Returns the wall time in seconds through *seconds.
Image renderImage(const GBuffer& g, unsigned threads, uint32_t stream,
                  const std::function<Vec3(const GSample&, Rng&)>& shade, double* seconds);

// PNG (8 bits per channel: round(255 * clamp(v)), no transfer curve, so that the 8-bit error of
// the table is the difference of the PNG values) and EXR (linear half RGB). Errors: kIoWrite.
vff::Status writePng(const Image& image, const std::string& path);
vff::Status writeExr(const Image& image, const std::string& path);
// |a - b| on the 8-bit scale, times `gain`, through a black-red-yellow-white ramp; pixels outside
// the mask are dark grey.
// The images side by side, left to right (all of the first one's height).
Image sideBySide(const std::vector<Image>& images);
vff::Status writeErrorMap(const Image& reference, const Image& image, const std::vector<uint8_t>& mask,
                          float gain, const std::string& path);

struct ErrorStats {
  double rms = 0;  // on the 8-bit scale, over every channel of the masked pixels
  double max = 0;
  uint64_t pixels = 0;
};
ErrorStats compareImages(const Image& reference, const Image& image, const std::vector<uint8_t>& mask);

// ---- Experiments --------------------------------------------------------------------------------
struct Options {
  std::string experiment;
  std::string mesh = "/usr/share/glmark2/models/bunny.obj";
  std::string out = "out/experiments";
  int size = 512;
  int rays = 0;       // 0: the experiment's default (ao 256, intra-ao 121, shadows 20, reflections 4)
  unsigned threads = 0;
  std::vector<std::string> configs;  // empty: the experiment's default field configurations (none with fields)
  std::vector<std::string> fields;   // .vff files of the same mesh to evaluate besides (or instead of) bakes
  // AO range as a multiple of R (2 R: the whole bounding sphere). Rays from the plane start off the
  // object (spec/geometry.md 7.4), so shorter ranges keep the contact shadow.
  float aoDistance = 2.0f;
  // ao: the ranges to render (multiples of R); empty: aoDistance alone.
  std::vector<float> aoRanges;
  // bench
  uint32_t benchRays = 1u << 21;
  uint32_t benchBatch = 4096;  // rays per batch call in (b), (d) and (e)
  int repeat = 3;
  // scene-bench
  std::vector<uint32_t> instanceCounts{1, 10, 100, 1000, 10000};
  uint32_t sceneRays = 1u << 18;  // AO rays per frame
  // triangle-bench
  uint32_t minTriangles = 10000;    // the coarsest level has at least this many
  uint32_t maxTriangles = 1000000;  // subdivide until at least this many
  int frames = 3;
  // sdf-bench: memory per object, MiB (each the nearest field configuration's payload)
  std::vector<double> sdfMemory{1, 4, 16, 64};
  // the distance-field peer's rows (sdf_field.h): on by default
  bool sdf = true;
  SdfValues sdfValues = SdfValues::kFp8;
  float sdfBand = SdfBuildOptions{}.bandVoxels;
  bool sdfUnsure = false;  // sdf-bench --unsure
  bool sdfRefined = true;  // the refined field: sdf-bench's table, the image experiments' rows (--no-refined: none)
  bool refineProbe = false;  // sdf-bench --refine-probe (RefineOptions::probe)
  float refineMargin = vff::RefineOptions{}.marginSpreads;  // sdf-bench --refine-margin
  // scene
  std::vector<std::string> objects;  // meshes besides --mesh (none: four procedural shapes)
};

// What every experiment needs first: the world, its exact tracer and the object's Embree scene.
// The tracers refer to the world's meshes, so a Setup stays where it was made (held by pointer).
struct Setup {
  World world;
  std::optional<ExactTracer> exact;
  std::optional<vff::bake::Scene> scene;
};
vff::Result<std::unique_ptr<Setup>> makeSetup(const Options& o, unsigned threads);

// The result table of an image experiment, printed as Markdown and written to OUT/NAME-table.md.
struct TableRow {
  std::string configuration, reconstruction;
  double memoryMiB = -1;  // < 0: not applicable
  double rms = 0, max = 0, seconds = 0;
  bool reference = false;
  double rmsContact = -1, rmsOutside = -1;  // ImageExperiment::contactRegion (< 0: not measured)
};
// The table; with contact, the RMS columns of the contact region and of the rest beside the whole's.
std::string formatTable(const std::vector<TableRow>& rows, bool contact = false);

// Every experiment returns an exit code (vff::cli::kExit*), after printing its diagnostics.
int runAo(const Options& o);
int runIntraAo(const Options& o);
int runShadows(const Options& o);
int runReflections(const Options& o);
int runBench(const Options& o);
int runSceneBench(const Options& o);
int runTriangleBench(const Options& o);
int runScene(const Options& o);
int runSdfBench(const Options& o);

// The benchmarks' incoherent ray sets (bench.cpp, where they are described), in world space; object
// is left for the caller to fill.
struct RaySet {
  std::string name;
  std::vector<vff::Ray> world, object;
};
RaySet makeAoRays(const World& w, uint32_t count, float range);
RaySet makeAimedRays(const World& w, uint32_t count);

// The CPU as Linux names it ("model name", family and model from /proc/cpuinfo), or "unknown CPU".
std::string cpuName();

// The shared driver of the image experiments (experiment.cpp): loads the world, builds the exact
// tracer and the G-buffer, bakes the configurations, renders the reference and every (config,
// reconstruction) image, writes images, heat maps and the table.
struct ImageExperiment {
  std::string name;  // "ao": files OUT/ao-*.png, OUT/ao-table.md
  int defaultRays = 0;
  std::vector<std::string> defaultConfigs;
  bool normals = false;           // bake the normal plane too
  bool comparePlane = true;    // pixels whose error is measured: plane pixels,
  bool compareObject = false;  // object pixels
  // The distance field's rows (sdf_field.h, at the memory of each field): kNearest is sphere
  // tracing's hit or miss, kInterpolated its cone estimate.
  std::vector<vff::Reconstruction> sdfRows{vff::Reconstruction::kNearest, vff::Reconstruction::kInterpolated};
  // Returns the shade function of one method: field and sdf null is the exact reference; else the
  // field, or the distance field, with reconstruction r.
  // range: the AO range in multiples of R, one of `ranges` (experiments without ranges ignore it).
  std::function<std::function<Vec3(const GSample&, Rng&)>(const World&, const ExactTracer&, const BakedQuery* field,
                                                            const SdfField* sdf, vff::Reconstruction r, int rays,
                                                            float range)>
      makeShader;
  // The AO ranges to render, each with its own reference (empty: one pass, range unused). The table
  // then names the range in every row.
  std::vector<float> ranges;
  // Also report the error over the plane pixels inside the object's bounding sphere (the contact
  // region, where rays start inside the sphere) and over the rest, beside the whole image's.
  bool contactRegion = false;
};
int runImageExperiment(const Options& o, const ImageExperiment& e);

inline constexpr const char* kProg = "vff-experiments";

}  // namespace vffx
