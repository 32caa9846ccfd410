// peak_rss.cpp - vff_peak_rss: runs a command and reports its exit status, peak memory and time.
//
//   vff_peak_rss SECONDS OUT ERR CMD [ARGS...]
//
// runs CMD with stdout to the file OUT and stderr to the file ERR, kills it with SIGKILL when it is
// still running after SECONDS, and prints one line on stdout:
//
//   EXIT PEAK_KIB WALL_SECONDS
//
// EXIT is CMD's exit code, or 128 + the signal that ended it (137 after the time limit); PEAK_KIB is
// its peak resident set size as the kernel counts it (wait4's ru_maxrss, KiB on Linux: the most
// memory the process ever had in RAM, whatever it allocated and freed); WALL_SECONDS its run time.
// The harness exits 0 when it could run CMD and report, 2 otherwise.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

pid_t gChild = 0;

// SIGALRM: the time limit has passed.
void onAlarm(int) {
  if (gChild > 0) kill(gChild, SIGKILL);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: vff_peak_rss SECONDS OUT ERR CMD [ARGS...]\n");
    return 2;
  }
  const double limit = std::atof(argv[1]);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    std::fprintf(stderr, "vff_peak_rss: fork: %s\n", std::strerror(errno));
    return 2;
  }
  if (pid == 0) {
    const int out = ::open(argv[2], O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int err = ::open(argv[3], O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (out < 0 || err < 0 || dup2(out, 1) < 0 || dup2(err, 2) < 0) _exit(126);
    execvp(argv[4], argv + 4);
    std::fprintf(stderr, "vff_peak_rss: cannot run %s: %s\n", argv[4], std::strerror(errno));
    _exit(127);
  }
  gChild = pid;
  struct sigaction sa {};
  sa.sa_handler = onAlarm;
  sigaction(SIGALRM, &sa, nullptr);
  itimerval timer{};
  timer.it_value.tv_sec = static_cast<time_t>(limit);
  timer.it_value.tv_usec = static_cast<suseconds_t>((limit - double(timer.it_value.tv_sec)) * 1e6);
  setitimer(ITIMER_REAL, &timer, nullptr);
  int status = 0;
  rusage ru{};
  while (wait4(pid, &status, 0, &ru) != pid) {
    if (errno != EINTR) {
      std::fprintf(stderr, "vff_peak_rss: wait4: %s\n", std::strerror(errno));
      return 2;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::printf("%d %ld %.3f\n", code, ru.ru_maxrss, seconds);
  return 0;
}
