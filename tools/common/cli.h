// cli.h - what every vff-* command-line tool shares: exit codes, diagnostics, --version, --format,
// reading "-" from stdin and writing output files atomically.
//
// Conventions (in the manner of KTX-Software's tools):
//   - data goes to stdout, diagnostics to stderr;
//   - a diagnostic reads "vff-inspect: error: file.vff@0x40 [DIST]: header-checksum (3005): message";
//   - every tool returns one of the documented exit codes below and prints exitCodeHelp() in --help;
//   - every tool has --help and --version; tools with a report take --format text|json.
//
//   int main(int argc, char** argv) {
//     CLI::App app{"Does things.\n" + vff::cli::exitCodeHelp()};
//     vff::cli::CommonOptions common;
//     vff::cli::addCommonOptions(app, "vff-thing", common);
//     if (auto rc = vff::cli::parse(app, "vff-thing", argc, argv)) return *rc;
//     auto f = vff::File::open(path);
//     if (!f) return vff::cli::reportError("vff-thing", path, f.error());
//   }
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "vff/error.h"

namespace vff::cli {

// ---- Exit codes ---------------------------------------------------------------------------------
inline constexpr int kExitSuccess = 0;      // the command did what was asked (a file may still have warnings)
inline constexpr int kExitUsage = 1;        // bad command line: unknown option, missing or invalid argument
inline constexpr int kExitIo = 2;           // a file cannot be opened, read or written
inline constexpr int kExitInvalidFile = 3;  // an input file is not valid (not a .vff, corrupt, fails validation)
inline constexpr int kExitRuntime = 4;      // any other failure while running (out of memory, internal error)
inline constexpr int kExitUnsupported = 5;  // a valid request this build or this field does not support

// The exit code for a libvff error code:
//   1xxx (I/O) -> 2; 2xxx..8xxx (file problems) -> 3; 9005 (unsupported) -> 5;
//   10xxx (mesh input): 10001 unknown mesh format and 10003 unsupported mesh content -> 5,
//   the other 10xxx (an unparsable or unusable mesh) -> 3; 11xxx (scene description): 11002 (not a
//   vff-scene version 1) -> 5, the others -> 3; everything else (9xxx API, unknown) -> 4.
int exitCodeFor(Code code) noexcept;

// The "Exit codes:" paragraph for the end of every tool's --help text.
std::string exitCodeHelp();

// "vff-inspect 0.1.0 (libvff 0.1.0, .vff format 1.0)", for --version.
std::string versionString(std::string_view prog);

// ---- Diagnostics (all to stderr) ----------------------------------------------------------------
// "PROG: SEVERITY: FILE@0xOFFSET [TAG]: code-name (1234): message". The place is left out piece by
// piece when unknown: no "@0x.." without an offset, no "[TAG]" without a section, no "FILE" when
// `file` is empty (then the colon after the place goes too).
std::string formatDiagnostic(std::string_view prog, std::string_view severity, std::string_view file,
                             const Error& error);

// Prints formatDiagnostic(prog, "error", file, error) to stderr and returns exitCodeFor(error.code).
int reportError(std::string_view prog, std::string_view file, const Error& error);

// Runs a tool's body; everything it throws (an allocation, the JSON library) ends as a runtime error
// naming `prog` (out-of-memory, or an internal error with the exception's text), not an abort.
int runGuarded(std::string_view prog, int (*body)(int, char**), int argc, char** argv);

// Prints "PROG: warning: ..." for an Error that does not stop the command.
void reportWarning(std::string_view prog, std::string_view file, const Error& error);

// Prints "PROG: error: message" and a hint to run --help. The caller returns kExitUsage.
void usageError(std::string_view prog, std::string_view message);

// Prints "PROG: error: message" for a failure that is neither a usage error nor a libvff Error.
void printError(std::string_view prog, std::string_view message);

// ---- Options shared by every tool ---------------------------------------------------------------
enum class OutputFormat { kText, kJson };

struct CommonOptions {
  OutputFormat format = OutputFormat::kText;  // --format text|json
};

// Adds --version (printing versionString(prog)) to `app`.
void addVersionFlag(CLI::App& app, std::string_view prog);
// Adds --format text|json, stored into `format`.
void addFormatOption(CLI::App& app, OutputFormat& format);
// Both of the above.
void addCommonOptions(CLI::App& app, std::string_view prog, CommonOptions& options);

// Parses the command line. Returns nothing when the tool should go on; otherwise the exit code to
// return at once: kExitSuccess after --help or --version (printed to stdout), kExitUsage after a
// parse error (printed to stderr as a diagnostic, with a hint to run --help).
// It also ignores SIGXFSZ, so that a file growing past RLIMIT_FSIZE (ulimit -f) makes write() fail
// with EFBIG, reported like a full disk (exit 2, no partial file), instead of killing the tool.
// And it installs checkStdoutAtExit(prog) (once per process, before parsing, so --help and --version
// are covered too).
std::optional<int> parse(CLI::App& app, std::string_view prog, int argc, char** argv);

// Registers (std::atexit, once per process; later calls only change `prog`) a check that runs when
// the tool returns from main or calls std::exit: it flushes std::cout and stdout and, when either
// could not be written at any point (a full disk, /dev/full, an I/O error), prints
// "PROG: error: stdout: No space left on device" (the cause from errno, or "write error") to stderr
// and ends the process with kExitIo, whatever main returned (the coreutils close_stdout rule: a
// report that did not arrive is a failure). Output files written with writeFileAtomic are complete
// by then; only the report on stdout was lost. A closed pipe still ends the tool with SIGPIPE, as
// for any Unix filter. When stdout is not a terminal its buffer becomes 64 KiB, so that a report up
// to that size fails at exit with its cause known. Called by parse() before anything is printed; a
// tool that does not use parse() calls it itself, first.
void checkStdoutAtExit(std::string_view prog);

// ---- Formatting ---------------------------------------------------------------------------------
// "17309696 bytes (16.508 MiB)": the exact count and MiB (2^20 bytes) with three decimals.
std::string formatBytes(uint64_t bytes);
// "1 field", "3 fields": a count and its noun, plural unless the count is 1 (`plural` where the
// noun does not take an -s: count(2, "mesh", "meshes")).
std::string count(uint64_t n, std::string_view noun, std::string_view plural = {});
// "0x1f40"
std::string hex(uint64_t value);
// "0x0123456789abcdef" (always 16 digits, for checksums)
std::string hex64(uint64_t value);
// "0123456789abcdef": the same without the prefix (the spelling of vff.source.xxh3 in META)
std::string hexDigits64(uint64_t value);

// ---- Files --------------------------------------------------------------------------------------
// Refuses, before anything reads it, an input path that is not a regular file: kIoOpen (exit 2),
// "PATH: not a regular file" for a FIFO, a folder, a device or a socket; or the
// reason it cannot be opened. A FIFO would block a reader until a writer came, and a field must be
// mapped or read to a known size. (Standard input, "-", is read as a stream and not checked here.)
Status checkRegularFile(const std::string& path);

// The whole of standard input (for a FILE argument of "-"). Fails with kIoRead.
Result<std::vector<uint8_t>> readStdin();

// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so that a
// failure never leaves a partial file (nor removes an existing one). "-" writes to stdout.
// Fails with kIoWrite (the message names the file).
Status writeFileAtomic(const std::string& path, std::span<const uint8_t> bytes);

// An output file written in pieces, in any order and from many threads (pwrite at offsets), that
// appears at `path` only when commit() succeeds: a temporary file in the same folder renamed into
// place. Dropped without commit(), the temporary is removed. writeFileAtomic is this in one piece.
//
//   auto out = vff::cli::AtomicFile::create("hits.npy");
//   if (!out) return reportError(prog, "", out.error());
//   if (auto st = out->writeAt(0, header); !st) ...;   // any thread, any order
//   if (auto st = out->commit(); !st) ...;
class AtomicFile {
 public:
  // Fails with kIoWrite naming the file (its folder cannot take a temporary file).
  static Result<AtomicFile> create(const std::string& path);
  AtomicFile(AtomicFile&& o) noexcept;
  AtomicFile& operator=(AtomicFile&&) = delete;
  ~AtomicFile();
  // Writes all of `bytes` at `offset`; safe from many threads at once for disjoint ranges.
  Status writeAt(uint64_t offset, std::span<const uint8_t> bytes) const;
  // Gives the file a plain create's mode, closes it and renames it over `path` (kIoWrite).
  Status commit();

 private:
  AtomicFile(std::string path, std::string tmp, int fd) : path_(std::move(path)), tmp_(std::move(tmp)), fd_(fd) {}
  std::string path_, tmp_;
  int fd_ = -1;
};

// Whether s ends with suffix, ASCII letters compared without case (suffix in lower case).
bool endsWithNoCase(std::string_view s, std::string_view suffix);

// Whether `path` names a glTF asset: a name ending in .gltf or .glb (any case), or a regular file
// that starts with the GLB magic "glTF" ("-" never: standard input is not peeked at).
bool isGltfInput(const std::string& path);

}  // namespace vff::cli
