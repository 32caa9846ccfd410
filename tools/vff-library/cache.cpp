// cache.cpp - the content-addressed cache: an entry's key (its geometry as vff-bake reads it, its
// options as vff-bake resolves them, the baker's and format's versions), the cached fields at
// CACHE/ab/KEY.vff, and installing them at their outputs.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bake_job.h"
#include "cli.h"
#include "library.h"
#include "platform/parallel.h"
#include "vff/bake/mesh.h"
#include "vff/version.h"

namespace fs = std::filesystem;

namespace vff::library {

namespace {

std::string hex128(XXH128_hash_t h) {
  char s[33];
  std::snprintf(s, sizeof s, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return s;
}

}  // namespace

std::optional<std::string> fileHash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  XXH3_state_t* s = XXH3_createState();
  XXH3_128bits_reset(s);
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    XXH3_128bits_update(s, buf.data(), size_t(in.gcount()));
  }
  const XXH128_hash_t h = XXH3_128bits_digest(s);
  XXH3_freeState(s);
  return hex128(h);
}

namespace {

// CLI11's message of a number out of a range without an upper bound prints binary64's largest value
// in 309 digits ("--count: Value 0 not in range 0.000000 to 1797..."): said as the bound instead.
std::string readableRange(std::string message) {
  const size_t at = message.find(" not in range ");
  const size_t to = at == std::string::npos ? at : message.find(" to ", at);
  if (to == std::string::npos || message.size() - to < 4 + 40) return message;
  // The options vff-bake checks so (CLI11's PositiveNumber and NonNegativeNumber, both shown as 0).
  const char* bound = message.starts_with("--count:") ? "> 0" : ">= 0";
  return message.substr(0, at) + " is not " + bound;
}

// The options as vff-bake resolves them (its own parser), one canonical line: two spellings of
// the same bake (a default given or left out, -m or --map-size) share a key.
std::optional<std::string> canonicalOptions(const Entry& e, bake_tool::Options* o, std::string* error) {
  CLI::App app;
  bake_tool::addOptions(app, *o);
  std::vector<std::string> argv = {"vff-bake", e.mesh};
  argv.insert(argv.end(), e.args.begin(), e.args.end());
  argv.insert(argv.end(), {"-o", e.split.empty() ? "library.vff" : "library.vffscene.json"});
  std::vector<std::string> rev(argv.rbegin(), argv.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& pe) {
    *error = readableRange(pe.what());
    return std::nullopt;
  }
  if (auto problem = bake_tool::checkOptions(*o)) {
    *error = *problem;
    return std::nullopt;
  }
  const bake::BakeOptions bo = bake_tool::bakeOptions(*o);
  const WriteOptions wo = bake_tool::writeOptions(*o);
  nlohmann::json c = {{"positions", positionSchemeName(bo.positionScheme)},
                      {"n", bo.positionParam},
                      {"directions", directionSchemeName(bo.directionScheme)},
                      {"m", bo.mapResolution},
                      {"encoding", distanceEncodingName(bo.encoding)},
                      {"normals", bo.normals},
                      {"codec", codecName(wo.codec)},
                      {"zstdLevel", wo.codec == Codec::kZstd ? wo.zstdLevel : 0},
                      {"mapsPerBlock", wo.mapsPerBlock},
                      {"layout", {layoutTargetName(wo.layout.target), wo.layout.maxTextureSize, wo.layout.maxLayers,
                                  wo.layout.gutter}},
                      {"scene", o->scene},
                      {"grid", o->grid},
                      {"allowClippedSphere", o->allowClippedSphere}};
  if (bo.sphere) {
    char s[96];
    std::snprintf(s, sizeof s, "%a %a %a %a", double(bo.sphere->center[0]), double(bo.sphere->center[1]),
                  double(bo.sphere->center[2]), double(bo.sphere->radius));
    c["sphere"] = s;
  }
  if (!o->split.empty()) c["split"] = o->split;  // absent for one field: the keys of earlier runs hold
  return c.dump();
}

// A file's identity for the notes below: device, inode, size and modification time in nanoseconds.
std::optional<std::string> statLine(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return std::to_string(st.st_dev) + " " + std::to_string(st.st_ino) + " " + std::to_string(st.st_size) + " " +
         std::to_string(st.st_mtim.tv_sec) + "." + std::to_string(st.st_mtim.tv_nsec);
}

// A buffer's or image's URI as the file name the bake opens: decoded as tinygltf 2.7's loader
// decodes it (its dlib::urldecode, which is not part of its interface): '+' is a space and each
// "%XY" one byte (a character that is not a hex digit counting as 0), so that the note names the
// very files the bake reads.
std::string gltfUriPath(const std::string& uri) {
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return 0;
  };
  std::string path;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '+') {
      path += ' ';
    } else if (uri[i] == '%' && uri.size() > i + 2) {
      path += char((hex(uri[i + 1]) << 4) | hex(uri[i + 2]));
      i += 2;
    } else {
      path += uri[i];
    }
  }
  return path;
}

