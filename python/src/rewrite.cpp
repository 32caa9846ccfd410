// rewrite.cpp - vff.compress, vff.decompress and vff.convert: rewriting a .vff with other block
// codecs or packed-layout limits through libvff's Writer. The maps, the field description and the
// metadata are kept; sections this library does not know are not copied (vff-compress and
// vff-convert copy the copy-safe ones), and other formats (OpenEXR, OpenVDB) are the CLI's only.
#include <pybind11/stl.h>

#include "bindings.h"
#include "errors.h"
#include "vff/spelling.h"

namespace py = pybind11;

namespace vff::python {

namespace {

std::shared_ptr<PyFile> rewrite(const std::string& src, const std::string& dst, WriteOptions wo, bool keepLayout) {
  auto in = openFile(src, "all");
  const File& f = in->file;
  if (f.info().roCompatFeatures)
    raise(makeError(Code::kUnsupported, src + " has roCompatFeatures this library does not know: it must not be rewritten"));
  const LayoutDesc& l = f.layout();
  if (keepLayout) wo.layout = LayoutLimits{l.target, l.maxTextureSize, l.maxLayers, l.gutter};
  wo.metadataJson = std::string(f.metadata());
  Status st;
  {
    py::gil_scoped_release unlocked;
    auto w = Writer::create(dst, f.field(), wo);
    if (!w) {
      st = std::move(w).error();
    } else {
      for (Plane p : {Plane::kDistance, Plane::kNormal}) {
        if (!f.plane(p).present) continue;
        for (uint32_t b = 0; b < f.plane(p).blocks.size() && st; ++b) {
          auto bytes = f.blockData(p, b);
          st = bytes ? w->writeMaps(p, *bytes) : Status(std::move(bytes).error());
        }
      }
      if (st) st = w->finish();
    }
  }
  check(st);
  return openFile(dst, "all");
}

}  // namespace

void bindRewrite(py::module_& m) {
  m.def("compress", [](const std::string& src, const std::string& dst, int level, const std::string& filter, uint32_t mapsPerBlock) {
        WriteOptions wo;
        wo.codec = Codec::kZstd;
        if (level < 1 || level > 22) throw py::value_error("level: expected 1..22");
        wo.zstdLevel = level;
        wo.mapsPerBlock = mapsPerBlock;
        auto probe = openFile(src, "lazy");
        const DistanceEncoding e = probe->file.field().distanceEncoding;
        const bool eightBit = e == DistanceEncoding::kUnorm8Diameter || e == DistanceEncoding::kUnorm8Chord;
        if (filter == "auto") wo.filter = eightBit ? Filter::kHitsMed : Filter::kNone;
        else if (filter == "hits-med") wo.filter = Filter::kHitsMed;
        else if (filter == "none") wo.filter = Filter::kNone;
        else throw py::value_error("filter: expected \"auto\", \"hits-med\" or \"none\", got \"" + filter + "\"");
        return rewrite(src, dst, wo, true);
      },
      py::arg("src"), py::arg("dst"), py::arg("level") = 19, py::arg("filter") = "auto", py::arg("maps_per_block") = 0u,
      R"doc(
Lossless compression, as vff-compress: every block as a zstd frame at `level`, with the hits-med
filter where it makes the block smaller (filter "auto": 8-bit distance encodings). Writes `dst`
atomically and returns it opened. Unknown sections are not copied; vff-compress --bc4 (lossy) is
the CLI's only.)doc");
  m.def("decompress", [](const std::string& src, const std::string& dst) { return rewrite(src, dst, WriteOptions{}, true); },
        py::arg("src"), py::arg("dst"), "Rewrites `src` with stored blocks (zero-copy maps), as vff-compress --decompress.");
  m.def("convert", [](const std::string& src, const std::string& dst, const std::string& codec, int zstdLevel,
                      uint32_t mapsPerBlock, const py::object& target, const py::object& maxTextureSize,
                      const py::object& maxLayers, const py::object& gutter) {
        auto probe = openFile(src, "lazy");
        const LayoutDesc& l = probe->file.layout();
        WriteOptions wo;
        wo.codec = vff::kCodecs.parse(codec).value_or(Codec::kStored);
        if (!vff::kCodecs.parse(codec)) throw py::value_error("codec: expected \"stored\" or \"zstd\", got \"" + codec + "\"");
        wo.zstdLevel = zstdLevel;
        wo.mapsPerBlock = mapsPerBlock;
        wo.layout = LayoutLimits{l.target, l.maxTextureSize, l.maxLayers, l.gutter};
        if (!target.is_none()) {
          auto t = vff::kLayoutTargets.parse(target.cast<std::string>());
          if (!t) throw py::value_error("target: expected \"2d-array\" or \"3d\"");
          wo.layout.target = *t;
        }
        if (!maxTextureSize.is_none()) wo.layout.maxTextureSize = maxTextureSize.cast<uint32_t>();
        if (!maxLayers.is_none()) wo.layout.maxLayers = maxLayers.cast<uint32_t>();
        if (!gutter.is_none()) wo.layout.gutter = gutter.cast<uint32_t>();
        return rewrite(src, dst, wo, false);
      },
      py::arg("src"), py::arg("dst"), py::kw_only(), py::arg("codec") = "stored", py::arg("zstd_level") = 19,
      py::arg("maps_per_block") = 0u, py::arg("target") = py::none(), py::arg("max_texture_size") = py::none(),
      py::arg("max_layers") = py::none(), py::arg("gutter") = py::none(), R"doc(
Repacks a .vff for other GPU limits or block codecs, as vff-convert --to vff (the layout options
not given keep the input's). Re-encoding, level of detail, OpenEXR and OpenVDB are vff-convert's
only. Returns `dst` opened.)doc");
}

}  // namespace vff::python
