// vff-gpu-bench - field queries per second and the ground-AO render (the paper's Fig. 3 setting,
// gpu/harness/ao_scene.h) on the GPU through gpu/glsl/vff_query.glsl, with the CPU FieldQuery on the
// same rays in the same run as the baseline.
//
//   vff-gpu-bench [--field FILE.vff] [--mesh MESH] [--size 512] [--spp 256] [--threads N] [--scene N]
//                 [--sdf [--sdf-size N] [--sdf-spp N]] [--api gl|vulkan|vulkan-hlsl[,...]]
//
// --api vulkan adds the field's queries/s through the Vulkan pipeline (vk_bench.h, gpu/vulkan: the
// same vff_query.glsl as SPIR-V) on the GL table's rays, printed after it with the Vulkan device's
// name (built where Vulkan and glslangValidator are found). --api vulkan-hlsl adds the same table
// with the kernel compiled from the generated HLSL (vff::vk::ShaderLanguage::kHlsl; built where
// spirv-cross is found too). A comma-separated list asks for several (--api vulkan,vulkan-hlsl);
// the GL tables always run.
// --scene N adds the scene benchmark (scene_bench.h): the ground AO under N instances of the field
// through gpu/glsl/vff_scene.glsl against the CPU vff::Scene, and a frame's instance update.
// --sdf adds the distance-field peer (sdf_bench.h): the same AO through gpu/glsl/vff_sdf.glsl at the
// field's memory, both against the exact image (needs the mesh: with --field, --mesh must name the
// mesh the field was baked from; built with the samples only), rendered at --sdf-size with --sdf-spp
// rays per pixel (default: --size and --spp; sphere tracing costs a software renderer many times
// the field's lookups, so a smaller image keeps the run short).
//
// Without --field it bakes MESH (default /usr/share/glmark2/models/bunny.obj, else the procedural
// torus knot) as samples/experiments does: octa-hemi2 n = 32 (4226 maps), 64 x 64, unorm8-diameter.
// Timings are wall clock around glDispatchCompute + glFinish (uploads excluded), the best of 2
// runs; the CPU runs the batch FieldQuery::visibility (kNearest: 0 or 1, as !occluded()) on
// --threads threads (default: all cores).
// Exit codes: 0 ok, 1 usage, 2 I/O, 4 runtime (no GL context, shader or bake failure).
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "egl_context.h"
#include "ao_gl.h"
#include "ao_scene.h"
#include "platform/parallel.h"
#include "scene_bench.h"
#ifdef VFF_GPU_BENCH_SDF
#include "sdf_bench.h"
#endif
#ifdef VFF_GPU_BENCH_VULKAN
#include "vk_bench.h"
#endif
#include "vff/bake/baker.h"
#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vff/gl/loader.h"
#include "vff/vff.h"

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

GLuint buildProgram(const std::string& body, std::string* log) {
  return vff::harness::buildQueryProgram("#define VFF_NO_NORMALS\n", body, log);
}

const char* kRayShader = R"(
layout(local_size_x = 64) in;
struct BenchRay { vec4 origin; vec4 direction; };  // origin.w = tmax
layout(std430, binding = 5) readonly buffer BenchRays { BenchRay rays[]; };
layout(std430, binding = 6) writeonly buffer BenchOut { float results[]; };
layout(location = 0) uniform int interpolated;
layout(location = 1) uniform uint firstRay;
void main() {
  uint id = gl_GlobalInvocationID.x + firstRay;
  if (id >= uint(rays.length())) return;
  BenchRay r = rays[id];
  results[id] = interpolated != 0 ? vffVisibility(r.origin.xyz, r.direction.xyz, 0.0, r.origin.w, -1.0)
                                  : (vffOccluded(r.origin.xyz, r.direction.xyz, 0.0, r.origin.w, -1.0) ? 0.0 : 1.0);
}
)";

int usage() {
#ifdef VFF_GPU_BENCH_SDF
  std::fprintf(stderr, "usage: vff-gpu-bench [--field FILE.vff] [--mesh MESH] [--size N] [--spp N] [--ao-distance R] [--threads N] [--scene N] [--sdf [--sdf-size N] [--sdf-spp N]] [--api gl|vulkan|vulkan-hlsl[,...]]\n");
#else
  std::fprintf(stderr, "usage: vff-gpu-bench [--field FILE.vff] [--mesh MESH] [--size N] [--spp N] [--ao-distance R] [--threads N] [--scene N] [--api gl|vulkan|vulkan-hlsl[,...]]\n");
#endif
  return 1;
}

