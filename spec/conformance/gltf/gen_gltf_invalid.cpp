// gen_gltf_invalid.cpp - the assets that break a rule of the extension, one function per group of
// rules in the order a reader checks them: the file (14001-14003), the extension's value and its
// source (14004-14005), the bufferView (14006), the uri and the mimeType (14007-14008), the payload
// (14009), the mesh the field is on (14010-14011).
#include <cctype>
#include <functional>

#include "gen_gltf.h"

namespace vff::gltf_gen {
namespace {

using Edit = std::function<void(Asset&)>;

// An asset of one tetrahedron whose extension value an edit changes, breaking a rule at a member.
// The payload is never read: placeholder().
class Editor {
 public:
  explicit Editor(const Fields& f) : f_(f), ph_(placeholder()) {}

  Output operator()(const std::string& file, int rule, const std::string& member, const Edit& edit,
                    bool glb = true, bool ioError = false) const {
    Output o("invalid/" + file);
    Asset a = oneTetra(f_, ph_);
    edit(a);
    o.bytes = glb ? asGlb(a) : asGltf(a);
    o.meshes = 1;
    o.problems.push_back({rule, "error", extPath(0, member), ioError});
    if (rule >= 14004) o.fields.push_back(invalidField(0));
    return o;
  }

 private:
  const Fields& f_;
  std::vector<uint8_t> ph_;
};

Edit setExt(const std::string& key, json v) {
  return [key, v](Asset& a) { a.ext(0)[key] = v; };
}

Edit eraseExt(const std::string& key) {
  return [key](Asset& a) { a.ext(0).erase(key); };
}

// 14001: not a glTF 2.0 asset; 14002, 14003: extensionsRequired, extensionsUsed.
void fileLevelAssets(const Fields& f, std::vector<Output>& out) {
  const std::vector<uint8_t> ph = placeholder();
  {
    Output o("invalid/14001-glb-magic.glb");
    Asset a = oneTetra(f, ph);
    o.bytes = asGlb(a);
    o.bytes[0] = 'G';
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-glb-length.glb");
    Asset a = oneTetra(f, ph);
    o.bytes = asGlb(a);
    o.bytes.resize(o.bytes.size() - 64);  // the header's length says 64 bytes more
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-json-syntax.gltf");
    Asset a = oneTetra(f, ph);
    o.bytes = asGltf(a);
    o.bytes.resize(o.bytes.size() / 2);
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-asset-version.gltf");
    Asset a = oneTetra(f, ph);
    a.j["asset"]["version"] = "1.0";
    o.bytes = asGltf(a);
    o.problems.push_back({14001, "error", "/asset/version"});
    out.push_back(std::move(o));
  }
  {  // two problems: 14001 is checked first
    Output o("invalid/14001-asset-version-before-required.gltf");
    Asset a = oneTetra(f, ph);
    a.j["asset"]["version"] = "3.0";
    a.j["extensionsRequired"] = json::array({kExt});
    o.bytes = asGltf(a);
    o.problems.push_back({14001, "error", "/asset/version"});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14002-extension-required.glb");
    Asset a = oneTetra(f, ph);
    a.j["extensionsRequired"] = json::array({kExt});
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14002, "error", "/extensionsRequired"});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14003-extension-not-used.glb");
    Asset a = oneTetra(f, ph);
    a.j.erase("extensionsUsed");
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14003, "error", "/extensionsUsed"});
    out.push_back(std::move(o));
  }
  {  // two problems: 14003 (file level) ends the check before the extension's value is read
    Output o("invalid/14003-not-used-before-extension-value.glb");
    Asset a = oneTetra(f, ph);
    a.j.erase("extensionsUsed");
    a.ext(0)["geometryHash"] = "not a hash";
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14003, "error", "/extensionsUsed"});
    out.push_back(std::move(o));
  }
}

