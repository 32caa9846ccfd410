// manifest.cpp - a library's entries, from a manifest (spec/library.md) or from a folder and a glob.
// The checks run in the order of spec/library.md's rule table, which a first-error reader follows so
// that every invalid manifest has one ID; each reports `name (ID)` and the value's JSON path.
#include <fnmatch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "cli.h"
#include "library.h"
#include "vff/strict_json.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff::library {

namespace {

// The options a manifest may set, in the kinds of spec/library.md section 4.
enum class OptionKind { kFlag, kCenter, kValue };
const std::map<std::string, OptionKind>& bakeOptionKinds() {
  static const std::map<std::string, OptionKind> kinds = {
      {"positions", OptionKind::kValue}, {"count", OptionKind::kValue},
      {"map-size", OptionKind::kValue},  {"directions", OptionKind::kValue},
      {"encoding", OptionKind::kValue},  {"normals", OptionKind::kFlag},
      {"center", OptionKind::kCenter},   {"radius", OptionKind::kValue},
      {"allow-clipped-sphere", OptionKind::kFlag}, {"codec", OptionKind::kValue},
      {"zstd-level", OptionKind::kValue}, {"maps-per-block", OptionKind::kValue},
      {"target", OptionKind::kValue},    {"max-texture-size", OptionKind::kValue},
      {"max-layers", OptionKind::kValue}, {"gutter", OptionKind::kValue},
      {"scene", OptionKind::kValue},     {"grid", OptionKind::kValue}};
  return kinds;
}

// How a number is spelled on vff-bake's command line: an integer in decimal, any other number as
// printf's "%.9g" (enough digits for the binary32 values vff-bake keeps).
std::string numberText(const json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  char s[40];
  std::snprintf(s, sizeof s, "%.9g", v.get<double>());
  return s;
}

// A value as a message shows it: its JSON text, cut short.
std::string shown(const json& v) {
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  if (v.is_string()) return "the string " + s;
  if (v.is_object()) return "an object";
  if (v.is_array()) return "an array";
  if (v.is_number()) return "the number " + s;
  return s;  // true, false, null
}

// A string as JSON writes it (a byte that is not UTF-8 shown as U+FFFD: a message never throws).
std::string jsonQuoted(const std::string& s) { return json(s).dump(-1, ' ', false, json::error_handler_t::replace); }

bool isCount(const json& v) { return v.is_number_unsigned() || (v.is_number_integer() && v.get<int64_t>() >= 0); }

// A manifest being checked: its name in messages, and the exit code of the first problem.
class Checker {
 public:
  Checker(const std::string& file, int* rc) : file_(file), rc_(rc) {}
  // "FILE: name (ID): PATH: what" (PATH left out at the top level), and *rc its rule's exit code.
  std::string fail(const ManifestRule& rule, const std::string& path, const std::string& what) const {
    *rc_ = rule.exitCode;
    return file_ + ": " + ruleLabel(rule) + ": " + (path.empty() ? "" : path + ": ") + what;
  }
  // The value at `path` is of the type `type` names (`ok`), or the member-type problem.
  std::optional<std::string> type(bool ok, const std::string& path, const json& v, const std::string& type) const {
    if (ok) return std::nullopt;
    return fail(kRuleMemberType, path, "must be " + type + ", not " + shown(v));
  }