// ---- Options -------------------------------------------------------------------------------------

struct BenchOptions {
  std::string fieldPath, meshPath = "/usr/share/glmark2/models/bunny.obj";
  int size = 512, spp = 256;
  float aoDistance = 2.0f;  // --ao-distance: the AO range of the ground renders, multiples of R
  int sceneInstances = 0;  // --scene N: also the scene benchmark with N instances
  bool sdf = false;        // --sdf: also the distance-field peer at equal memory
  int sdfSize = 0, sdfSpp = 0;  // its image and rays per pixel (0: --size and --spp)
  bool meshGiven = false;  // --mesh was given
  bool vulkan = false;     // --api vulkan: also the queries through the Vulkan pipeline
  bool hlsl = false;       // --api vulkan-hlsl: also that pipeline with the kernel built from HLSL
  unsigned threads = vff::parallel::resolveThreads(0);
};

// Parses the command line into *o; returns an exit code to stop with (0 after --help), or -1 to run.
int parseOptions(int argc, char** argv, BenchOptions* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") {
      usage();
      return 0;
    } else if (a == "--field" && (v = next())) {
      o->fieldPath = v;
    } else if (a == "--mesh" && (v = next())) {
      o->meshPath = v;
      o->meshGiven = true;
    } else if (a == "--size" && (v = next())) {
      o->size = std::atoi(v);
    } else if (a == "--spp" && (v = next())) {
      o->spp = std::atoi(v);
    } else if (a == "--ao-distance" && (v = next())) {
      o->aoDistance = float(std::atof(v));
      if (!(o->aoDistance > 0)) {
        std::fprintf(stderr, "vff-gpu-bench: --ao-distance takes a positive number (multiples of R)\n");
        return 1;
      }
    } else if (a == "--scene" && (v = next())) {
      o->sceneInstances = std::atoi(v);
    } else if (a == "--sdf") {
      o->sdf = true;
    } else if (a == "--sdf-size" && (v = next())) {
      o->sdfSize = std::atoi(v);
    } else if (a == "--sdf-spp" && (v = next())) {
      o->sdfSpp = std::atoi(v);
    } else if (a == "--api" && (v = next())) {
      std::string list = v;
      for (size_t at = 0; at <= list.size();) {
        const size_t end = std::min(list.find(',', at), list.size());
        const std::string api = list.substr(at, end - at);
        if (api == "vulkan") {
          o->vulkan = true;
        } else if (api == "vulkan-hlsl") {
          o->hlsl = true;
        } else if (api != "gl") {
          std::fprintf(stderr, "vff-gpu-bench: --api: '%s' is not gl, vulkan or vulkan-hlsl\n", api.c_str());
          return 1;
        }
        at = end + 1;
      }
    } else if (a == "--threads" && (v = next())) {
      o->threads = unsigned(std::max(1, std::atoi(v)));
    } else {
      return usage();
    }
  }
  if (o->sceneInstances < 0) {
    std::fprintf(stderr, "vff-gpu-bench: --scene takes a number of instances\n");
    return 1;
  }
  if (o->sdf && !o->fieldPath.empty() && !o->meshGiven) {
    std::fprintf(stderr, "vff-gpu-bench: error: --sdf with --field needs --mesh, the mesh the field was baked from\n");
    return 1;
  }
#ifndef VFF_GPU_BENCH_SDF
  if (o->sdf) {
    std::fprintf(stderr, "vff-gpu-bench: error: --sdf: built without the samples (VFF_BUILD_SAMPLES), no distance field\n");
    return 1;
  }
#endif
#ifndef VFF_GPU_BENCH_VULKAN
  if (o->vulkan || o->hlsl) {
    std::fprintf(stderr, "vff-gpu-bench: error: --api vulkan: built without Vulkan (libvulkan-dev, glslangValidator)\n");
    return 1;
  }
#endif
  if (o->sdfSize == 0) o->sdfSize = o->size;
  if (o->sdfSpp == 0) o->sdfSpp = o->spp;
  if (o->size < 8 || o->size % 8 != 0 || o->spp < 1 || o->sdfSize < 8 || o->sdfSize % 8 != 0 || o->sdfSpp < 1) {
    std::fprintf(stderr, "vff-gpu-bench: --size and --sdf-size must be positive multiples of 8, --spp and --sdf-spp positive\n");
    return 1;
  }
  return -1;
}

