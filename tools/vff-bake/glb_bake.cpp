// glb_bake.cpp - vff-bake SCENE.gltf|glb -o X.glb: a field per mesh of the scene, each in its mesh's
// own frame, attached to the asset with the glTF extension VFF_visibility_field
// (spec/gltf/VFF_visibility_field/README.md) in one self-contained .glb; with --external-fields
// the fields go beside it as X.meshI.vff and the .glb references them by uri.
//
// Each field is the very file `--split mesh` writes for that mesh (the same META), baked through
// split_bake.cpp's bakeObject into a temporary. Embedded fields are read back and packed
// (vff::bake::packGlbWithFields); the .glb is written to a temporary and renamed into place last,
// after the external fields, as --split puts its set in place: an error or an interrupt leaves the
// old outputs as they were and no temporary behind.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "bake.h"
#include "cli.h"
#include "vff/bake/gltf.h"
#include "vff/bake/gltf_fields.h"
#include "vff/bake/mesh.h"

namespace vff::bake_tool {
namespace {

// The output path without ".glb".
std::string glbStem(const std::string& output) { return output.substr(0, output.size() - 4); }

// The bounds of the vertices of the mesh's triangles (what the extension's min and max declare).
void triangleBounds(const bake::Mesh& m, std::array<float, 3>* lo, std::array<float, 3>* hi) {
  *lo = {INFINITY, INFINITY, INFINITY};
  *hi = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t v : m.indices)
    for (size_t k = 0; k < 3; ++k) {
      (*lo)[k] = std::min((*lo)[k], m.positions[3 * size_t(v) + k]);
      (*hi)[k] = std::max((*hi)[k], m.positions[3 * size_t(v) + k]);
    }
}

// A file name as a glTF uri: every byte but letters, digits and "-._~" percent-encoded, which
// every reader decodes back (spaces included, which some do not accept raw).
std::string uriOf(const std::string& name) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

Status readBytes(const std::string& path, std::vector<uint8_t>* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot be opened");
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) return makeError(Code::kIoRead, path + ": cannot be read");
  return {};
}

// The bufferView each mesh's field went to, from the packed file's JSON.
nlohmann::json fieldViews(const std::vector<uint8_t>& glb) {
  if (glb.size() < 20) return nullptr;
  uint32_t n = 0;
  std::copy(glb.begin() + 12, glb.begin() + 16, reinterpret_cast<uint8_t*>(&n));
  const nlohmann::json doc = nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + n, nullptr, false);
  nlohmann::json views = nlohmann::json::object();
  if (!doc.is_object() || !doc.contains("meshes")) return views;
  for (size_t m = 0; m < doc["meshes"].size(); ++m) {
    const nlohmann::json& mesh = doc["meshes"][m];
    if (mesh.contains("extensions") && mesh["extensions"].contains(bake::kGltfFieldExtension) &&
        mesh["extensions"][bake::kGltfFieldExtension].contains("bufferView"))
      views[std::to_string(m)] = mesh["extensions"][bake::kGltfFieldExtension]["bufferView"];
  }
  return views;
}

}  // namespace

