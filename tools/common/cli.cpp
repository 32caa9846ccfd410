// cli.cpp - the shared command-line helpers (see cli.h).
#include "cli.h"

#include <algorithm>
#include <new>
#include <stdexcept>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>

#include "vff/format.h"
#include "vff/version.h"

namespace vff::cli {

int exitCodeFor(Code code) noexcept {
  const auto c = static_cast<uint32_t>(code);
  if (c == 0) return kExitSuccess;
  if (c >= 1000 && c < 2000) return kExitIo;
  if (c >= 2000 && c < 9000) return kExitInvalidFile;
  if (code == Code::kUnsupported) return kExitUnsupported;
  if (code == Code::kMeshFormat || code == Code::kMeshUnsupported) return kExitUnsupported;
  if (code == Code::kSceneVersion) return kExitUnsupported;
  if (c >= 10000 && c < 12000) return kExitInvalidFile;  // mesh inputs, scene descriptions
  return kExitRuntime;
}

std::string exitCodeHelp() {
  return "Exit codes:\n"
         "  0  success\n"
         "  1  command-line error (unknown option, missing or invalid argument)\n"
         "  2  I/O error (a file cannot be opened, read or written)\n"
         "  3  invalid input file (not a .vff file, corrupt, or fails validation)\n"
         "  4  runtime error\n"
         "  5  unsupported (a valid request this tool or field does not support)";
}

std::string versionString(std::string_view prog) {
  return std::string(prog) + " " + kLibraryVersion + " (libvff " + kLibraryVersion + ", .vff format " +
         std::to_string(kVersionMajor) + "." + std::to_string(kVersionMinor) + ")";
}

namespace {

// The length of "LINE:COLUMN" at the start of `s` (the place a JSON reader gives after the file
// name, spec/scene.md section 1), or 0.
size_t lineColumnLength(std::string_view s) {
  size_t i = 0, parts = 0;
  while (parts < 2) {
    const size_t start = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    if (i == start) return 0;
    if (++parts < 2) {
      if (i >= s.size() || s[i] != ':') return 0;
      ++i;
    }
  }
  return i;
}

}  // namespace

std::string formatDiagnostic(std::string_view prog, std::string_view severity, std::string_view file,
                             const Error& error) {
  // libvff and the baker name the file in their messages ("P: not a regular file", a JSON reader's
  // "P:LINE:COLUMN: ..."), for callers that print only the message; the diagnostic names it once,
  // in its place, with the line and column when the message has them.
  std::string_view message = error.message;
  std::string place(file);
  if (!file.empty() && message.size() > file.size() + 2 && message.starts_with(file)) {
    const std::string_view rest = message.substr(file.size());
    if (rest.starts_with(": ")) {
      message.remove_prefix(file.size() + 2);
    } else if (const size_t n = rest.size() > 1 && rest[0] == ':' ? lineColumnLength(rest.substr(1)) : 0;
               n > 0 && rest.substr(1 + n).starts_with(": ")) {
      place += rest.substr(0, 1 + n);
      message.remove_prefix(file.size() + 1 + n + 2);
    }
  }
  if (error.offset != kNoOffset) place += "@" + hex(error.offset);
  if (error.section != 0) {
    if (!place.empty()) place += ' ';
    place += "[" + sectionTagName(error.section) + "]";
  }
  std::string s = std::string(prog) + ": " + std::string(severity) + ": ";
  if (!place.empty()) s += place + ": ";
  s += codeName(error.code);
  s += " (" + std::to_string(static_cast<uint32_t>(error.code)) + "): ";
  s += message;
  return s;
}

int reportError(std::string_view prog, std::string_view file, const Error& error) {
  (void)std::fprintf(stderr, "%s\n", formatDiagnostic(prog, "error", file, error).c_str());
  const int rc = exitCodeFor(error.code);
  return rc == kExitSuccess ? kExitRuntime : rc;  // an Error with kOk is still a failure
}

int runGuarded(std::string_view prog, int (*body)(int, char**), int argc, char** argv) {
  try {
    return body(argc, argv);
  } catch (const std::bad_alloc&) {
    return reportError(prog, "", makeError(Code::kOutOfMemory, "out of memory"));
  } catch (const std::exception& e) {
    return reportError(prog, "", makeError(Code::kBadState, std::string("internal error: ") + e.what()));
  }
}

void reportWarning(std::string_view prog, std::string_view file, const Error& error) {
  (void)std::fprintf(stderr, "%s\n", formatDiagnostic(prog, "warning", file, error).c_str());
}

void usageError(std::string_view prog, std::string_view message) {
  const std::string p(prog), m(message);
  (void)std::fprintf(stderr, "%s: error: %s\nRun with --help for more information.\n", p.c_str(), m.c_str());
}

void printError(std::string_view prog, std::string_view message) {
  const std::string p(prog), m(message);
  (void)std::fprintf(stderr, "%s: error: %s\n", p.c_str(), m.c_str());
}

void addVersionFlag(CLI::App& app, std::string_view prog) {
  app.set_version_flag("--version", versionString(prog), "print the version and exit");
}

void addFormatOption(CLI::App& app, OutputFormat& format) {
  app.add_option_function<std::string>(
         "--format",
         [&format](const std::string& v) { format = v == "json" ? OutputFormat::kJson : OutputFormat::kText; },
         "output format: text, or json (one JSON object on stdout)")
      ->check(CLI::IsMember({"text", "json"}))
      ->option_text("text|json");
}

void addCommonOptions(CLI::App& app, std::string_view prog, CommonOptions& options) {
  addVersionFlag(app, prog);
  addFormatOption(app, options.format);
}

namespace {

std::string gStdoutProg;  // the tool named by the exit check's diagnostic

void stdoutExitCheck() {
  // std::cout shares stdout's buffer (sync_with_stdio), so flushing both sends every byte the tool
  // wrote; ferror() also remembers a failure of an earlier, implicit flush.
  errno = 0;
  std::cout.flush();
  int err = errno;
  const bool flushed = std::fflush(stdout) == 0;
  if (!flushed && errno != 0) err = errno;
  if (flushed && !std::ferror(stdout) && !std::cout.fail()) return;
  // The write failed earlier (an explicit flush: std::endl, CLI11's --help) and errno is gone: a
  // write of nothing, which changes nothing, still reports the cause on a device such as /dev/full.
  if (err == 0 && ::write(STDOUT_FILENO, "", 0) < 0) err = errno;
  (void)std::fprintf(stderr, "%s: error: stdout: %s\n", gStdoutProg.c_str(),
                     err != 0 ? std::strerror(err) : "write error");
  std::_Exit(kExitIo);  // not exit(): the handlers still to run could write to stdout again
}

}  // namespace

void checkStdoutAtExit(std::string_view prog) {
  static const bool registered = [] {
    // A report that fits the buffer (64 KiB rather than stdio's 4 KiB; not on a terminal, which
    // stays line-buffered) is written at exit, so the check still knows the cause (errno); a larger
    // one that fails earlier is reported as "write error".
    if (::isatty(STDOUT_FILENO) == 0) (void)std::setvbuf(stdout, nullptr, _IOFBF, std::size_t{1} << 16);
    return std::atexit(stdoutExitCheck) == 0;
  }();
  (void)registered;
  gStdoutProg = std::string(prog);
}

std::optional<int> parse(CLI::App& app, std::string_view prog, int argc, char** argv) {
  checkStdoutAtExit(prog);
  // A write beyond RLIMIT_FSIZE (ulimit -f) raises SIGXFSZ, whose default action kills the process
  // and leaves its temporary file behind. Ignored, the write fails with EFBIG instead and the tool
  // reports it like a full disk: exit 2, the temporary removed, the destination untouched.
  (void)std::signal(SIGXFSZ, SIG_IGN);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, --version: CLI11 prints them to stdout
      app.exit(e);
      return kExitSuccess;
    }
    usageError(prog, e.what());
    return kExitUsage;
  }
  return std::nullopt;
}

