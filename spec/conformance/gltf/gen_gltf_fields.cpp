// gen_gltf_fields.cpp - the meshes of the glTF extension's conformance assets and their fields:
// tiny bakes with the baker and libvff's writer (stored blocks; the partial result with vff-bake's
// own partial options, zstd blocks), so the bytes depend only on libvff, the baker and libzstd.
#include <algorithm>
#include <limits>

#include "bake_job.h"
#include "gen_gltf.h"
#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/validate.h"
#include "vff/writer.h"

namespace vff::gltf_gen {
namespace {

bake::BakeOptions bakeOptions() {
  bake::BakeOptions bo;
  bo.positionParam = 2;  // the smallest octa-hemi2 field with hits and misses: small assets
  bo.mapResolution = 4;
  bo.threads = 1;
  return bo;
}

// META as vff-bake writes it for a mesh, with a fixed generator version so that the bytes do not
// change with the library's version.
json metadata(const std::string& name, const bake::Mesh& mesh, MetaHash hash) {
  json source = {{"name", name},
                 {"format", "gltf"},
                 {"xxh3", hex64(bake::meshHash(mesh))},
                 {"vertices", mesh.vertexCount()},
                 {"triangles", mesh.triangleCount()}};
  if (hash == MetaHash::kSame) source["geometryHash"] = hex64(bake::geometryHash(mesh));
  return {{"vff.generator", "vff-gltf-gen"},
          {"vff.generatorVersion", "1"},
          {"vff.source", source},
          {"vff.bake",
           {{"rayOrigin", "texel centre"}, {"sphere", "minimal-enclosing"}, {"twoSided", true}, {"normals", "none"}}}};
}

struct Baked {
  FieldDesc field;
  bake::BakedField maps;
  bake::Mesh mesh;
};

Baked bakeMesh(bake::Mesh mesh, const bake::BakeOptions& bo) {
  if (Status s = bake::checkMesh(&mesh, "mesh"); !s) die(s.error().toString());
  auto desc = bake::describeBake(mesh, bo);
  if (!desc) die(desc.error().toString());
  auto scene = bake::Scene::create(mesh, 1);
  if (!scene) die(scene.error().toString());
  auto maps = bake::bakeField(*scene, bo);
  if (!maps) die(maps.error().toString());
  return {*desc, std::move(*maps), std::move(mesh)};
}

}  // namespace

// A regular tetrahedron off the origin: 4 vertices, 4 triangles.
bake::Mesh tetrahedron() {
  bake::Mesh m;
  m.positions = {0.75f, 1.0f, 0.5f, 0.75f, 0.0f, -0.5f, -0.25f, 1.0f, -0.5f, -0.25f, 0.0f, 0.5f};
  m.indices = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  return m;
}

bake::Mesh box() {
  bake::Mesh m = bake::makeBox(0.5f, 0.25f, 0.75f);
  m.normals.clear();  // POSITION only: the assets carry no other attribute
  return m;
}

// The box with every vertex on its +x face moved by `dx`: the hash changes, one bound moves by dx.
bake::Mesh movedBox(float dx) {
  bake::Mesh m = box();
  float hi = -std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < m.positions.size(); i += 3) hi = std::max(hi, m.positions[i]);
  for (size_t i = 0; i < m.positions.size(); i += 3)
    if (m.positions[i] == hi) m.positions[i] += dx;
  return m;
}

Geometry geometryOf(bake::Mesh m) {
  if (Status s = bake::checkMesh(&m, "mesh"); !s) die(s.error().toString());
  Geometry g;
  g.hash = hex64(bake::geometryHash(m));
  g.min.fill(std::numeric_limits<float>::infinity());
  g.max.fill(-std::numeric_limits<float>::infinity());
  for (uint32_t v : m.indices)
    for (int c = 0; c < 3; ++c) {
      g.min[c] = std::min(g.min[c], m.positions[3 * v + c]);
      g.max[c] = std::max(g.max[c], m.positions[3 * v + c]);
    }
  return g;
}

Field bakeField(const bake::Mesh& mesh, const std::string& name, MetaHash hash) {
  Baked b = bakeMesh(mesh, bakeOptions());
  WriteOptions wo;
  wo.codec = Codec::kStored;
  wo.sync = false;
  wo.threads = 1;
  wo.metadataJson = metadata(name, b.mesh, hash).dump();
  auto bytes = writeMemory(b.field, b.maps.distance, {}, wo);
  if (!bytes) die(name + ": " + bytes.error().toString());
  return {std::move(*bytes), geometryOf(b.mesh), double(b.field.sphere.radius)};
}

// A partial result as `vff-bake --map-range 0:2` writes it: vff-bake's partial options and META,
// the maps outside the range misses.
Field bakePartial(const bake::Mesh& mesh, const std::string& name) {
  bake::BakeOptions bo = bakeOptions();
  bo.mapBegin = 0;
  bo.mapEnd = 2;
  Baked b = bakeMesh(mesh, bo);
  WriteOptions whole;
  whole.codec = Codec::kStored;
  whole.threads = 1;
  whole.metadataJson = metadata(name, b.mesh, MetaHash::kSame).dump();
  WriteOptions wo = bake_tool::partialWriteOptions(whole);
  wo.sync = false;
  wo.metadataJson = bake_tool::partialMetadata(whole.metadataJson, whole, {0, 2}, b.field.mapCount);
  auto w = Writer::createInMemory(b.field, wo);
  if (!w) die(name + ": " + w.error().toString());
  Status st = w->writeMaps(Plane::kDistance, b.maps.distance);
  const std::vector<uint8_t> miss = bake_tool::missMap(b.field);
  for (uint32_t k = 2; st && k < b.field.mapCount; ++k) st = w->writeMaps(Plane::kDistance, miss);
  if (!st) die(name + ": " + st.error().toString());
  auto bytes = w->finishToMemory();
  if (!bytes) die(name + ": " + bytes.error().toString());
  return {std::move(*bytes), geometryOf(b.mesh), double(b.field.sphere.radius)};
}

// The field with one byte of its first distance block changed: the checksums of the block (6009)
// and of the section holding it (4008) no longer match.
std::vector<uint8_t> corruptBlock(const Field& f, const bake::Mesh& mesh) {
  const Baked b = bakeMesh(mesh, bakeOptions());
  std::vector<uint8_t> bytes = f.bytes;
  const auto& d = b.maps.distance;
  auto at = std::search(bytes.begin(), bytes.end(), d.begin(), d.begin() + 64);
  if (at == bytes.end()) die("the first distance block is not in the file");
  at[5] ^= 0x01;
  const Report r = validate(bytes);
  if (r.valid() || !r.has(Code::kBlockChecksum)) die("the changed byte is not a block checksum error");
  return bytes;
}

// Bytes that are never read: the asset breaks a rule checked before the payload (14004-14008). A
// reader that validates the payload first reports 14009 instead and fails the vector.
std::vector<uint8_t> placeholder() {
  const std::string text = "not a .vff file, never read      ";
  return {text.begin(), text.begin() + 32};
}

}  // namespace vff::gltf_gen
