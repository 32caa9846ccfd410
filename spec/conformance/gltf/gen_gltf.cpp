// gen_gltf.cpp - vff-gltf-gen OUTDIR: the conformance assets of the glTF extension
// VFF_visibility_field (README.md, spec/gltf/VFF_visibility_field/README.md). Every asset is
// written by this tool byte by byte (JSON by nlohmann, the GLB framing by gen_gltf_write.cpp), so
// the vectors do not depend on the writer they test. The fields are tiny bakes of procedural shapes
// (libvff's writer, stored blocks; the partial result with vff-bake's own partial options, zstd
// blocks), so the bytes depend only on libvff, the baker, this tool and, for the one partial
// result, libzstd.
//
// manifest.json lists, for each asset, the problems a reader reports (rule, severity, JSON pointer,
// in check order) and the fields it finds (match, usability, hashes, payload size and XXH3-64).
//
// This file: the assets that break no rule, and main. gen_gltf.h lists the others.
#include <zstd.h>

#include <filesystem>
#include <fstream>

#include "gen_gltf.h"
#include "vff/bake/procedural.h"

namespace fs = std::filesystem;

namespace vff::gltf_gen {
std::vector<Output> validAssets(const Fields& f) {
  std::vector<Output> out;
  const std::vector<std::pair<int, bool>> node0 = {{0, true}};
  {  // one mesh, its field embedded; matched exactly
    Output o("valid/one-mesh.glb");
    Asset a = oneTetra(f, f.tetraField.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  // Two meshes, three nodes: a similarity, a plain one, one with a non-uniform scale (14104). The
  // tetrahedron's field is embedded, the box's is box.vff beside the .glb.
  {
    Output o("valid/two-meshes-three-nodes.glb");
    Asset a;
    const int t = a.mesh(f.tetra, "tetrahedron"), b = a.mesh(f.box, "box");
    a.node(t, "turned", {{"rotation", {0.0, 0.6, 0.0, 0.8}}, {"scale", {2.0, 2.0, 2.0}}, {"translation", {1.0, 0.0, -3.0}}});
    a.node(b, "plain");
    a.node(b, "stretched", {{"scale", {1.0, 3.0, 1.0}}});
    a.scene();
    a.used();
    a.attach(t, a.payloadView(f.tetraField.bytes), f.tetraField.geometry);
    a.attachUri(b, "box.vff", f.boxField.geometry);
    o.bytes = asGlb(a);
    o.meshes = 2;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), {{0, true}}));
    o.fields.push_back(validField(1, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), {{1, true}, {2, false}}));
    o.problems.push_back({14104, "note", "/nodes/2"});
    out.push_back(std::move(o));
  }
  {  // a .gltf with the field in a .vff file beside it (the close and mismatch assets share it)
    Output o("valid/external-uri.gltf");
    Asset a;
    const int m = a.mesh(f.box, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "box.vff", f.boxField.geometry);
    o.bytes = asGltf(a);
    o.beside["valid/box.vff"] = f.boxField.bytes;
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  {  // a .gltf with the field in a data: URI (and a mimeType, optional with uri)
    Output o("valid/data-uri.gltf");
    Asset a;
    const int m = a.mesh(f.box, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "data:application/vnd.vff;base64," + bake::base64(f.boxField.bytes), f.boxField.geometry);
    a.ext(m)["mimeType"] = kMediaType;
    o.bytes = asGltf(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  // The box shipped with its +x face moved: by a quarter of tau (close, used) and by three tau
  // (mismatch, not used). The field is the one baked from the box as it was.
  for (const auto& [name, steps] : {std::pair<std::string, double>{"close", 0.25}, {"mismatch", 3.0}}) {
    Output o("valid/" + name + ".glb");
    const bake::Mesh moved = movedBox(float(steps * f.boxField.tolerance()));
    const Geometry shipped = geometryOf(moved);
    Asset a;
    const int m = a.mesh(moved, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "box.vff", f.boxField.geometry);
    o.bytes = asGltf(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, shipped,
                                  f.boxField.tolerance(), node0));
    if (name == "close")
      o.problems.push_back({14102, "note", extPath(0)});
    else
      o.problems.push_back({14103, "warning", extPath(0)});
    out.push_back(std::move(o));
  }
  {  // extensionsUsed lists the extension, no mesh carries it: nothing to report
    Output o("valid/used-without-field.glb");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron");
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    o.bytes = asGlb(a);
    o.meshes = 1;
    out.push_back(std::move(o));
  }
  {  // the payload's META has no vff.source.geometryHash: the extension's alone is checked
    Output o("valid/meta-without-geometry-hash.glb");
    const Field nohash = bakeField(f.tetra, "tetrahedron", MetaHash::kNone);
    Asset a = oneTetra(f, nohash.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", nohash.bytes, nohash.geometry, f.tetraField.geometry,
                                  nohash.tolerance(), node0));
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace vff::gltf_gen

int main(int argc, char** argv) {
  using namespace vff::gltf_gen;
  if (argc != 2) die("usage: vff-gltf-gen OUTDIR");
  const fs::path out = argv[1];
  std::error_code ec;
  fs::remove_all(out / "valid", ec);
  fs::remove_all(out / "invalid", ec);
  const Fields fields;
  std::vector<Output> all = validAssets(fields);
  for (Output& o : invalidAssets(fields)) all.push_back(std::move(o));
  json assets = json::object(), files = json::object();
  for (const Output& o : all) {
    writeFile(out / o.file, o.bytes);
    files[o.file] = {{"bytes", o.bytes.size()}, {"xxh3", xxh3(o.bytes)}, {"zstd", o.zstd}};
    for (const auto& [name, bytes] : o.beside) {
      writeFile(out / name, bytes);
      files[name] = {{"bytes", bytes.size()}, {"xxh3", xxh3(bytes)}, {"zstd", false}};
    }
    json problems = json::array();
    bool error = false;
    for (const Problem& p : o.problems) {
      problems.push_back(problemJson(p));
      error = error || std::string(p.severity) == "error";
    }
    assets[o.file] = {{"hasError", error}, {"problems", problems}, {"fields", o.fields}};
    // A file-level problem (14001-14003) ends the check: how far a reader counted meshes is its own.
    const bool fileLevel = !o.problems.empty() && o.problems.front().rule <= 14003;
    if (o.meshes >= 0 && !fileLevel) assets[o.file]["meshes"] = o.meshes;
  }
  const json manifest = {{"generator", "vff-gltf-gen"},
                         {"extension", kExt},
                         {"zstdVersion", ZSTD_versionString()},
                         {"assets", assets},
                         {"files", files}};
  std::ofstream(out / "manifest.json") << manifestText(manifest);
  return 0;
}