// 14004: the extension's value; 14005: both or neither source.
void extensionValueAssets(const Fields& f, std::vector<Output>& out) {
  const Editor edited(f);
  out.push_back(edited("14004-not-an-object.glb", 14004, "", [](Asset& a) { a.ext(0) = json::array({1, 2}); }));
  out.push_back(edited("14004-buffer-view-type.glb", 14004, "bufferView", setExt("bufferView", "0")));
  out.push_back(edited("14004-buffer-view-negative.glb", 14004, "bufferView", setExt("bufferView", -1)));
  out.push_back(edited("14004-uri-type.glb", 14004, "uri", [](Asset& a) {
    a.ext(0).erase("bufferView");
    a.ext(0)["uri"] = 7;
  }));
  out.push_back(edited("14004-mime-type-type.glb", 14004, "mimeType", setExt("mimeType", json::array({kMediaType}))));
  out.push_back(edited("14004-geometry-hash-type.glb", 14004, "geometryHash", setExt("geometryHash", 1234)));
  out.push_back(edited("14004-geometry-hash-uppercase.glb", 14004, "geometryHash", [&](Asset& a) {
    std::string h = f.tetraField.geometry.hash;
    for (char& c : h) c = char(std::toupper(static_cast<unsigned char>(c)));
    if (h == f.tetraField.geometry.hash) h[0] = 'A';  // all digits: make it upper case anyway
    a.ext(0)["geometryHash"] = h;
  }));
  out.push_back(edited("14004-geometry-hash-length.glb", 14004, "geometryHash",
                       setExt("geometryHash", f.tetraField.geometry.hash.substr(0, 15))));
  out.push_back(edited("14004-geometry-hash-missing.glb", 14004, "geometryHash", eraseExt("geometryHash")));
  out.push_back(edited("14004-min-type.glb", 14004, "min", setExt("min", "0 0 0")));
  out.push_back(edited("14004-min-two-numbers.glb", 14004, "min", setExt("min", json::array({0.0, 0.0}))));
  out.push_back(edited("14004-max-not-a-number.glb", 14004, "max", setExt("max", json::array({1.0, "1", 1.0}))));
  out.push_back(edited("14004-min-above-max.glb", 14004, "min", [&](Asset& a) {
    std::array<float, 3> lo = f.tetraField.geometry.min;
    lo[1] = f.tetraField.geometry.max[1] + 1.0f;
    a.ext(0)["min"] = vec3(lo);
  }));
  out.push_back(edited("14004-max-missing.glb", 14004, "max", eraseExt("max")));
  {  // two problems: the value (14004) is checked before the bufferView (14006)
    Output o = edited("14004-extension-value-before-buffer-view.glb", 14004, "geometryHash", [](Asset& a) {
      a.ext(0)["geometryHash"] = "0123456789abcdeg";
      a.ext(0)["bufferView"] = 99;
    });
    out.push_back(std::move(o));
  }

  // 14005: both or neither source
  out.push_back(edited("14005-both-sources.glb", 14005, "", setExt("uri", "tetrahedron.vff")));
  out.push_back(edited("14005-no-source.glb", 14005, "", eraseExt("bufferView")));
}

// 14006: the bufferView.
void bufferViewAssets(const Fields& f, std::vector<Output>& out) {
  const std::vector<uint8_t> ph = placeholder();
  const Editor edited(f);
  out.push_back(edited("14006-buffer-view-index.glb", 14006, "bufferView", setExt("bufferView", 99)));
  out.push_back(edited("14006-buffer-view-stride.glb", 14006, "bufferView",
                       [](Asset& a) { a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())]["byteStride"] = 4; }));
  out.push_back(edited("14006-buffer-view-out-of-range.glb", 14006, "bufferView", [](Asset& a) {
    json& v = a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())];
    v["byteLength"] = v["byteLength"].get<size_t>() + 4096;  // past the end of the buffer
  }));
  {  // a .glb whose buffer 0 has no binary chunk; the mesh's data is in a data: URI buffer
    Output o("invalid/14006-no-binary-chunk.glb");
    Asset a = oneTetra(f, ph);
    a.finishBuffer(false);
    json& payload = a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())];
    a.j["buffers"].insert(a.j["buffers"].begin(), json{{"byteLength", 256}});  // the GLB-stored buffer
    for (json& v : a.j["bufferViews"]) v["buffer"] = 1;
    payload = {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 128}};
    o.bytes = glbBytes(a.j.dump(), nullptr);
    o.meshes = 1;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // a .gltf whose payload's buffer is a file that does not exist
    Output o("invalid/14006-buffer-uri-missing.gltf");
    Asset a = oneTetra(f, ph);
    a.finishBuffer(false);
    a.j["buffers"].push_back({{"byteLength", 128}, {"uri", "missing.bin"}});
    a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())] = {{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 128}};
    const std::string text = a.j.dump(1) + "\n";
    o.bytes.assign(text.begin(), text.end());
    o.meshes = 1;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
}