// ---- The field -----------------------------------------------------------------------------------

int fail(const vff::Error& e, int code) {
  std::fprintf(stderr, "vff-gpu-bench: %s\n", e.toString().c_str());
  return code;
}

// Bakes MESH (or the procedural torus knot when it does not exist) as samples/experiments does, into
// *file (the mesh in *meshOut), with the ground height (the mesh's lowest point). Returns an exit code, 0 on success.
int bakeField(const std::string& meshPath, vff::Result<vff::File>* file, float* groundY, vff::bake::Mesh* meshOut) {
  using namespace vff;
  bake::Mesh& mesh = *meshOut;
  std::string name = meshPath;
  if (std::filesystem::exists(meshPath)) {
    auto m = bake::loadMesh(meshPath);
    if (!m) return fail(m.error(), 2);
    mesh = std::move(*m);
  } else {
    mesh = bake::makeShape("torus-knot");
    name = "torus-knot (procedural; " + meshPath + " not found)";
  }
  *groundY = INFINITY;
  for (size_t v = 1; v < mesh.positions.size(); v += 3) *groundY = std::min(*groundY, mesh.positions[v]);
  auto scene = bake::Scene::create(mesh);
  if (!scene) return fail(scene.error(), 4);
  bake::BakeOptions bo;
  bo.positionScheme = PositionScheme::kOctaHemi2;
  bo.positionParam = 32;
  bo.mapResolution = 64;
  bo.encoding = DistanceEncoding::kUnorm8Diameter;
  const auto t0 = Clock::now();
  auto baked = bake::bakeField(*scene, bo);
  if (!baked) return fail(baked.error(), 4);
  auto bytes = writeMemory(baked->field, baked->distance);
  if (!bytes) return fail(bytes.error(), 4);
  *file = File::openBuffer(std::move(*bytes));
  std::printf("field: %s baked in %.1f s\n", name.c_str(), seconds(t0, Clock::now()));
  return 0;
}

// --field's file, or the baked default, with the ground height. Returns an exit code, 0 on success.
int openField(const BenchOptions& o, vff::Result<vff::File>* file, float* groundY, vff::bake::Mesh* mesh) {
  if (o.fieldPath.empty()) return bakeField(o.meshPath, file, groundY, mesh);
  if (o.sdf) {  // the distance field's mesh
    auto m = vff::bake::loadMesh(o.meshPath);
    if (!m) return fail(m.error(), 2);
    *mesh = std::move(*m);
  }
  *file = vff::File::open(o.fieldPath);
  if (!*file) return fail(file->error(), 2);
  *groundY = (*file)->field().sphere.center[1] - (*file)->field().sphere.radius;
  std::printf("field: %s\n", o.fieldPath.c_str());
  return 0;
}

// ---- Queries per second --------------------------------------------------------------------------

// n random rays: origins 1.05-3 R from the centre towards points within 1.1 R, unit directions, tmax
// 2 R; for the CPU (rays) and the shader's BenchRay (rayData, 8 floats each).
void makeRandomRays(const vff::FieldDesc& f, size_t n, uint64_t seed, std::vector<vff::Ray>* rays,
                    std::vector<float>* rayData) {
  using vff::Vec3;
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::mt19937_64 g{seed};
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto dir = [&] {
    const float z = 2 * u(g) - 1, phi = 6.2831853f * u(g);
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    return Vec3{r * std::cos(phi), r * std::sin(phi), z};
  };
  rayData->assign(n * 8, 0.0f);
  rays->assign(n, vff::Ray{});
  for (size_t i = 0; i < n; ++i) {
    const Vec3 a = dir(), b = dir();
    const float s = R * (1.05f + 2.0f * u(g)), s2 = R * 1.1f * std::cbrt(u(g));
    const Vec3 o{c.x + a.x * s, c.y + a.y * s, c.z + a.z * s};
    const Vec3 d{c.x + b.x * s2 - o.x, c.y + b.y * s2 - o.y, c.z + b.z * s2 - o.z};
    const float l = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const Vec3 w{d.x / l, d.y / l, d.z / l};
    (*rays)[i] = vff::Ray{o, w, 0.0f, 2.0f * R};
    float* r = &(*rayData)[i * 8];
    r[0] = o.x, r[1] = o.y, r[2] = o.z, r[3] = 2.0f * R, r[4] = w.x, r[5] = w.y, r[6] = w.z, r[7] = 0;
  }
}