int bakeGltfGlb(const Options& o, bake::BakeOptions bo, WriteOptions wo) {
  bake::MeshInfo info;
  const auto t0 = std::chrono::steady_clock::now();
  auto objects = bake::loadGltfObjects(o.mesh, {.split = bake::GltfSplit::kMesh, .scene = o.scene, .ownFrame = true}, &info);
  if (!objects) return reportLoadError(objects.error(), o.mesh);
  noteUnbakedScenes(o, info);

  // Plan every field before any output exists. Embedded fields are written to temporaries beside
  // the output, named after the file --external-fields would write.
  const std::string stem = glbStem(o.output);
  std::vector<Planned> plan;
  for (const bake::GltfObject& obj : *objects) {
    const std::string path = stem + ".mesh" + std::to_string(obj.mesh) + ".vff";
    Planned p{path, temporaryOf(path), {}, 0};
    auto field = bake::describeBake(obj.geometry, bo);
    if (auto rc = checkPlan(field, wo.layout, &p.payload)) return *rc;
    p.field = *field;
    plan.push_back(std::move(p));
  }
  const std::vector<Planned> external = o.externalFields ? plan : std::vector<Planned>{};
  if (auto rc = checkOutputs(external, o.output)) return *rc;
  // What the packing needs (every buffer and image the asset references) is there before any bake.
  if (auto packable = bake::packGlbWithFields(o.mesh, {}); !packable) return cli::reportError(kProg, o.mesh, packable.error());

  std::vector<std::string> written;  // this run's temporaries, complete or being written
  std::vector<bake::GltfFieldPayload> payloads;
  nlohmann::json report = nlohmann::json::array();
  for (size_t i = 0; i < objects->size(); ++i) {
    const bake::GltfObject& obj = (*objects)[i];
    nlohmann::json entry;
    if (auto rc = bakeObject(o, bo, wo, obj, info, plan[i], &written, &entry)) return *rc;
    bake::GltfFieldPayload p;
    p.mesh = obj.mesh;
    p.geometryHash = cli::hexDigits64(bake::geometryHash(obj.geometry));
    triangleBounds(obj.geometry, &p.min, &p.max);
    if (o.externalFields) {
      p.uri = uriOf(baseName(plan[i].path));
      entry["uri"] = p.uri;
    } else {
      if (Status s = readBytes(plan[i].temporary, &p.bytes); !s) {
        removeAll(written);
        return cli::reportError(kProg, o.output, s.error());
      }
      ::unlink(plan[i].temporary.c_str());
      written.erase(std::find(written.begin(), written.end(), plan[i].temporary));
      entry.erase("output");
    }
    entry["geometryHash"] = p.geometryHash;
    payloads.push_back(std::move(p));
    report.push_back(entry);
    if (!o.quiet && !o.json)
      std::fprintf(stderr, "%s: %s: mesh %zu/%zu (mesh %d%s, %s)%s\n", kProg, o.mesh.c_str(), i + 1, objects->size(),
                   obj.mesh, obj.name.empty() ? "" : (" '" + obj.name + "'").c_str(),
                   cli::count(obj.geometry.triangleCount(), "triangle").c_str(),
                   o.externalFields ? (" -> " + plan[i].path).c_str() : "");
  }

  // The .glb, to its temporary; then the whole set goes into place.
  auto glb = bake::packGlbWithFields(o.mesh, payloads);
  if (!glb) {
    removeAll(written);
    return cli::reportError(kProg, o.mesh, glb.error());
  }
  const std::string glbTmp = temporaryOf(o.output);
  removeStaleTemporaries(o.output);
  written.push_back(glbTmp);
  removeTemporaryOnSignal(o.output, written);
  Status st = writeText(glbTmp, std::string_view(reinterpret_cast<const char*>(glb->data()), glb->size()), wo.sync);
  if (!st) {
    removeAll(written);
    return cli::reportError(kProg, o.output, st.error());
  }
  if (auto rc = commitSet(external, o.output, glbTmp, stem, wo.sync)) return *rc;

  if (o.json) {
    if (!o.externalFields) {
      const nlohmann::json views = fieldViews(*glb);
      for (auto& e : report)
        if (views.contains(std::to_string(e["mesh"].get<int>()))) e["bufferView"] = views[std::to_string(e["mesh"].get<int>())];
    }
    nlohmann::json summary = {{"mesh", o.mesh},     {"scene", info.gltfScene},   {"output", o.output},
                              {"fields", report},   {"fileBytes", glb->size()}, {"seconds", secondsSince(t0)}};
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr, "%s: %s: %s in %.2f s -> %s\n", kProg, o.mesh.c_str(), cli::count(payloads.size(), "field").c_str(),
                 secondsSince(t0), o.output.c_str());
  }
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