// 14007: the uri (a .gltf each; the field's bufferView replaced by the uri); 14008: the mimeType.
void uriAndMimeTypeAssets(const Fields& f, std::vector<Output>& out) {
  const Editor edited(f);
  auto uri = [&](const std::string& file, const std::string& u, bool ioError = false) {
    return edited(
        file, 14007, "uri",
        [u](Asset& a) {
          a.ext(0).erase("bufferView");
          a.ext(0).erase("mimeType");
          a.ext(0)["uri"] = u;
        },
        false, ioError);
  };
  out.push_back(uri("14007-uri-absolute-path.gltf", "/fields/tetrahedron.vff"));
  out.push_back(uri("14007-uri-scheme.gltf", "https://example.com/tetrahedron.vff"));
  out.push_back(uri("14007-uri-network-path.gltf", "//example.com/tetrahedron.vff"));
  out.push_back(uri("14007-uri-query.gltf", "tetrahedron.vff?v=1"));
  out.push_back(uri("14007-uri-backslash.gltf", "fields\\tetrahedron.vff"));
  out.push_back(uri("14007-uri-bad-percent.gltf", "tetra%G0hedron.vff"));
  out.push_back(uri("14007-uri-decoded-nul.gltf", "tetrahedron%00.vff"));
  out.push_back(uri("14007-data-uri-not-base64.gltf", "data:application/vnd.vff,VFF"));
  out.push_back(uri("14007-uri-missing-file.gltf", "14007-uri-missing-file.mesh0.vff", true));


  // 14008: the mimeType
  out.push_back(edited("14008-mime-type-missing.glb", 14008, "", eraseExt("mimeType")));
  out.push_back(edited("14008-mime-type-wrong.glb", 14008, "mimeType", setExt("mimeType", "application/octet-stream")));
}

// 14009: the payload.
void payloadAssets(const Fields& f, std::vector<Output>& out) {
  {
    const std::vector<uint8_t> head(f.tetraField.bytes.begin(), f.tetraField.bytes.begin() + 64);
    std::vector<uint8_t> bad = head;
    bad[0] = 'X';
    Output o("invalid/14009-payload-magic.glb");
    Asset a = oneTetra(f, bad);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14009, "error", extPath(0), false, vffErrorCodes(bad)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14009-payload-checksum.glb");
    const std::vector<uint8_t> corrupt = corruptBlock(f.tetraField, f.tetra);
    Asset a = oneTetra(f, corrupt);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14009, "error", extPath(0), false, vffErrorCodes(corrupt)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14009-payload-partial.glb");
    const Field partial = bakePartial(f.tetra, "tetrahedron");
    Asset a = oneTetra(f, partial.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.zstd = true;
    o.problems.push_back({14009, "error", extPath(0)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
}

// 14010, 14011 and a second mesh checked after an error on the first. They share tetrahedron.vff, a
// valid field, beside them.
void meshAssets(const Fields& f, std::vector<Output>& out) {
  {  // the extension declares another geometryHash than the payload's META
    Output o("invalid/14010-hash-conflict.gltf");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron");
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    a.attachUri(m, "tetrahedron.vff", f.tetraField.geometry);
    a.ext(m)["geometryHash"] = "0123456789abcdef";
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 1;
    o.problems.push_back({14010, "error", extPath(0, "geometryHash")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // the mesh is drawn as lines: no triangle to match the field with
    Output o("invalid/14011-mesh-lines-only.gltf");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron", 1);
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    a.attachUri(m, "tetrahedron.vff", f.tetraField.geometry);
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 1;
    o.problems.push_back({14011, "error", "/meshes/0"});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // mesh 0 has an error, mesh 1 is still checked and used
    Output o("invalid/14006-first-mesh-second-valid.gltf");
    Asset a;
    const int t = a.mesh(f.tetra, "tetrahedron"), u = a.mesh(f.tetra, "tetrahedron-too");
    a.node(t, "tetrahedron");
    a.node(u, "tetrahedron-too");
    a.scene();
    a.used();
    a.attach(t, 99, f.tetraField.geometry);
    a.attachUri(u, "tetrahedron.vff", f.tetraField.geometry);
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 2;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    o.fields.push_back(validField(1, "tetrahedron-too", "uri", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), {{1, true}}));
    out.push_back(std::move(o));
  }
}

}  // namespace

std::vector<Output> invalidAssets(const Fields& f) {
  std::vector<Output> out;
  fileLevelAssets(f, out);
  extensionValueAssets(f, out);
  bufferViewAssets(f, out);
  uriAndMimeTypeAssets(f, out);
  payloadAssets(f, out);
  meshAssets(f, out);
  return out;
}

}  // namespace vff::gltf_gen