// The GPU's best of 2 runs over n rays (bound at 5 and 6; the program in use), in seconds; the
// answers in *results.
double timeGpuRays(size_t n, GLuint resultBuffer, std::vector<float>* results) {
  double best = 1e30;
  for (int rep = 0; rep < 2; ++rep) {
    glFinish();
    const auto t0 = Clock::now();
    // At most 2^20 rays per dispatch (GL guarantees 65535 work groups per dimension).
    for (size_t first = 0; first < n; first += size_t(1) << 20) {
      glUniform1ui(1, GLuint(first));
      glDispatchCompute(GLuint((std::min(n - first, size_t(1) << 20) + 63) / 64), 1, 1);
    }
    glFinish();
    best = std::min(best, seconds(t0, Clock::now()));
  }
  results->assign(n, 0.0f);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, resultBuffer);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(n * 4), results->data());
  return best;
}

// The CPU's time over the rays, in seconds, with the batch calls, 4096 rays at a time (kNearest
// visibility: 0 or 1, as !occluded()); the answers in *results.
double timeCpuRays(const vff::FieldQuery& cpu, const std::vector<vff::Ray>& rays, bool interp, unsigned threads,
                   std::vector<float>* results) {
  const size_t n = rays.size();
  results->assign(n, 0.0f);
  std::span<float> out(*results);
  vff::QueryOptions qo;
  qo.reconstruction = interp ? vff::Reconstruction::kInterpolated : vff::Reconstruction::kNearest;
  const auto c0 = Clock::now();
  vff::parallel::parallelFor(n, 4096, threads, [&](size_t b, size_t e) {
    cpu.visibility(std::span<const vff::Ray>(rays.data() + b, e - b), out.subspan(b, e - b), qo);
  });
  return seconds(c0, Clock::now());
}

void benchQueries(const vff::FieldDesc& f, const vff::gl::GpuField& gpu, const vff::FieldQuery& cpu, GLuint rayProg,
                  unsigned threads) {
  std::printf("\nfield queries/s (random rays: origins 1.05-3 R from the centre towards points within 1.1 R, tmax 2 R;\n"
              "GPU wall time around dispatch + glFinish, best of 2; CPU on %u thread(s))\n", threads);
  std::printf("| rays | query | GPU rays/s | CPU rays/s | GPU/CPU |\n|---|---|---|---|---|\n");
  for (int logN = 20; logN <= 22; ++logN) {
    const size_t n = size_t(1) << logN;
    std::vector<float> rayData;
    std::vector<vff::Ray> rays;
    makeRandomRays(f, n, uint64_t(logN), &rays, &rayData);
    GLuint bufs[2];
    glGenBuffers(2, bufs);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[0]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(rayData.size() * 4), rayData.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[1]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(n * 4), nullptr, GL_STREAM_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, bufs[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, bufs[1]);
    gpu.bind();
    glUseProgram(rayProg);
    for (int interp = 0; interp < 2; ++interp) {
      glUniform1i(0, interp);
      std::vector<float> gres, cres;
      const double best = timeGpuRays(n, bufs[1], &gres);
      const double cpuS = timeCpuRays(cpu, rays, interp != 0, threads, &cres);
      size_t differ = 0;
      for (size_t i = 0; i < n; ++i) differ += std::fabs(gres[i] - cres[i]) > 1e-4f;
      std::printf("| 2^%d | %s | %.3g | %.3g | %.2f |   (answers differing by > 1e-4: %zu)\n", logN,
                  interp ? "interpolated visibility" : "nearest occluded", double(n) / best, double(n) / cpuS,
                  cpuS / best, differ);
      std::fflush(stdout);
    }
    glDeleteBuffers(2, bufs);
  }
}

// ---- AO render -----------------------------------------------------------------------------------