// The identities of the files a .gltf reads besides itself (its buffers and images not inlined as
// data: URIs), one line each; nothing for other formats. None when the .gltf cannot be read as
// JSON or a file it names is missing: the entry is then read anew (and the bake says what is wrong).
std::optional<std::string> referencedFiles(const std::string& mesh) {
  if (fs::path(mesh).extension() != ".gltf") return std::string();
  std::ifstream in(mesh, std::ios::binary);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return std::nullopt;
  std::string out;
  for (const char* list : {"buffers", "images"}) {
    if (!j.contains(list) || !j[list].is_array()) continue;
    for (const auto& item : j[list]) {
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) continue;
      const std::string path = gltfUriPath(uri);  // relative to the .gltf
      const std::string full = (fs::path(mesh).parent_path() / path).string();
      const auto id = statLine(full);
      if (!id) return std::nullopt;
      out += "\n" + full + " " + *id;
    }
  }
  return out;
}

// What the bake reads of a mesh and records of it, as one line; read from the mesh, or from the
// note CACHE/sources/ab/ID.txt an earlier run left for the same file (path, device, inode, size and
// modification time in nanoseconds unchanged, and those of the files a .gltf names), so that an
// up-to-date run reads no mesh. *error: why the mesh could not be read.
std::optional<std::string> meshGeometry(const Entry& e, const bake_tool::Options& o, const CacheOptions& c,
                                        Error* error) {
  std::string note;
  const auto self = c.statNotes ? statLine(e.mesh) : std::nullopt;
  const auto others = self ? referencedFiles(e.mesh) : std::nullopt;
  if (self && others) {
    const std::string id = e.mesh + "\n" + *self + "\nscene " + std::to_string(o.scene) +
                           (e.split.empty() ? "" : "\nsplit " + e.split) + *others;
    const std::string key = hex128(XXH3_128bits(id.data(), id.size()));
    note = c.dir + "/sources/" + key.substr(0, 2) + "/" + key + ".txt";
    std::ifstream in(note, std::ios::binary);
    std::string line;
    if (in && std::getline(in, line) && line.rfind("mesh ", 0) == 0) return line;
  }
  std::string geometry;
  if (!e.split.empty()) {
    uint64_t objects = 0;
    auto g = splitGeometry(e, o.scene, error, &objects);
    if (!g) return std::nullopt;
    geometry = *g;
  } else {
    bake::MeshInfo info;
    auto mesh = bake::loadMesh(e.mesh, &info, {.gltfScene = o.scene});
    if (!mesh) {
      *error = mesh.error();
      return std::nullopt;
    }
    geometry = "mesh " + info.format + " " + cli::hexDigits64(bake::geometryHash(*mesh)) + " " +
               cli::hexDigits64(bake::meshHash(*mesh)) + " " + std::to_string(mesh->droppedDegenerate) + " " +
               std::to_string(info.gltfScene);
  }
  if (!note.empty()) {
    std::error_code ec;
    fs::create_directories(fs::path(note).parent_path(), ec);
    const std::string text = geometry + "\n";
    (void)cli::writeFileAtomic(note, {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
  }
  return geometry;
}

}  // namespace

std::optional<std::string> checkBakeArgs(const Entry& e) {
  bake_tool::Options o;
  std::string error;
  if (canonicalOptions(e, &o, &error)) return std::nullopt;
  return error;
}

std::string keyHash(const std::string& text) { return hex128(XXH3_128bits(text.data(), text.size())); }

std::optional<std::string> keyText(Entry& e, const CacheOptions& c) {
  bake_tool::Options o;
  std::string error;
  auto options = canonicalOptions(e, &o, &error);
  if (!options) {
    // Named once: the report names the entry's mesh; the rule and the options' place follow.
    e.error = ruleLabel(kRuleBakeOption) + ": " + (e.where.empty() ? "" : e.where + ".options: ") + error;
    e.exitCode = kRuleBakeOption.exitCode;
    return std::nullopt;
  }
  // What the bake reads and what it records of it: the output's META names the source file and
  // format and holds both of its hashes (vff.source), so each is part of the key.
  std::string geometry;
  if (bake_tool::isVdbPath(e.mesh)) {
    auto h = fileHash(e.mesh);
    if (!h) {
      e.error = "io-open (1001): cannot be read";
      e.exitCode = cli::kExitIo;
      return std::nullopt;
    }
    geometry = "vdb " + *h;
  } else if (Error err; auto g = meshGeometry(e, o, c, &err)) {
    geometry = *g;
  } else {
    // The report names the mesh: the message keeps the rule and the problem, without the path again.
    std::string message = err.message;
    for (size_t at; (at = message.find(e.mesh + ": ")) != std::string::npos;) message.erase(at, e.mesh.size() + 2);
    e.error = std::string(codeName(err.code)) + " (" + std::to_string(static_cast<uint32_t>(err.code)) + "): " + message;
    // As vff-bake: a --scene the file does not have is a usage error.
    e.exitCode = err.code == Code::kInvalidArgument ? cli::kExitUsage : cli::exitCodeFor(err.code);
    return std::nullopt;
  }
  const bake::BakeOptions bo = bake_tool::bakeOptions(o);
  if (auto maps = positionCount(bo.positionScheme, bo.positionParam)) {
    e.maps = *maps;
    e.rays = uint64_t(*maps) * bo.mapResolution * bo.mapResolution;
    if (!e.split.empty()) e.rays *= splitObjects(geometry);
  }
  const std::string text = std::string("vff-library key 1\nbaker vff-bake ") + kLibraryVersion + "\nformat " +
                           std::to_string(kVersionMajor) + "\nsource " + fs::path(e.mesh).filename().string() +
                           "\ngeometry " + geometry + "\noptions " + *options + "\n" +
                           // The description names its fields after its own file name.
                           (e.split.empty() ? "" : "output " + fs::path(e.output).filename().string() + "\n");
  return text;
}

namespace {

// The key of one entry, or its error.
void computeKey(Entry& e, const CacheOptions& c) {
  if (auto text = keyText(e, c)) e.key = keyHash(*text);
}

std::string hostName() {
  char h[256] = {};
  gethostname(h, sizeof h - 1);
  return h[0] ? h : "host";
}

}  // namespace

void computeKeys(std::vector<Entry>& entries, const CacheOptions& o) {
  parallel::parallelFor(entries.size(), 1, std::max(1u, o.threads), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) computeKey(entries[i], o);
  });
}

