// manifest.cpp - a library's entries, from a manifest (spec/library.md) or from a folder and a glob.
#include <fnmatch.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "cli.h"
#include "library.h"

namespace fs = std::filesystem;

namespace vff::library {

namespace {

// The vff-bake options a manifest may set: those that shape the field's bytes (spec/library.md).
const std::set<std::string>& bakeOptionNames() {
  static const std::set<std::string> names = {
      "positions", "count",     "map-size", "directions",      "encoding",   "normals",
      "center",    "radius",    "allow-clipped-sphere", "codec", "zstd-level", "maps-per-block",
      "target",    "max-texture-size", "max-layers", "gutter", "scene",      "grid"};
  return names;
}

std::string numberText(const nlohmann::json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  char s[40];
  std::snprintf(s, sizeof s, "%.9g", v.get<double>());
  return s;
}

// Appends the options of the object `o` (a manifest's "defaults" or an entry's "options") to `args`
// as vff-bake spells them; a problem names `where`.
std::optional<std::string> appendOptions(const nlohmann::json& o, const std::string& where,
                                         std::vector<std::string>* args) {
  if (!o.is_object()) return where + ": must be an object of vff-bake options";
  for (const auto& [k, v] : o.items()) {
    if (!bakeOptionNames().count(k))
      return where + ": \"" + k + "\" is not a vff-bake option a library sets (spec/library.md lists them)";
    const std::string flag = "--" + k;
    if (v.is_boolean()) {
      if (k != "normals" && k != "allow-clipped-sphere") return where + "." + k + ": takes a value, not true/false";
      if (v.get<bool>()) args->push_back(flag);
    } else if (v.is_number()) {
      args->insert(args->end(), {flag, numberText(v)});
    } else if (v.is_string()) {
      args->insert(args->end(), {flag, v.get<std::string>()});
    } else if (v.is_array() && k == "center" && v.size() == 3 &&
               std::all_of(v.begin(), v.end(), [](const auto& x) { return x.is_number(); })) {
      args->push_back(flag);
      for (const auto& x : v) args->push_back(numberText(x));
    } else {
      return where + "." + k + ": unexpected value " + v.dump();
    }
  }
  return std::nullopt;
}

// OUT/{dir}{stem}.vff style names: the pattern's {dir} (the mesh's folder relative to the base, with
// a trailing slash, or nothing), {stem} (its name without extension), {name} (with it).
std::string expandPattern(const std::string& pattern, const fs::path& relative) {
  std::string dir = relative.parent_path().generic_string();
  if (!dir.empty()) dir += '/';
  const std::pair<const char*, std::string> vars[] = {
      {"{dir}", dir}, {"{stem}", relative.stem().string()}, {"{name}", relative.filename().string()}};
  std::string s = pattern;
  for (const auto& [var, value] : vars)
    for (size_t at; (at = s.find(var)) != std::string::npos;) s.replace(at, std::string(var).size(), value);
  return s;
}

}  // namespace

std::optional<std::string> readManifest(const std::string& path, const std::string& outDir,
                                        std::vector<Entry>* entries, int* rc) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  if (in) text << in.rdbuf();
  if (!in || in.bad()) {
    *rc = cli::kExitIo;
    return path + ": cannot be read";
  }
  return parseManifest(text.str(), path, outDir, entries, rc);
}

