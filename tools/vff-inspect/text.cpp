// text.cpp - the human-readable rendering of a vff-inspect report document.
#include <algorithm>
#include <cinttypes>
#include <string>
#include <vector>

#include "cli.h"
#include "inspect.h"

namespace vff::inspect {

using nlohmann::json;

namespace {

std::string str(const json& j) {
  if (j.is_string()) return j.get<std::string>();
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

uint64_t u64(const json& j) {
  return j.get<uint64_t>();
}

std::string join(const json& names, const char* none) {
  if (names.empty()) return none;
  std::string s;
  for (const json& n : names) s += (s.empty() ? "" : ", ") + str(n);
  return s;
}

std::string num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// %g-style: 1.5, -1, 2 (for sphere coordinates, which are floats).
std::string gnum(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string checksumStatusText(const json& s) {
  const std::string v = str(s);
  if (v == "verified") return "verified OK";
  if (v == "failed") return "FAILED";
  return "not verified";
}

void printPlane(std::FILE* out, const char* name, const json& p) {
  if (p.is_null()) {
    std::fprintf(out, "  %-8s absent\n", name);
    return;
  }
  std::fprintf(out, "  %-8s %s raw, %" PRIu64 " bytes per map\n", name, cli::formatBytes(u64(p["rawBytes"])).c_str(),
               u64(p["mapBytes"]));
  std::fprintf(out, "           stored %s, compression ratio %s (raw/stored)\n",
               cli::formatBytes(u64(p["storedBytes"])).c_str(), num(p["compressionRatio"].get<double>(), 3).c_str());
  std::string codecs;
  for (const auto& [codec, count] : p["codecs"].items())
    codecs += (codecs.empty() ? "" : ", ") + codec + " " + std::to_string(count.get<uint64_t>());
  std::string filters;
  for (const auto& [filter, count] : p["filters"].items())
    filters += (filters.empty() ? "" : ", ") + filter + " " + std::to_string(count.get<uint64_t>());
  std::fprintf(out,
               "           %s, %" PRIu64 " maps per block (last block %" PRIu64 "), codecs: %s; filters: %s\n",
               cli::count(u64(p["blockCount"]), "block").c_str(), u64(p["mapsPerBlock"]), u64(p["lastBlockMaps"]),
               codecs.c_str(), filters.c_str());
  // Per-block stored sizes: every one for a few blocks, else the spread (JSON lists them all).
  std::vector<uint64_t> sizes;
  for (const auto& b : p["blocks"]) sizes.push_back(u64(b["storedBytes"]));
  if (!sizes.empty() && sizes.size() <= 32) {
    std::string list;
    for (size_t i = 0; i < sizes.size(); ++i)
      list += (i == 0 ? "" : i % 8 == 0 ? ",\n                                " : ", ") + std::to_string(sizes[i]);
    std::fprintf(out, "           block stored bytes: %s\n", list.c_str());
  } else if (!sizes.empty()) {
    std::sort(sizes.begin(), sizes.end());
    std::fprintf(out,
                 "           block stored bytes: min %" PRIu64 ", median %" PRIu64 ", max %" PRIu64
                 " (--format json lists every block)\n",
                 sizes.front(), sizes[sizes.size() / 2], sizes.back());
  }
  std::fprintf(out, "           slice %s\n", cli::formatBytes(u64(p["sliceBytes"])).c_str());
}

void printSummary(const json& doc, std::FILE* out) {
  const json& fmt = doc["format"];
  std::fprintf(out, "format:      vff %s, %s\n", str(fmt["version"]).c_str(),
               cli::formatBytes(u64(fmt["fileSize"])).c_str());
  std::fprintf(
      out, "features:    incompat %s (%s), roCompat %s (%s)\n", cli::hex(u64(fmt["incompatFeatures"]["value"])).c_str(),
      join(fmt["incompatFeatures"]["names"], "none").c_str(), cli::hex(u64(fmt["roCompatFeatures"]["value"])).c_str(),
      join(fmt["roCompatFeatures"]["names"], "none").c_str());
  std::fprintf(out, "header:      checksum %s %s, %s\n", str(fmt["checksumAlgorithm"]).c_str(),
               str(fmt["headerChecksum"]).c_str(), checksumStatusText(fmt["headerChecksumStatus"]).c_str());

  std::fprintf(out, "\nsections (%zu):\n", doc["sections"].size());
  std::fprintf(out, "  %-4s  %-19s  %10s  %12s  %12s  %-6s  %3s  %-18s  %s\n", "tag", "flags", "offset", "stored",
               "raw", "codec", "ver", "checksum", "status");
  for (const json& s : doc["sections"]) {
    std::string flags = cli::hex(u64(s["flags"]));
    if (!s["flagNames"].empty()) flags += " " + join(s["flagNames"], "");
    std::fprintf(out, "  %-4s  %-19s  %10" PRIu64 "  %12" PRIu64 "  %12" PRIu64 "  %-6s  %3" PRIu64 "  %-18s  %s%s\n",
                 str(s["tag"]).c_str(), flags.c_str(), u64(s["offset"]), u64(s["storedSize"]), u64(s["rawSize"]),
                 str(s["codec"]).c_str(), u64(s["sectionVersion"]), str(s["checksum"]).c_str(),
                 checksumStatusText(s["checksumStatus"]).c_str(), s["known"].get<bool>() ? "" : " (unknown tag)");
  }

  const json& f = doc["field"];
  const json& c = f["sphere"]["center"];
  std::fprintf(out, "\nfield:\n");
  std::fprintf(out, "  sphere:     centre (%s, %s, %s), radius %s\n", gnum(c[0].get<double>()).c_str(),
               gnum(c[1].get<double>()).c_str(), gnum(c[2].get<double>()).c_str(),
               gnum(f["sphere"]["radius"].get<double>()).c_str());
  std::fprintf(out, "  positions:  %s, param %" PRIu64 ", %" PRIu64 " maps\n", str(f["positionScheme"]).c_str(),
               u64(f["positionParam"]), u64(f["mapCount"]));
  std::fprintf(out, "  directions: %s, map resolution %" PRIu64 " (%" PRIu64 "x%" PRIu64 " texels)\n",
               str(f["directionScheme"]).c_str(), u64(f["mapResolution"]), u64(f["mapResolution"]),
               u64(f["mapResolution"]));
  std::fprintf(out, "  frame:      %s\n", str(f["frame"]).c_str());
  std::fprintf(out, "  distance:   %s, miss code %" PRIu64 "\n", str(f["distanceEncoding"]).c_str(),
               u64(f["missCode"]));
  std::fprintf(out, "  normals:    %s\n", str(f["normalEncoding"]).c_str());
  // A partial result of vff-bake --map-range (spec/partial.md): say so beside the field it is part of.
  if (doc.contains("partial") && doc["partial"].is_object()) {
    const json& p = doc["partial"];
    if (p["mapBegin"].is_number_unsigned())
      std::fprintf(out,
                   "  partial:    maps %" PRIu64 ":%" PRIu64 " of %" PRIu64
                   " only (vff-bake --map-range); the others hold misses until vff-bake --merge\n",
                   u64(p["mapBegin"]), u64(p["mapEnd"]), u64(p["mapCount"]));
    else
      std::fprintf(out, "  partial:    a partial result whose \"vff.partial\" gives no usable map range\n");
  }

  std::fprintf(out, "\npayload:\n");
  printPlane(out, "distance", doc["planes"]["distance"]);
  printPlane(out, "normal", doc["planes"]["normal"]);

  const json& l = doc["layout"];
  std::fprintf(out, "\nlayout:\n");
  std::fprintf(out, "  target:    %s\n", str(l["target"]).c_str());
  std::fprintf(out,
               "  tiles:     %" PRIu64 " texels (gutter %" PRIu64 "), %" PRIu64 " per row x %" PRIu64
               " per column = %" PRIu64 " per slice\n",
               u64(l["tileSize"]), u64(l["gutter"]), u64(l["tilesPerRow"]), u64(l["tilesPerColumn"]),
               u64(l["tilesPerSlice"]));
  std::fprintf(out, "  slices:    %" PRIu64 " x %" PRIu64 " texels, %" PRIu64 " slice%s\n", u64(l["sliceWidth"]),
               u64(l["sliceHeight"]), u64(l["sliceCount"]), u64(l["sliceCount"]) == 1 ? "" : "s");
  std::fprintf(out, "  limits:    max texture size %" PRIu64 ", max layers %" PRIu64 "\n", u64(l["maxTextureSize"]),
               u64(l["maxLayers"]));

  const json& st = doc["statistics"];
  std::fprintf(out, "\nhits:        %" PRIu64 " of %" PRIu64 " texels, hit ratio %s (%s %%)\n", u64(st["hits"]),
               u64(st["texels"]), num(st["hitRatio"].get<double>(), 6).c_str(),
               num(100 * st["hitRatio"].get<double>(), 3).c_str());
  if (doc.contains("partial") && doc["partial"].is_object() && doc["partial"]["mapBegin"].is_number_unsigned())
    std::fprintf(out, "             (maps %" PRIu64 ":%" PRIu64 " only: the others are fillers, not the field's)\n",
                 u64(doc["partial"]["mapBegin"]), u64(doc["partial"]["mapEnd"]));
  if (u64(st["unreadableBlocks"]) != 0)
    std::fprintf(out, "             (%" PRIu64 " unreadable blocks left out)\n", u64(st["unreadableBlocks"]));

  const json& h = doc["histogram"];
  if (h["hitsOnly"].get<bool>()) {
    std::fprintf(out, "\nhistogram:   hits only (bit1 stores no distance): %" PRIu64 " hits, %" PRIu64 " misses\n",
                 u64(h["hits"]), u64(h["misses"]));
  } else {
    const double diameter = h["range"][1].get<double>();
    std::fprintf(out, "\ndistance histogram (%" PRIu64 " bins over [0, 2R] = [0, %s]):\n", u64(h["binCount"]),
                 gnum(diameter).c_str());
    std::fprintf(out, "  %-22s  %-15s  %12s  %8s\n", "distance", "of 2R", "hits", "share");
    for (const json& b : h["bins"]) {
      const std::string range = "[" + num(b["lower"].get<double>(), 4) + ", " + num(b["upper"].get<double>(), 4) + ")";
      const std::string frac =
          num(b["lowerFraction"].get<double>(), 3) + "-" + num(b["upperFraction"].get<double>(), 3);
      const double share = b["share"].get<double>();
      std::string bar(static_cast<size_t>(share * 40 + 0.5), '#');
      std::fprintf(out, "  %-22s  %-15s  %12" PRIu64 "  %7s%%%s%s\n", range.c_str(), frac.c_str(), u64(b["count"]),
                   num(100 * share, 2).c_str(), bar.empty() ? "" : "  ", bar.c_str());
    }
  }

  if (const json& r = doc["refinement"]; r.is_object())
    std::fprintf(out, "\nrefinement:  %" PRIu64 " unsure texels (%s%%), margin %s R; exact step: %" PRIu64
                      " vertices, %" PRIu64 " triangles\n",
                 u64(r["unsureTexels"]), num(100 * r["unsureShare"].get<double>(), 2).c_str(),
                 num(r["margin"].get<double>(), 4).c_str(), u64(r["vertices"]), u64(r["triangles"]));
  std::fprintf(out, "\nmetadata:");
  if (doc["metadata"].is_null())
    std::fprintf(out, " none\n");
  else
    std::fprintf(out, "\n%s\n", doc["metadata"].dump(2, ' ', false, json::error_handler_t::replace).c_str());
}

void printValidation(const json& v, std::FILE* out) {
  const uint64_t errors = u64(v["errors"]), warnings = u64(v["warnings"]);
  std::fprintf(out, "validation:  %s, %" PRIu64 " error%s, %" PRIu64 " warning%s\n",
               v["valid"].get<bool>() ? "valid" : "INVALID", errors, errors == 1 ? "" : "s", warnings,
               warnings == 1 ? "" : "s");
  for (const json& i : v["issues"]) {
    std::string place;
    if (!i["section"].is_null()) place += " [" + str(i["section"]) + "]";
    if (!i["offset"].is_null()) place += " @" + cli::hex(u64(i["offset"]));
    std::fprintf(out, "  %-7s %" PRIu64 " %s%s: %s\n", str(i["severity"]).c_str(), u64(i["id"]), str(i["name"]).c_str(),
                 place.c_str(), str(i["message"]).c_str());
  }
}

}  // namespace

void printText(const json& doc, std::FILE* out) {
  std::fprintf(out, "file:        %s\n", str(doc["file"]).c_str());
  if (doc.contains("format")) printSummary(doc, out);
  if (doc.contains("preview")) {
    const json& p = doc["preview"];
    std::fprintf(
        out,
        "\npreview:     %s, %" PRIu64 " maps in %" PRIu64 " x %" PRIu64 " tiles, %" PRIu64 " x %" PRIu64 " pixels\n",
        str(p["path"]).c_str(), u64(p["maps"]), u64(p["columns"]), u64(p["rows"]), u64(p["width"]), u64(p["height"]));
  }
  if (doc.contains("validation")) {
    if (doc.contains("format")) std::fprintf(out, "\n");
    printValidation(doc["validation"], out);
  }
}

}  // namespace vff::inspect
