// worker.cpp - bakes one entry into the cache: vff-bake writes it in a private folder (its own
// temporary and rename there), then a rename moves it to CACHE/ab/KEY.vff. A process killed at any
// point leaves at most a private folder, which the next run on that machine removes.
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli.h"
#include "library.h"

namespace fs = std::filesystem;

namespace vff::library {

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

namespace {

// The last "error:" line of vff-bake's stderr (or its last line).
std::string lastErrorLine(const std::string& err) {
  std::string last, lastError;
  std::stringstream s(err);
  for (std::string line; std::getline(s, line);) {
    if (line.empty() || line[0] == '\r') continue;
    last = line;
    if (line.find(": error: ") != std::string::npos) lastError = line;
  }
  return lastError.empty() ? last : lastError;
}

}  // namespace

int runProcess(const std::vector<std::string>& args, const std::string& out, const std::string& err) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    // The bake ends with the process that waits for it (a killed pool leaves no bake running).
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    const int o = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (o < 0 || e < 0) _exit(127);
    dup2(o, 1);
    dup2(e, 2);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

namespace {

// Runs vff-bake with `args` (and -o DIR/NAME) in a private folder; on success moves the file to
// `to` in the cache. A scene (`sceneName`: its description's file name): -o DIR/scene/NAME, and the
// folder DIR/scene, description and fields, is moved to `to`.
BakeResult runVffBake(std::vector<std::string> args, const std::string& to, const WorkerOptions& o,
                      const std::string& sceneName = "") {
  BakeResult r;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string dir = makePrivateDir(o.cacheDir);
  std::string file = dir + "/" + fs::path(to).filename().string();
  if (!sceneName.empty()) {
    std::error_code ec;
    fs::create_directories(dir + "/scene", ec);
    file = dir + "/scene";
    args.insert(args.end(), {"-o", file + "/" + sceneName});
  } else {
    args.insert(args.end(), {"-o", file});
  }
  const int rc = runProcess(args, dir + "/stdout.json", dir + "/stderr.txt");
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.exitCode = rc;
  if (rc == 0) {
    auto summary = nlohmann::json::parse(readText(dir + "/stdout.json"), nullptr, false);
    r.rays = jsonCount(summary, "rays");
    if (summary.is_object() && summary.contains("fields") && summary["fields"].is_array())  // a scene
      for (const auto& f : summary["fields"]) r.rays += jsonCount(f, "rays");
    std::error_code ec;
    fs::create_directories(fs::path(to).parent_path(), ec);
    struct stat st{};
    if (::rename(file.c_str(), to.c_str()) != 0 &&
        // A folder cannot replace another: a racing writer put the same scene there first.
        !(!sceneName.empty() && (errno == ENOTEMPTY || errno == EEXIST) && ::stat(to.c_str(), &st) == 0)) {
      const std::string problem = to + ": " + std::strerror(errno);
      r.error = problem;
      r.exitCode = cli::kExitIo;
    } else {
      r.ok = true;
    }
  } else if (rc < 0 || rc == 127) {
    r.error = "cannot run " + o.vffBake;
    r.exitCode = cli::kExitRuntime;
  } else {
    r.error = lastErrorLine(readText(dir + "/stderr.txt"));
    // The report names the entry: vff-bake's prefix and the path of its input (args[1]) are left out.
    for (const std::string& prefix : {std::string("vff-bake: error: "), args.size() > 1 ? args[1] + ": " : std::string("\n")})
      if (r.error.compare(0, prefix.size(), prefix) == 0) r.error.erase(0, prefix.size());
    if (rc > 128) r.error = "vff-bake killed by signal " + std::to_string(rc - 128) + (r.error.empty() ? "" : ": " + r.error);
    if (r.error.empty()) r.error = "vff-bake failed with exit code " + std::to_string(rc);
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  return r;
}

}  // namespace

BakeResult bakeUnit(const Entry& e, const Unit& u, const WorkerOptions& o) {
  std::vector<std::string> args = {o.vffBake, e.mesh};
  args.insert(args.end(), e.args.begin(), e.args.end());
  args.insert(args.end(), {"-j", std::to_string(o.threads), "--json", "-q"});
  if (!e.split.empty())
    return runVffBake(args, sceneCachePath(o.cacheDir, e.key), o, fs::path(e.output).filename().string());
  if (!u.part()) return runVffBake(args, cachePath(o.cacheDir, e.key), o);
  args.insert(args.end(), {"--map-range", std::to_string(u.begin) + ":" + std::to_string(u.end)});
  return runVffBake(args, partPath(o.cacheDir, e.key, u.begin, u.end), o);
}

BakeResult mergeParts(const Entry& e, const std::vector<Unit>& parts, const WorkerOptions& o) {
  std::vector<std::string> args = {o.vffBake, "--merge"};
  for (const Unit& u : parts) args.push_back(partPath(o.cacheDir, e.key, u.begin, u.end));
  args.push_back("-q");
  BakeResult r = runVffBake(args, cachePath(o.cacheDir, e.key), o);
  if (r.ok)
    for (const Unit& u : parts) ::unlink(partPath(o.cacheDir, e.key, u.begin, u.end).c_str());
  return r;
}

std::string selfPath() {
  std::error_code ec;
  auto p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(kProg) : p.string();
}

std::string findVffBake() {
  if (const char* env = std::getenv("VFF_BAKE"); env && *env) return env;
  const fs::path beside = fs::path(selfPath()).parent_path();
  for (const fs::path& p : {beside / "vff-bake", beside / ".." / "vff-bake" / "vff-bake"}) {
    std::error_code ec;
    if (fs::exists(p, ec)) return fs::absolute(p).lexically_normal().string();
  }
  return "vff-bake";
}

}  // namespace vff::library