std::optional<std::string> parseManifest(std::string_view text, const std::string& path, const std::string& outDir,
                                         std::vector<Entry>* entries, int* rc) {
  *rc = cli::kExitInvalidFile;
  nlohmann::json m = nlohmann::json::parse(text, nullptr, false);
  if (m.is_discarded()) return path + ": not JSON";
  if (!m.is_object() || m.value("vffLibrary", 0) != 1)
    return path + ": not a vff library manifest (\"vffLibrary\": 1 is missing)";
  for (const auto& [k, v] : m.items())
    if (k != "vffLibrary" && k != "defaults" && k != "output" && k != "entries" && k != "shardMaps")
      return path + ": unknown field \"" + k + "\"";
  const fs::path base = fs::absolute(fs::path(path)).parent_path();
  const nlohmann::json defaults = m.contains("defaults") ? m["defaults"] : nlohmann::json::object();
  std::vector<std::string> checked;
  if (auto p = appendOptions(defaults, path + ": defaults", &checked)) return p;
  const std::string pattern = m.value("output", std::string("{dir}{stem}.vff"));
  const uint64_t shardDefault = m.value("shardMaps", uint64_t{0});
  if (!m.contains("entries") || !m["entries"].is_array()) return path + ": \"entries\" must be an array";
  std::set<std::string> outputs;
  size_t i = 0;
  for (const auto& j : m["entries"]) {
    const std::string where = path + ": entries[" + std::to_string(i++) + "]";
    if (!j.is_object() || !j.contains("mesh") || !j["mesh"].is_string()) return where + ": needs \"mesh\" (a path)";
    for (const auto& [k, v] : j.items())
      if (k != "mesh" && k != "options" && k != "output" && k != "shardMaps" && k != "split")
        return where + ": unknown field \"" + k + "\"";
    Entry e;
    e.name = j["mesh"].get<std::string>();
    const fs::path mesh = fs::path(e.name).is_absolute() ? fs::path(e.name) : base / e.name;
    e.mesh = mesh.lexically_normal().string();
    // The entry's options over the defaults, key by key.
    nlohmann::json options = defaults;
    if (j.contains("options")) {
      if (!j["options"].is_object()) return where + ".options: must be an object of vff-bake options";
      for (const auto& [k, v] : j["options"].items()) options[k] = v;
    }
    if (auto p = appendOptions(options, where + ".options", &e.args)) return p;
    if (j.contains("split")) {
      if (!j["split"].is_string() || (j["split"] != "mesh" && j["split"] != "node"))
        return where + ".split: must be \"mesh\" or \"node\" (vff-bake --split)";
      e.split = j["split"].get<std::string>();
      e.args.insert(e.args.end(), {"--split", e.split});
    }
    std::string rel = j.contains("output") ? j["output"].get<std::string>()
                                           : expandPattern(pattern, fs::path(e.name).is_absolute()
                                                                        ? fs::path(e.name).filename()
                                                                        : fs::path(e.name));
    // A split entry's output is its scene description: the pattern's ".vff" becomes ".vffscene.json".
    if (!e.split.empty() && !j.contains("output") && rel.size() > 4 && rel.compare(rel.size() - 4, 4, ".vff") == 0)
      rel = rel.substr(0, rel.size() - 4) + ".vffscene.json";
    if (rel.empty() || fs::path(rel).is_absolute() || rel.find("..") != std::string::npos)
      return where + ": output \"" + rel + "\" must be a relative path inside the output folder";
    if (!e.split.empty() && (rel.size() < 5 || rel.compare(rel.size() - 5, 5, ".json") != 0))
      return where + ": output \"" + rel + "\" of a split entry must name its scene description (.json)";
    e.output = (fs::absolute(fs::path(outDir)) / rel).lexically_normal().string();
    if (!outputs.insert(e.output).second) return where + ": output \"" + rel + "\" is named by an earlier entry too";
    e.shardMaps = j.value("shardMaps", shardDefault);
    entries->push_back(std::move(e));
  }
  *rc = 0;
  return std::nullopt;
}

std::optional<std::string> readFolder(const std::string& folder, const std::string& globs,
                                      const std::vector<std::string>& args, const std::string& outDir,
                                      std::vector<Entry>* entries) {
  std::vector<std::string> patterns;
  std::stringstream ss(globs);
  for (std::string g; std::getline(ss, g, ',');)
    if (!g.empty()) patterns.push_back(g);
  std::error_code ec;
  std::vector<fs::path> found;
  const fs::path root = fs::absolute(fs::path(folder));
  for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string rel = fs::relative(it->path(), root).generic_string();
    const std::string name = it->path().filename().string();
    for (const auto& p : patterns)
      if (fnmatch(p.c_str(), rel.c_str(), 0) == 0 || fnmatch(p.c_str(), name.c_str(), 0) == 0) {
        found.push_back(it->path().lexically_relative(root));  // a linked file keeps its link's name
        break;
      }
  }
  if (ec) return folder + ": " + ec.message();
  std::sort(found.begin(), found.end());
  for (const auto& rel : found) {
    Entry e;
    e.name = rel.generic_string();
    e.mesh = (root / rel).string();
    e.args = args;
    e.output = (fs::absolute(fs::path(outDir)) / expandPattern("{dir}{stem}.vff", rel)).lexically_normal().string();
    entries->push_back(std::move(e));
  }
  return std::nullopt;
}

}  // namespace vff::library
