// interrupt.cpp - vff-bake's temporaries: removed when the bake is interrupted (SIGINT, SIGTERM,
// SIGHUP), and those of an earlier run that died are removed by the next (see bake.h).
//
// libvff's Writer writes DIR/.NAME.tmp-PID-N next to DIR/NAME and renames it when complete; it does
// not say N, so the temporaries of this process are found by their name: every one that carries
// this process's PID is this process's (a process that had the PID before is dead).
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "bake.h"

namespace vff::bake_tool {

namespace {

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
// The paths the handler removes. Each arming builds a new list and publishes it whole; lists are
// never freed (a handler could be reading one), and are kept reachable here.
struct PathList {
  std::vector<std::string> paths;
  std::vector<const char*> cStrings;
};
std::deque<PathList> gLists;
PathList* volatile gList = nullptr;
volatile sig_atomic_t gPathCount = 0;

// Async-signal-safe: unlink, sigaction and raise only. The signal is blocked while this runs, so the
// raised one is delivered with the default action as the handler returns: the process ends killed
// by it, as it would have without the handler.
void onSignal(int sig) {
  const PathList* list = gList;
  for (sig_atomic_t i = 0; list && i < gPathCount; ++i) ::unlink(list->cStrings[size_t(i)]);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  raise(sig);
}

// The folder of `output` and the prefix of its temporaries' names (".NAME.tmp-").
std::pair<std::filesystem::path, std::string> temporaryPattern(const std::string& output) {
  const size_t slash = output.find_last_of('/');
  return {folderOf(output), "." + (slash == std::string::npos ? output : output.substr(slash + 1)) + ".tmp-"};
}

// The PID in a temporary's name PREFIX PID-N, or 0 when the name is not one.
pid_t temporaryPid(const std::string& name, const std::string& prefix) {
  if (name.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string rest = name.substr(prefix.size());
  const size_t dash = rest.find('-');
  if (dash == 0 || dash == std::string::npos || dash > 9 || rest.size() == dash + 1 ||
      rest.find_first_not_of("0123456789-") != std::string::npos || rest.find('-', dash + 1) != std::string::npos)
    return 0;
  return pid_t(std::stol(rest.substr(0, dash)));
}

// The temporaries of `output` in its folder whose PID `keep` accepts.
template <typename Keep>
std::vector<std::filesystem::path> temporaries(const std::string& output, Keep keep) {
  const auto [dir, prefix] = temporaryPattern(output);
  std::vector<std::filesystem::path> found;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const pid_t pid = temporaryPid(it->path().filename().string(), prefix);
    if (pid > 0 && keep(pid)) found.push_back(it->path());
  }
  return found;
}

}  // namespace

std::string folderOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

bool processIsGone(pid_t pid) { return ::kill(pid, 0) == -1 && errno == ESRCH; }

void removeStaleTemporaries(const std::string& output) {
  std::error_code ec;
  for (const auto& p : temporaries(output, processIsGone)) std::filesystem::remove(p, ec);
}

void removeTemporaryOnSignal(const std::string& output, const std::vector<std::string>& finished) {
  const pid_t self = getpid();
  PathList& list = gLists.emplace_back();
  for (const auto& p : temporaries(output, [self](pid_t pid) { return pid == self; })) list.paths.push_back(p.string());
  list.paths.insert(list.paths.end(), finished.begin(), finished.end());
  for (const std::string& p : list.paths) list.cStrings.push_back(p.c_str());
  gPathCount = 0;
  gList = &list;
  gPathCount = sig_atomic_t(list.cStrings.size());
  for (int sig : kSignals) {
    struct sigaction old {}, act {};
    // A signal the caller ignores (nohup, a background job of a script) stays ignored.
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    act.sa_handler = onSignal;
    sigemptyset(&act.sa_mask);
    for (int other : kSignals) sigaddset(&act.sa_mask, other);
    sigaction(sig, &act, nullptr);
  }
}

}  // namespace vff::bake_tool
