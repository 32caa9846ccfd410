// wgsl_runner.h - the WebGPU side of the GPU suites: the WGSL translations of the Vulkan kernels
// (gpu/wgsl/kernels, generated from gpu/vulkan/shaders by web/tools/gen-wgsl.mjs) run through
// WebGPU in headless Chromium by web/tools/run-wgsl.mjs, with the data the Vulkan loaders upload.
//
//   wgsltest::Job job("nearest-array2d");                 // a folder under the test's temp dir
//   auto q = job.addQuery(file, rays);                    // as vff::vk::loadField + QueryPipeline::run
//   wgsltest::Outcome o = job.run();                      // one Chromium for every run of the job
//   if (o.skipped) GTEST_SKIP() << o.message;
//   std::vector<wgsltest::QueryAnswer> answers = job.answers<wgsltest::QueryAnswer>(*q);
//
// The bindings are the Vulkan descriptor set's (vff/vk/field.h, query.h, scene.h), all in group 0;
// the push constant {which, firstRay, rayCount} is the uniform at group 1, binding 0 (16 bytes).
// The data come from the same places as the Vulkan loaders': vff::gl::makeFieldBlock,
// makePositionsBuffer, planScene, makeSceneInstances, makeSceneNodes (vff_gl_data, no GL calls),
// the slices from File::readSlice. The textures are those of vff::vk: r8uint (unorm8-diameter,
// unorm8-chord, bit1 at a byte per 8 texels), r16uint (unorm16-diameter), bc4-r-unorm
// (bc4-diameter), normals rg16sint (a 1 x 1 x 1 placeholder without a normal plane). A BC4 texture
// also carries its texels decoded by vff::decodeBc4Block as an r8unorm fallback, which the runner
// binds instead where the adapter does not decode BC4 (SwiftShader's WebGPU reads zeros), saying so
// in a note that run() prints: the bc4 kernel is then checked, the adapter's BC4 decoder is not.
//
// The answer and ray structs are the std430 layouts of vff::vk::QueryRay, QueryAnswer and
// SceneRay, declared here so that the WebGPU suites build without the Vulkan headers; the scene's
// answers are scene_cases.h's SceneOut (vff::vk::SceneAnswer's layout).
//
// Skips (Outcome::skipped, with the reason): no node (VFF_NODE at configure time, or the
// environment's VFF_NODE), no web/node_modules/playwright-core, no chromium or no WebGPU adapter
// (the runner's exit 77), a kernel not generated yet.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "vff/error.h"
#include "vff/gl/scene_loader.h"
#include "vff/vff.h"

namespace vff::wgsltest {

// std430 VffVkRay (vff::vk::QueryRay).
struct QueryRay {
  float origin[4];
  float direction[4];
  float range[4];  // tmin, tmax, intraBias, unused
};
static_assert(sizeof(QueryRay) == 48);

// std430 VffVkAnswer (vff::vk::QueryAnswer).
struct QueryAnswer {
  enum : uint32_t { kHit = 1, kInside = 2, kLooked = 4, kHasNormal = 8, kInterpHit = 16, kInterpHasNormal = 32 };
  uint32_t flags;
  float t;
  uint32_t sampleIndex, texelI, texelJ, code;
  float distance;
  float visibility;
  float normal[4];
  float interpNormal[4];
  float interpT[4];
};
static_assert(sizeof(QueryAnswer) == 80);

// std430 VffVkSceneRay (vff::vk::SceneRay).
struct SceneRay {
  float origin[3];
  uint32_t source;
  float direction[3];
  float tmin;
  float tmax;
  float intraBias;
  uint32_t reserved[2];
};
static_assert(sizeof(SceneRay) == 48);

// The kernels, one per Vulkan variant.
enum class Kernel { kQuery2D, kQuery3D, kQueryBc4, kScene, kRefine };
const char* kernelName(Kernel k);  // "vff_vk_query.wgsl", ...
std::string kernelPath(Kernel k);  // in the source tree's gpu/wgsl/kernels
// The kernel a field needs (the Vulkan loader's MapsKind).
Kernel queryKernel(const File& file);

// Why the runner cannot run here ("" when node and playwright-core are there).
std::string environmentSkip();

struct Outcome {
  bool ok = false;
  bool skipped = false;
  std::string message;  // the skip's reason or the failure, from the runner's output
  std::string log;      // everything the runner printed
};

// A scene's fields in the job, as vff::vk::loadScene uploads them (the textures, positions and
// field table, written once; every run of the scene binds them).
struct SceneData {
  gl::ScenePlan plan;
  std::vector<const FieldQuery*> queries;
  std::string maps, normals, positions, fields;  // the job's files
  std::string mapsBindings, normalsBindings;     // their texture bindings (JSON)
};

class Job {
 public:
  // The folder <testing::TempDir()>/vff-wgsl-<name>-<pid>, emptied first.
  explicit Job(const std::string& name);
  ~Job();  // removes the folder when every run succeeded
  Job(const Job&) = delete;
  Job& operator=(const Job&) = delete;

  // One field's query: vff::vk::loadField's bindings 0 to 3, the rays at 4, the answers at 5,
  // `which` (bit 0 kNearest, bit 1 kInterpolated) in the push constant. Returns the run's index.
  Result<size_t> addQuery(const File& file, std::span<const QueryRay> rays, uint32_t which = 3);

  // One refined field's query (gpu/vulkan/shaders/vff_vk_refine.comp's WGSL; 2D-array maps): the
  // query's bindings, and the refinement as vff::gl::makeRefinementBuffers gives it, at 10 to 14.
  // Its answers are kRefinedAnswerBytes a ray (refine_cases.h's GpuOut).
  Result<size_t> addRefinedQuery(const File& file, std::span<const QueryRay> rays);
  static constexpr size_t kRefinedAnswerBytes = 64;

  // The scene's fields (vff::vk::loadScene), then a run of the scene as `scene` is committed
  // (GpuScene::update) over `rays` (ScenePipeline::run: bindings 1 to 8, `which` all four queries).
  Result<SceneData> addSceneFields(std::span<const gl::SceneField> fields);
  Result<size_t> addSceneRun(const SceneData& data, const Scene& scene, std::span<const SceneRay> rays,
                             uint32_t which = 15);

  // Runs every run in one Chromium (node web/tools/run-wgsl.mjs <folder>).
  Outcome run();

  // A run's answers (empty before a successful run()).
  template <class T>
  std::vector<T> answers(size_t run) const {
    const std::vector<uint8_t>& b = outputs_.at(run);
    std::vector<T> out(b.size() / sizeof(T));
    if (!out.empty()) std::memcpy(out.data(), b.data(), out.size() * sizeof(T));
    return out;
  }

  const std::string& folder() const { return folder_; }

 private:
  std::string writeFile(const std::string& stem, const void* data, size_t size);
  // Bindings 0 to 4 of a query run (the field as vff::vk::loadField uploads it, the rays).
  Result<std::string> fieldBindings(const File& file, std::span<const QueryRay> rays);
  size_t addRun(Kernel kernel, const std::string& bindings, size_t items, size_t answerBytes, uint32_t which);

  std::string folder_;
  int files_ = 0;
  std::vector<std::string> runs_;         // each run's JSON
  std::vector<std::string> outputFiles_;  // each run's answers file
  std::vector<size_t> outputSizes_;
  std::vector<std::vector<uint8_t>> outputs_;
  bool keep_ = true;
};

}  // namespace vff::wgsltest