 private:
  std::string file_;
  int* rc_;
};

// The members of an object that the manifest does not define: the first by byte order of names.
std::optional<std::string> unknownMember(const Checker& c, const json& o, const std::string& path,
                                         std::initializer_list<const char*> known, const std::string& what) {
  for (const auto& [k, v] : o.items()) {
    if (std::none_of(known.begin(), known.end(), [&key = k](const char* n) { return key == n; })) {
      std::string p = path;
      appendJsonPathKey(p, k);
      return c.fail(kRuleUnknownMember, p, "not a member of " + what);
    }
  }
  return std::nullopt;
}

// Checks an options object's names, then its value types (section 4: every name before any type);
// `path` names it.
std::optional<std::string> checkOptions(const Checker& c, const json& o, const std::string& path) {
  for (const auto& [k, v] : o.items()) {
    std::string p = path;
    appendJsonPathKey(p, k);
    if (!bakeOptionKinds().count(k))
      return c.fail(kRuleUnknownOption, p, "not a vff-bake option a library sets (spec/library.md section 4)");
  }
  for (const auto& [k, v] : o.items()) {
    std::string p = path;
    appendJsonPathKey(p, k);
    switch (bakeOptionKinds().at(k)) {
      case OptionKind::kFlag:
        if (!v.is_boolean()) return c.fail(kRuleOptionType, p, "must be true or false, not " + shown(v));
        break;
      case OptionKind::kCenter:
        if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }))
          return c.fail(kRuleOptionType, p, "must be an array of three numbers, not " + shown(v));
        break;
      case OptionKind::kValue:
        if (!v.is_number() && !v.is_string()) return c.fail(kRuleOptionType, p, "must be a number or a string, not " + shown(v));
        break;
    }
  }
  return std::nullopt;
}

// The options of a checked object as vff-bake's arguments, in the object's (byte) order of names.
void appendArgs(const json& o, std::vector<std::string>* args) {
  for (const auto& [k, v] : o.items()) {
    const std::string flag = "--" + k;
    if (v.is_boolean()) {
      if (v.get<bool>()) args->push_back(flag);
    } else if (v.is_array()) {
      args->push_back(flag);
      for (const auto& x : v) args->push_back(numberText(x));
    } else {
      args->insert(args->end(), {flag, v.is_string() ? v.get<std::string>() : numberText(v)});
    }
  }
}

// OUT/{dir}{stem}.vff style names: the pattern's {dir} (the mesh's folder relative to the base, with
// a trailing slash, or nothing), {stem} (its name without extension), {name} (with it).
std::string expandPattern(const std::string& pattern, const fs::path& relative) {
  std::string dir = relative.parent_path().generic_string();
  if (!dir.empty()) dir += '/';
  const std::pair<const char*, std::string> vars[] = {
      {"{dir}", dir}, {"{stem}", relative.stem().string()}, {"{name}", relative.filename().string()}};
  std::string s = pattern;
  for (const auto& [var, value] : vars) {
    // Left to right, never into what was put in (a file named "{dir}" stays so).
    const std::string v(var);
    for (size_t at = 0; (at = s.find(v, at)) != std::string::npos; at += value.size()) s.replace(at, v.size(), value);
  }
  return s;
}

// The problem of an output name (section 5): relative, its '/'-separated segments neither empty nor
// "." nor "..", no NUL; nothing when it is a name inside the output folder.
std::optional<std::string> outputNameProblem(const std::string& rel) {
  if (rel.empty()) return "is empty";
  if (rel.find('\0') != std::string::npos) return "holds a NUL character";
  if (rel[0] == '/') return "is absolute";
  std::stringstream ss(rel);
  for (std::string seg; std::getline(ss, seg, '/');)
    if (seg.empty() || seg == "." || seg == "..") return "has a segment \"" + seg + "\" (empty, \".\" and \"..\" are not allowed)";
  if (rel.back() == '/') return "ends with '/'";
  return std::nullopt;
}