std::string formatBytes(uint64_t bytes) {
  char buf[64];
  (void)std::snprintf(buf, sizeof buf, "%" PRIu64 " bytes (%.3f MiB)", bytes,
                      static_cast<double>(bytes) / (1024.0 * 1024.0));
  return buf;
}

std::string count(uint64_t n, std::string_view noun, std::string_view plural) {
  std::string s = std::to_string(n) + " ";
  if (n == 1) return s += noun;
  if (!plural.empty()) return s += plural;
  return (s += noun) += "s";
}

std::string hex(uint64_t value) {
  char buf[24];
  (void)std::snprintf(buf, sizeof buf, "0x%" PRIx64, value);
  return buf;
}

std::string hexDigits64(uint64_t value) {
  char buf[24];
  (void)std::snprintf(buf, sizeof buf, "%016" PRIx64, value);
  return buf;
}

std::string hex64(uint64_t value) {
  return "0x" + hexDigits64(value);
}

Status checkRegularFile(const std::string& path) {
  // O_NONBLOCK: the open of a FIFO for reading would otherwise wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  struct stat st {};
  const bool statted = ::fstat(fd, &st) == 0;
  const int err = errno;
  ::close(fd);
  if (!statted) return makeError(Code::kIoOpen, path + ": " + std::strerror(err));
  if (S_ISREG(st.st_mode)) return {};
  return makeError(Code::kIoOpen, path + ": not a regular file");  // (libvff's words for the same refusal)
}