void benchAo(const vff::FieldDesc& f, float groundY, const vff::gl::GpuField& gpu, const vff::FieldQuery& cpu,
             GLuint aoProg, const BenchOptions& o) {
  using namespace vff;
  const int size = o.size, spp = o.spp;
  const harness::AoScene s = harness::makeAoScene(f, groundY, size, o.aoDistance);
  const harness::AoBuffers aoBuffers(s);
  gpu.bind();
  glUseProgram(aoProg);
  std::printf("\nground AO %dx%d, %d rays/px (%.3g rays), tmax %g R; GPU vs CPU image on the 8-bit scale\n", size,
              size, spp, double(size) * size * spp, double(o.aoDistance));
  std::printf("| query | GPU s | CPU s | GPU/CPU | max | RMS |\n|---|---|---|---|---|---|\n");
  for (int interp = 0; interp < 2; ++interp) {
    std::vector<float> g;
    const double gpuS = harness::renderAo(s, aoBuffers, spp, interp, &g);
    const auto c0 = Clock::now();
    const std::vector<float> cimg =
        harness::cpuAo(cpu, s, spp, interp ? Reconstruction::kInterpolated : Reconstruction::kNearest, o.threads);
    const double cpuS = seconds(c0, Clock::now());
    const harness::AoDiff d = harness::compareAo(cimg, g);
    std::printf("| %s | %.2f | %.2f | %.2f | %.0f | %.4f |\n", interp ? "interpolated visibility" : "nearest occluded", gpuS,
                cpuS, cpuS / gpuS, d.max, d.rms);
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace vff;
  BenchOptions o;
  if (const int code = parseOptions(argc, argv, &o); code >= 0) return code;
  const harness::HeadlessGl& gl = harness::headlessGl();
  if (!gl.ok) {
    std::fprintf(stderr, "vff-gpu-bench: no headless OpenGL 4.3 context: %s\n", gl.error.c_str());
    return 4;
  }
  std::printf("GPU: %s (GL_RENDERER: %s)\n", gl.renderer.c_str(), reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  std::printf("CPU baseline: vff::FieldQuery on %u thread(s)\n", o.threads);

  Result<File> file = makeError(Code::kInvalidArgument, "no field");
  float groundY = 0;
  bake::Mesh mesh;  // when baked
  if (const int code = openField(o, &file, &groundY, &mesh); code != 0) return code;
  if (!file) return 4;
  const FieldDesc& f = file->field();
  std::printf("  %u maps, %ux%u, distance encoding %u, R = %g\n", f.mapCount, f.mapResolution, f.mapResolution,
              unsigned(f.distanceEncoding), double(f.sphere.radius));
  auto gpu = gl::loadField(*file);
  auto cpu = FieldQuery::fromFile(*file);
  if (!gpu || !cpu) return fail(!gpu ? gpu.error() : cpu.error(), 4);
  if (file->layout().target == LayoutTarget::kTexture3D) {
    std::fprintf(stderr, "vff-gpu-bench: 3D-texture layouts are not benchmarked\n");
    return 4;
  }
  std::string log;
  const GLuint rayProg = buildProgram(kRayShader, &log);
  const GLuint aoProg = rayProg ? buildProgram(harness::kAoShader, &log) : 0;
  if (!rayProg || !aoProg) {
    std::fprintf(stderr, "vff-gpu-bench: shader: %s\n", log.c_str());
    return 4;
  }

  benchQueries(f, *gpu, *cpu, rayProg, o.threads);
#ifdef VFF_GPU_BENCH_VULKAN
  auto makeRays = [&f](size_t n, uint64_t seed, std::vector<Ray>* rays) {
    std::vector<float> unused;
    makeRandomRays(f, n, seed, rays, &unused);
  };
  for (const bool hlsl : {false, true}) {
    if (!(hlsl ? o.hlsl : o.vulkan)) continue;
    if (const int code = harness::benchVulkanQueries(*file, *cpu, makeRays, hlsl); code != 0) return code;
  }
#endif
  benchAo(f, groundY, *gpu, *cpu, aoProg, o);
  if (o.sceneInstances > 0) {
    const harness::SceneBenchOptions so{.instances = o.sceneInstances, .size = o.size, .spp = o.spp,
                                        .threads = o.threads, .aoDistance = o.aoDistance};
    if (const int code = harness::benchScene(*file, *cpu, groundY, so); code != 0) return code;
  }
#ifdef VFF_GPU_BENCH_SDF
  if (o.sdf) {
    const harness::SdfBenchOptions so{.size = o.sdfSize, .spp = o.sdfSpp, .threads = o.threads,
                                      .aoDistance = o.aoDistance};
    if (const int code = harness::benchSdf(*file, *cpu, mesh, groundY, *gpu, aoProg, so); code != 0) return code;
  }
#endif
  glDeleteProgram(rayProg);
  glDeleteProgram(aoProg);
  if (glGetError() != GL_NO_ERROR) {
    std::fprintf(stderr, "vff-gpu-bench: GL error\n");
    return 4;
  }
  return 0;
}