// The top-level members, in the order of the rule table; *pattern and *shardMaps their values.
std::optional<std::string> checkTop(const Checker& c, const json& m, std::string* pattern, uint64_t* shardMaps) {
  const json& version = m["vffLibrary"];
  if (!version.is_number_integer() && !version.is_number_unsigned())
    return c.fail(kRuleVersionType, "vffLibrary", "must be an integer, not " + shown(version));
  if (!version.is_number_unsigned() || version.get<uint64_t>() != 1)
    return c.fail(kRuleVersion, "vffLibrary", "version " + version.dump() + " is not one this reader implements (1)");
  if (auto p = unknownMember(c, m, "", {"vffLibrary", "entries", "defaults", "output", "shardMaps"}, "a manifest"))
    return p;
  if (!m.contains("entries")) return c.fail(kRuleMissingMember, "entries", "a manifest needs its entries (an array)");
  if (auto p = c.type(m["entries"].is_array(), "entries", m["entries"], "an array of entries")) return p;
  if (m.contains("defaults"))
    if (auto p = c.type(m["defaults"].is_object(), "defaults", m["defaults"], "an object of vff-bake options")) return p;
  if (m.contains("output")) {
    if (auto p = c.type(m["output"].is_string(), "output", m["output"], "a string (an output name pattern)")) return p;
    *pattern = m["output"].get<std::string>();
  }
  if (m.contains("shardMaps")) {
    if (auto p = c.type(isCount(m["shardMaps"]), "shardMaps", m["shardMaps"], "an integer >= 0")) return p;
    *shardMaps = m["shardMaps"].get<uint64_t>();
  }
  if (m.contains("defaults"))
    if (auto p = checkOptions(c, m["defaults"], "defaults")) return p;
  return std::nullopt;
}

// One entry's members, in the order of the rule table.
std::optional<std::string> checkEntry(const Checker& c, const json& j, const std::string& where) {
  if (auto p = c.type(j.is_object(), where, j, "an object (an entry)")) return p;
  if (auto p = unknownMember(c, j, where, {"mesh", "options", "output", "shardMaps", "split"}, "an entry")) return p;
  if (!j.contains("mesh")) return c.fail(kRuleMissingMember, where + ".mesh", "an entry needs its mesh (a path)");
  if (auto p = c.type(j["mesh"].is_string(), where + ".mesh", j["mesh"], "a string (a path)")) return p;
  if (j.contains("options"))
    if (auto p = c.type(j["options"].is_object(), where + ".options", j["options"], "an object of vff-bake options")) return p;
  if (j.contains("output"))
    if (auto p = c.type(j["output"].is_string(), where + ".output", j["output"], "a string (a path)")) return p;
  if (j.contains("shardMaps"))
    if (auto p = c.type(isCount(j["shardMaps"]), where + ".shardMaps", j["shardMaps"], "an integer >= 0")) return p;
  if (j.contains("split"))
    if (auto p = c.type(j["split"].is_string(), where + ".split", j["split"], "a string")) return p;
  const std::string mesh = j["mesh"].get<std::string>();
  if (mesh.empty() || mesh.find('\0') != std::string::npos)
    return c.fail(kRuleMeshPath, where + ".mesh", mesh.empty() ? "is empty" : "holds a NUL character");
  if (j.contains("split") && j["split"] != "mesh" && j["split"] != "node")
    return c.fail(kRuleSplitValue, where + ".split", "must be \"mesh\" or \"node\" (vff-bake --split), not " + shown(j["split"]));
  if (j.contains("options"))
    if (auto p = checkOptions(c, j["options"], where + ".options")) return p;
  return std::nullopt;
}

}  // namespace