Result<std::vector<uint8_t>> readStdin() {
  // Read straight into the vector, sized up front when standard input is a file (a redirection):
  // through a small buffer, every growth of the vector copied and faulted in the bytes again.
  std::vector<uint8_t> bytes;
  struct stat st {};
  size_t room = size_t(1) << 20;
  if (::fstat(STDIN_FILENO, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) room = size_t(st.st_size) + 1;
  size_t used = 0;
  for (;;) {
    if (used == bytes.size()) bytes.resize(std::max(bytes.size() * 2, used + room));
    const ssize_t n = ::read(STDIN_FILENO, bytes.data() + used, bytes.size() - used);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      return makeError(Code::kIoRead, std::string("standard input: ") + std::strerror(errno));
    }
    used += size_t(n);
  }
  bytes.resize(used);
  return bytes;
}

namespace {

// Writes all of `bytes` to `fd`; false with errno set on failure.
bool writeAll(int fd, std::span<const uint8_t> bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

Error writeError(const std::string& path, const char* what) {
  return makeError(Code::kIoWrite, path + ": " + what + ": " + std::strerror(errno));
}

}  // namespace

Status writeFileAtomic(const std::string& path, std::span<const uint8_t> bytes) {
  if (path == "-") {
    if (!writeAll(STDOUT_FILENO, bytes)) return writeError("standard output", "cannot write");
    return {};
  }
  auto out = AtomicFile::create(path);
  if (!out) return std::move(out).error();
  if (Status st = out->writeAt(0, bytes); !st) return st;
  return out->commit();
}

Result<AtomicFile> AtomicFile::create(const std::string& path) {
  // The temporary lives next to the destination so that the rename stays within one file system.
  std::string tmp = path + ".tmp-XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) return writeError(path, "cannot create a temporary file");
  return AtomicFile(path, std::move(tmp), fd);
}

AtomicFile::AtomicFile(AtomicFile&& o) noexcept
    : path_(std::move(o.path_)),
      tmp_(std::move(o.tmp_)),
      fd_(std::exchange(o.fd_, -1)) {}

AtomicFile::~AtomicFile() {
  if (fd_ < 0) return;
  ::close(fd_);
  ::unlink(tmp_.c_str());
}

Status AtomicFile::writeAt(uint64_t offset, std::span<const uint8_t> bytes) const {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pwrite(fd_, bytes.data() + done, bytes.size() - done, off_t(offset + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      return writeError(path_, "cannot write");
    }
    done += static_cast<size_t>(n);
  }
  return {};
}

Status AtomicFile::commit() {
  // mkstemp creates the file 0600; give it the mode a plain create would (0666 less the umask).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  const int fd = std::exchange(fd_, -1);
  const bool moded = ::fchmod(fd, 0666 & ~mask) == 0;
  int err = errno;
  const bool closed = ::close(fd) == 0;
  if (moded && !closed) err = errno;
  if (!moded || !closed) {
    ::unlink(tmp_.c_str());
    errno = err;
    return writeError(path_, "cannot write");
  }
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp_.c_str());
    errno = e;
    return writeError(path_, "cannot rename the temporary file into place");
  }
  return {};
}

bool endsWithNoCase(std::string_view s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  const size_t base = s.size() - suffix.size();
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[base + i])) != suffix[i]) return false;
  return true;
}

bool isGltfInput(const std::string& path) {
  if (path == "-") return false;
  if (endsWithNoCase(path, ".gltf") || endsWithNoCase(path, ".glb")) return true;
  // Only a regular file is peeked at: a FIFO's bytes would be consumed, and the .vff path reports
  // why the others cannot be read.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  return in.read(magic, 4) && std::memcmp(magic, "glTF", 4) == 0;
}

}  // namespace vff::cli
