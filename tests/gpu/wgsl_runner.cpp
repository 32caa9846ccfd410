// wgsl_runner.cpp - see wgsl_runner.h.
#include "wgsl_runner.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "vff/bc4.h"
#include "vff/gl/loader.h"
#include "vff/gl/refine_loader.h"

namespace vff::wgsltest {
namespace fs = std::filesystem;

namespace {

std::string node() {
  if (const char* env = std::getenv("VFF_NODE"); env && *env) return env;
  return VFF_NODE;  // find_program at configure time; "" when not found
}

std::string webDir() {
  return std::string(VFF_SOURCE_DIR) + "/web";
}

std::string shellQuoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string bufferBinding(uint32_t binding, const char* kind, const std::string& file) {
  return "{\"group\":0,\"binding\":" + std::to_string(binding) + ",\"kind\":\"" + kind +
         "\",\"file\":" + jsonString(file) + "}";
}

// A texture binding; `writes`: its JSON list of {offset, origin, size} ("" for the whole texture).
std::string textureBinding(uint32_t binding, const std::string& file, bool is3D, const char* format, uint32_t w,
                           uint32_t h, uint32_t layers, const std::string& writes = "") {
  std::string s = "{\"group\":0,\"binding\":" + std::to_string(binding) +
                  ",\"kind\":\"texture\",\"file\":" + jsonString(file) + ",\"dimension\":\"" +
                  (is3D ? "3d" : "2d-array") + "\",\"format\":\"" + format + "\",\"width\":" + std::to_string(w) +
                  ",\"height\":" + std::to_string(h) + ",\"layers\":" + std::to_string(layers);
  if (!writes.empty()) s += ",\"writes\":[" + writes + "]";
  return s + "}";
}

std::string textureWrite(size_t offset, uint32_t layer, uint32_t w, uint32_t h) {
  return "{\"offset\":" + std::to_string(offset) + ",\"origin\":[0,0," + std::to_string(layer) + "],\"size\":[" +
         std::to_string(w) + "," + std::to_string(h) + ",1]}";
}

// Appends `item` to a JSON list's items.
void appendListItem(std::string& list, const std::string& item) {
  if (!list.empty()) list += ',';
  list += item;
}

// Appends every slice of the plane (File::readSlice: the maps at their placements, gutters filled).
Status appendSlices(const File& file, Plane plane, std::vector<uint8_t>& out) {
  std::vector<uint8_t> slice(file.sliceBytes(plane));
  for (uint32_t s = 0; s < file.layout().sliceCount; ++s) {
    if (Status st = file.readSlice(plane, s, slice); !st) return st;
    out.insert(out.end(), slice.begin(), slice.end());
  }
  return {};
}

// BC4 slices (rows of 4x4 blocks) decoded by libvff's decoder into r8 texels, w x h a slice.
std::vector<uint8_t> decodeBc4Slices(const std::vector<uint8_t>& blocks, uint32_t w, uint32_t h) {
  const size_t sliceBlocks = size_t(w / 4) * (h / 4);
  const size_t slices = blocks.size() / (sliceBlocks * kBc4BlockBytes);
  std::vector<uint8_t> texels(slices * w * h);
  uint8_t codes[16];
  for (size_t s = 0; s < slices; ++s)
    for (uint32_t by = 0; by < h / 4; ++by)
      for (uint32_t bx = 0; bx < w / 4; ++bx) {
        decodeBc4Block(&blocks[((s * (h / 4) + by) * (w / 4) + bx) * kBc4BlockBytes], codes);
        for (uint32_t u = 0; u < 16; ++u) texels[(s * h + by * 4 + u / 4) * w + bx * 4 + u % 4] = codes[u];
      }
  return texels;
}

// The distance texture's format and width in texels (vff::vk's mapsFormat).
Result<std::pair<const char*, uint32_t>> mapsFormat(const File& file) {
  const uint32_t w = file.layout().sliceWidth;
  switch (file.field().distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
      return std::pair<const char*, uint32_t>{"r8uint", w};
    case DistanceEncoding::kBit1:
      return std::pair<const char*, uint32_t>{"r8uint", w / 8};
    case DistanceEncoding::kUnorm16Diameter:
      return std::pair<const char*, uint32_t>{"r16uint", w};
    case DistanceEncoding::kBc4Diameter:
      return std::pair<const char*, uint32_t>{"bc4-r-unorm", w};
    default:
      return makeError(Code::kUnsupported, "no WebGPU format for this distance encoding");
  }
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The line of the runner's output that starts with `prefix`, without it.
std::string lineAfter(const std::string& log, const std::string& prefix) {
  std::istringstream in(log);
  std::string line, found;
  while (std::getline(in, line))
    if (line.rfind(prefix, 0) == 0 && found.empty()) found = line.substr(prefix.size());
  return found;
}

}  // namespace

const char* kernelName(Kernel k) {
  switch (k) {
    case Kernel::kQuery2D:
      return "vff_vk_query.wgsl";
    case Kernel::kQuery3D:
      return "vff_vk_query_3d.wgsl";
    case Kernel::kQueryBc4:
      return "vff_vk_query_bc4.wgsl";
    case Kernel::kRefine:
      return "vff_vk_refine.wgsl";
    default:
      return "vff_vk_scene.wgsl";
  }
}

std::string kernelPath(Kernel k) {
  return std::string(VFF_SOURCE_DIR) + "/gpu/wgsl/kernels/" + kernelName(k);
}

Kernel queryKernel(const File& file) {
  if (file.field().distanceEncoding == DistanceEncoding::kBc4Diameter) return Kernel::kQueryBc4;
  return file.layout().target == LayoutTarget::kTexture3D ? Kernel::kQuery3D : Kernel::kQuery2D;
}

std::string environmentSkip() {
  if (node().empty()) return "node was not found (VFF_NODE)";
  if (node().find('/') != std::string::npos && !fs::exists(node())) return "no node at " + node() + " (VFF_NODE)";
  if (!fs::exists(webDir() + "/node_modules/playwright-core"))
    return "web/node_modules/playwright-core is missing (npm ci in web/)";
  return "";
}

Job::Job(const std::string& name) {
  folder_ = (fs::path(::testing::TempDir()) / ("vff-wgsl-" + name + "-" + std::to_string(getpid()))).string();
  std::error_code ec;
  fs::remove_all(folder_, ec);
  fs::create_directories(folder_, ec);
}

Job::~Job() {
  if (keep_) {
    std::printf("[ wgsl ] the job is kept in %s\n", folder_.c_str());
    return;
  }
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

std::string Job::writeFile(const std::string& stem, const void* data, size_t size) {
  const std::string name = std::to_string(files_++) + "-" + stem + ".bin";
  std::ofstream out(fs::path(folder_) / name, std::ios::binary);
  out.write(static_cast<const char*>(data), std::streamsize(size));
  return name;
}

size_t Job::addRun(Kernel kernel, const std::string& bindings, size_t items, size_t answerBytes, uint32_t which) {
  const size_t index = runs_.size();
  const uint32_t push[4] = {which, 0, uint32_t(items), 0};
  const std::string pushFile = writeFile("push", push, sizeof(push));
  const std::string answers = "answers-" + std::to_string(index) + ".bin";
  const uint32_t answerBinding = kernel == Kernel::kScene ? 8 : 5;
  std::string s = "{\"name\":" + jsonString(std::string(kernelName(kernel)) + " run " + std::to_string(index)) +
                  ",\"kernel\":" + jsonString(kernelPath(kernel)) +
                  ",\"entry\":\"main\",\"workgroups\":" + std::to_string((items + 63) / 64) +
                  ",\"workgroupSize\":64,\"firstItem\":{\"group\":1,\"binding\":0,\"offset\":4},\"bindings\":[" +
                  bindings + ",{\"group\":0,\"binding\":" + std::to_string(answerBinding) +
                  ",\"kind\":\"storage-rw\",\"size\":" + std::to_string(answerBytes) +
                  "},{\"group\":1,\"binding\":0,\"kind\":\"uniform\",\"file\":" + jsonString(pushFile) +
                  "}],\"outputs\":[{\"group\":0,\"binding\":" + std::to_string(answerBinding) +
                  ",\"file\":" + jsonString(answers) + ",\"size\":" + std::to_string(answerBytes) + "}]}";
  runs_.push_back(s);
  outputFiles_.push_back(answers);
  outputSizes_.push_back(answerBytes);
  return index;
}

Result<std::string> Job::fieldBindings(const File& file, std::span<const QueryRay> rays) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  auto block = gl::makeFieldBlock(field, layout);
  if (!block) return block.error();
  auto positions = gl::makePositionsBuffer(field);
  if (!positions) return positions.error();
  auto format = mapsFormat(file);
  if (!format) return format.error();
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  std::vector<uint8_t> maps, normals;
  if (Status st = appendSlices(file, Plane::kDistance, maps); !st) return st.error();
  std::string normalsBinding;
  if (file.hasNormals()) {
    if (field.normalEncoding != NormalEncoding::kOctSnorm16)
      return makeError(Code::kUnsupported, "no WebGPU format for this normal encoding");
    if (Status st = appendSlices(file, Plane::kNormal, normals); !st) return st.error();
    normalsBinding = textureBinding(3, writeFile("normals", normals.data(), normals.size()), is3D, "rg16sint",
                                    layout.sliceWidth, layout.sliceHeight, layout.sliceCount);
  } else {
    // The placeholder of a field without normals: the kernel declares the binding either way.
    const uint32_t zero = 0;
    normalsBinding = textureBinding(3, writeFile("normals", &zero, sizeof(zero)), is3D, "rg16sint", 1, 1, 1);
  }
  std::string mapsBinding = textureBinding(1, writeFile("maps", maps.data(), maps.size()), is3D, format->first,
                                           format->second, layout.sliceHeight, layout.sliceCount);
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    // For an adapter that does not decode BC4 (the runner checks): the texels, decoded.
    const std::vector<uint8_t> texels = decodeBc4Slices(maps, layout.sliceWidth, layout.sliceHeight);
    mapsBinding.pop_back();
    mapsBinding += ",\"fallback\":{\"format\":\"r8unorm\",\"file\":" +
                   jsonString(writeFile("maps-decoded", texels.data(), texels.size())) + "}}";
  }
  return bufferBinding(0, "uniform", writeFile("field", &*block, sizeof(gl::FieldBlock))) + "," + mapsBinding + "," +
      bufferBinding(2, "storage-read", writeFile("positions", positions->data(), positions->size() * 4)) + "," +
      normalsBinding + "," + bufferBinding(4, "storage-read", writeFile("rays", rays.data(), rays.size_bytes()));
}

Result<size_t> Job::addQuery(const File& file, std::span<const QueryRay> rays, uint32_t which) {
  auto bindings = fieldBindings(file, rays);
  if (!bindings) return bindings.error();
  return addRun(queryKernel(file), *bindings, rays.size(), rays.size() * sizeof(QueryAnswer), which);
}

Result<size_t> Job::addRefinedQuery(const File& file, std::span<const QueryRay> rays) {
  if (queryKernel(file) != Kernel::kQuery2D)
    return makeError(Code::kUnsupported, "the refined kernel is generated for 2D-array maps only");
  auto bindings = fieldBindings(file, rays);
  if (!bindings) return bindings.error();
  auto b = gl::makeRefinementBuffers(file.field(), file.refinement());
  if (!b) return b.error();
  // (A buffer holds at least 16 bytes: WebGPU binds no empty buffer.)
  auto words = [&](const char* stem, const auto& v) {
    std::vector<uint8_t> bytes(std::max<size_t>(16, v.size() * 4), 0);
    if (!v.empty()) std::memcpy(bytes.data(), v.data(), v.size() * 4);
    return writeFile(stem, bytes.data(), bytes.size());
  };
  const std::string all = *bindings + "," + bufferBinding(10, "storage-read", words("unsure", b->unsure)) + "," +
                          bufferBinding(11, "storage-read", words("vertices", b->vertices)) + "," +
                          bufferBinding(12, "storage-read", words("bvh", b->nodes)) + "," +
                          bufferBinding(13, "storage-read", words("triangles", b->triangles)) + "," +
                          bufferBinding(14, "uniform", writeFile("refine", &b->block, sizeof b->block));
  return addRun(Kernel::kRefine, all, rays.size(), rays.size() * kRefinedAnswerBytes, 0);
}

Result<SceneData> Job::addSceneFields(std::span<const gl::SceneField> fields) {
  SceneData d;
  std::vector<FieldDesc> descs;
  std::vector<LayoutDesc> layouts;
  for (const gl::SceneField& f : fields) {
    descs.push_back(f.file->field());
    layouts.push_back(f.file->layout());
    d.queries.push_back(f.query);
  }
  auto plan = gl::planScene(descs, layouts);
  if (!plan) return plan.error();
  d.plan = std::move(*plan);
  const gl::ScenePlan& p = d.plan;
  // Field f's slices at layer mapsLayer (normalsLayer) from the corner (0, 0), as vff::vk::loadScene.
  std::vector<uint8_t> maps, normals;
  std::string mapsWrites, normalsWrites;
  for (size_t f = 0; f < fields.size(); ++f) {
    const File& file = *fields[f].file;
    const LayoutDesc& layout = file.layout();
    auto format = mapsFormat(file);
    if (!format) return format.error();
    for (uint32_t s = 0; s < layout.sliceCount; ++s)
      appendListItem(mapsWrites, textureWrite(maps.size() + s * file.sliceBytes(Plane::kDistance),
                                              p.fields[f].mapsLayer + s, format->second, layout.sliceHeight));
    if (Status st = appendSlices(file, Plane::kDistance, maps); !st) return st.error();
    if (!file.hasNormals() || p.normalsLayers == 0) continue;
    for (uint32_t s = 0; s < layout.sliceCount; ++s)
      appendListItem(normalsWrites, textureWrite(normals.size() + s * file.sliceBytes(Plane::kNormal),
                                                 p.fields[f].normalsLayer + s, layout.sliceWidth, layout.sliceHeight));
    if (Status st = appendSlices(file, Plane::kNormal, normals); !st) return st.error();
  }
  d.maps = writeFile("scene-maps", maps.data(), maps.size());
  d.mapsBindings = textureBinding(1, d.maps, false, p.wideTexels ? "r16uint" : "r8uint", p.mapsWidth, p.mapsHeight,
                                  p.mapsLayers, mapsWrites);
  if (p.normalsLayers > 0) {
    d.normals = writeFile("scene-normals", normals.data(), normals.size());
    d.normalsBindings = textureBinding(3, d.normals, false, "rg16sint", p.normalsWidth, p.normalsHeight,
                                       p.normalsLayers, normalsWrites);
  } else {
    const uint32_t zero = 0;
    d.normals = writeFile("scene-normals", &zero, sizeof(zero));
    d.normalsBindings = textureBinding(3, d.normals, false, "rg16sint", 1, 1, 1);
  }
  d.positions = writeFile("scene-positions", p.positions.data(), p.positions.size() * sizeof(float));
  d.fields = writeFile("scene-fields", p.fields.data(), p.fields.size() * sizeof(gl::SceneFieldBlock));
  return d;
}

Result<size_t> Job::addSceneRun(const SceneData& d, const Scene& scene, std::span<const SceneRay> rays,
                                uint32_t which) {
  // GpuScene::update's instance table and nodes.
  auto h = scene.hierarchy();
  if (!h) return std::move(h).error();
  auto inst = gl::makeSceneInstances(scene, *h, d.queries);
  if (!inst) return std::move(inst).error();
  auto nodes = gl::makeSceneNodes(*h, uint32_t(inst->size()));
  if (!nodes) return std::move(nodes).error();
  const std::string bindings =
      d.mapsBindings + "," + bufferBinding(2, "storage-read", d.positions) + "," + d.normalsBindings + "," +
      bufferBinding(4, "storage-read", d.fields) + "," +
      bufferBinding(5, "storage-read",
                    writeFile("instances", inst->data(), inst->size() * sizeof(gl::SceneInstanceBlock))) +
      "," + bufferBinding(6, "storage-read", writeFile("nodes", nodes->data(), nodes->size())) + "," +
      bufferBinding(7, "storage-read", writeFile("rays", rays.data(), rays.size_bytes()));
  return addRun(Kernel::kScene, bindings, rays.size(), rays.size() * 48, which);
}

Outcome Job::run() {
  Outcome o;
  if (std::string skip = environmentSkip(); !skip.empty()) {
    o.skipped = true;
    o.message = skip;
    keep_ = false;
    return o;
  }
  {
    std::ofstream job(fs::path(folder_) / "job.json");
    job << "{\"runs\":[\n";
    for (size_t r = 0; r < runs_.size(); ++r) job << runs_[r] << (r + 1 < runs_.size() ? ",\n" : "\n");
    job << "]}\n";
  }
  const std::string logPath = (fs::path(folder_) / "run-wgsl.log").string();
  const std::string cmd = shellQuoted(node()) + " " + shellQuoted(webDir() + "/tools/run-wgsl.mjs") + " " +
                          shellQuoted(folder_) + " > " + shellQuoted(logPath) + " 2>&1";
  const int status = std::system(cmd.c_str());
  o.log = readText(logPath);
  const int rc = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (rc == 77) {
    o.skipped = true;
    o.message = lineAfter(o.log, "SKIP: ");
    keep_ = false;
    return o;
  }
  if (rc != 0) {
    o.message = "run-wgsl.mjs exited with " + std::to_string(rc) + ":\n" + o.log;
    return o;
  }
  for (size_t r = 0; r < runs_.size(); ++r) {
    const std::string bytes = readText((fs::path(folder_) / outputFiles_[r]).string());
    if (bytes.size() != outputSizes_[r]) {
      o.message = "run " + std::to_string(r) + ": " + std::to_string(bytes.size()) + " bytes of answers, expected " +
                  std::to_string(outputSizes_[r]);
      return o;
    }
    outputs_.emplace_back(bytes.begin(), bytes.end());
  }
  o.ok = true;
  keep_ = false;
  if (const std::string note = lineAfter(o.log, "note: "); !note.empty())
    std::printf("[ wgsl ] note: %s\n", note.c_str());
  if (const std::string adapter = lineAfter(o.log, "adapter: "); !adapter.empty())
    std::printf("[ wgsl ] adapter: %s\n", adapter.c_str());
  return o;
}

}  // namespace vff::wgsltest