std::optional<std::string> readManifest(const std::string& path, const std::string& outDir,
                                        std::vector<Entry>* entries, int* rc) {
  // A named pipe or a folder is refused, not waited on.
  if (Status st = cli::checkRegularFile(path); !st) {
    *rc = cli::kExitIo;
    const std::string line = cli::formatDiagnostic(kProg, "error", path, st.error());
    return line.substr(line.find(path));  // "PATH: io-open (1001): ...", as the other tools say it
  }
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
  const Checker c(path, rc);
  *rc = cli::kExitInvalidFile;
  if (auto p = checkStrictJson(text))  // the JSON text rules (section 1), which scene descriptions share
    return path + ":" + std::to_string(p->line) + ":" + std::to_string(p->column) + ": " + ruleLabel(kRuleManifestJson) +
           ": " + (p->path.empty() ? "" : p->path + ": ") + p->message;
  const json m = json::parse(text, nullptr, false);
  if (m.is_discarded()) return c.fail(kRuleManifestJson, "", "not JSON");  // (checkStrictJson takes no text json does not)
  if (!m.is_object() || !m.contains("vffLibrary"))
    return c.fail(kRuleManifestObject, "", "not a vff library manifest (an object with \"vffLibrary\": 1)");
  std::string pattern = "{dir}{stem}.vff";
  uint64_t shardDefault = 0;
  if (auto p = checkTop(c, m, &pattern, &shardDefault)) return p;
  std::error_code ec;
  const fs::path base = fs::absolute(fs::path(path), ec).parent_path();
  const fs::path out = fs::absolute(fs::path(outDir), ec);
  const json defaults = m.contains("defaults") ? m["defaults"] : json::object();
  std::map<std::string, size_t> outputs;  // each output name, and the entry that names it
  std::vector<Entry> found;
  for (size_t i = 0; i < m["entries"].size(); ++i) {
    const json& j = m["entries"][i];
    const std::string where = "entries[" + std::to_string(i) + "]";
    if (auto p = checkEntry(c, j, where)) return p;
    Entry e;
    e.name = j["mesh"].get<std::string>();
    const fs::path mesh = fs::path(e.name).is_absolute() ? fs::path(e.name) : base / e.name;
    e.mesh = mesh.lexically_normal().string();
    // The entry's options over the defaults, key by key.
    json options = defaults;
    if (j.contains("options"))
      for (const auto& [k, v] : j["options"].items()) options[k] = v;
    appendArgs(options, &e.args);
    if (j.contains("split")) {
      e.split = j["split"].get<std::string>();
      e.args.insert(e.args.end(), {"--split", e.split});
    }
    const bool named = j.contains("output");
    std::string rel = named ? j["output"].get<std::string>()
                            : expandPattern(pattern, fs::path(e.name).is_absolute() ? fs::path(e.name).filename()
                                                                                     : fs::path(e.name).lexically_normal());
    // A split entry's output is its scene description: the pattern's ".vff" becomes ".vffscene.json".
    if (!e.split.empty() && !named && rel.size() > 4 && rel.compare(rel.size() - 4, 4, ".vff") == 0)
      rel = rel.substr(0, rel.size() - 4) + ".vffscene.json";
    const std::string outPath = named ? where + ".output" : where;
    // A name the pattern made is shown with the pattern; a given one is at its path already.
    const std::string fromPattern = "output " + jsonQuoted(rel) +
                                    " (from the pattern " + jsonQuoted(pattern) + ") ";
    if (auto p = outputNameProblem(rel))
      return c.fail(kRuleOutputPath, outPath, (named ? "" : fromPattern) + *p + ": an output is a relative path inside the output folder");
    if (!e.split.empty() && (rel.size() < 5 || rel.compare(rel.size() - 5, 5, ".json") != 0))
      return c.fail(kRuleSplitOutput, outPath, (named ? "" : fromPattern) +
                    "must name the split entry's scene description (.json), not " + jsonQuoted(rel));
    if (auto [it, fresh] = outputs.emplace(rel, i); !fresh)
      return c.fail(kRuleDuplicateOutput, outPath, (named ? jsonQuoted(rel) + " " : fromPattern) + "is the output of entries[" +
                                                       std::to_string(it->second) + "] too");
    e.outputName = rel;
    e.output = (out / rel).lexically_normal().string();
    e.shardMaps = j.contains("shardMaps") ? j["shardMaps"].get<uint64_t>() : shardDefault;
    e.shardMapsSet = j.contains("shardMaps") || m.contains("shardMaps");
    e.where = where;
    found.push_back(std::move(e));
  }
  entries->insert(entries->end(), std::make_move_iterator(found.begin()), std::make_move_iterator(found.end()));
  *rc = 0;
  return std::nullopt;
}

std::string ruleLabel(const ManifestRule& rule) { return std::string(rule.name) + " (" + std::to_string(rule.id) + ")"; }

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
    e.outputName = expandPattern("{dir}{stem}.vff", rel);
    e.output = (fs::absolute(fs::path(outDir)) / e.outputName).lexically_normal().string();
    entries->push_back(std::move(e));
  }
  return std::nullopt;
}

}  // namespace vff::library