std::string cachePath(const std::string& cacheDir, const std::string& key) {
  return cacheDir + "/" + key.substr(0, 2) + "/" + key + ".vff";
}

std::string partPath(const std::string& cacheDir, const std::string& key, uint32_t begin, uint32_t end) {
  return cacheDir + "/" + key.substr(0, 2) + "/" + key + ".maps-" + std::to_string(begin) + "-" + std::to_string(end) +
         ".vff";
}

bool inCache(const std::string& cacheDir, const Entry& e) {
  struct stat st{};
  if (!e.split.empty()) return ::stat(sceneCachePath(cacheDir, e.key).c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  return ::stat(cachePath(cacheDir, e.key).c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool sameFile(const std::string& from, const std::string& to) {
  struct stat c{}, o{};
  if (::stat(from.c_str(), &c) != 0 || ::stat(to.c_str(), &o) != 0) return false;
  if (c.st_dev == o.st_dev && c.st_ino == o.st_ino) return true;
  return c.st_size == o.st_size && c.st_mtim.tv_sec == o.st_mtim.tv_sec && c.st_mtim.tv_nsec == o.st_mtim.tv_nsec;
}

bool outputUpToDate(const std::string& cacheDir, const Entry& e) {
  if (!e.split.empty()) return sceneUpToDate(cacheDir, e);
  return sameFile(cachePath(cacheDir, e.key), e.output);
}

std::optional<std::string> installOutput(const std::string& cacheDir, const Entry& e) {
  if (!e.split.empty()) return installScene(cacheDir, e);
  return installFile(cachePath(cacheDir, e.key), e.output);
}

std::optional<std::string> installFile(const std::string& from, const std::string& output) {
  std::error_code ec;
  fs::create_directories(fs::path(output).parent_path(), ec);
  if (ec) return fs::path(output).parent_path().string() + ": " + ec.message();
  static std::atomic<unsigned> counter{0};
  const std::string tmp = fs::path(output).parent_path().string() + "/." + fs::path(output).filename().string() +
                          ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
  if (::link(from.c_str(), tmp.c_str()) != 0) {
    if (errno != EXDEV && errno != EPERM) return tmp + ": " + std::strerror(errno);
    // Another filesystem: a copy with the cached file's time, which outputUpToDate compares.
    fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, ec);
    struct stat st{};
    if (!ec && ::stat(from.c_str(), &st) == 0) {
      const timespec times[2] = {st.st_atim, st.st_mtim};
      ::utimensat(AT_FDCWD, tmp.c_str(), times, 0);
    }
    if (ec) {
      ::unlink(tmp.c_str());
      return output + ": " + ec.message();
    }
  }
  if (::rename(tmp.c_str(), output.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    return output + ": " + why;
  }
  return std::nullopt;
}

std::string makePrivateDir(const std::string& cacheDir) {
  static std::atomic<unsigned> counter{0};
  const std::string dir = cacheDir + "/tmp/" + hostName() + "." + std::to_string(getpid()) + "." +
                          std::to_string(counter++);
  std::error_code ec;
  fs::create_directories(dir, ec);
  return dir;
}

void removeStalePrivateDirs(const std::string& cacheDir) {
  const std::string prefix = hostName() + ".";
  std::error_code ec;
  for (fs::directory_iterator it(cacheDir + "/tmp", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string n = it->path().filename().string();
    if (n.compare(0, prefix.size(), prefix) != 0) continue;  // another machine's
    const long pid = std::strtol(n.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(it->path(), ec);
  }
}

std::optional<std::string> commitToCache(const std::string& cacheDir, const std::string& key, const std::string& file) {
  const std::string to = cachePath(cacheDir, key);
  std::error_code ec;
  fs::create_directories(fs::path(to).parent_path(), ec);
  if (::rename(file.c_str(), to.c_str()) != 0) return to + ": " + std::strerror(errno);
  return std::nullopt;
}

}  // namespace vff::library
