// The diagnostics every tool shares (tools/common/cli.h): a path named once, counts with their
// noun in the right number, and the refusal of inputs that are not regular files.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "cli.h"

namespace {

using vff::Code;
using vff::makeError;

TEST(Diagnostics, NameThePathOnce) {
  // libvff's and the baker's messages start with the path; the diagnostic names it in its place.
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "m.glb",
                                       makeError(Code::kMeshUnsupported, "m.glb: requires the glTF extension X")),
            "vff-bake: error: m.glb: mesh-unsupported (10003): requires the glTF extension X");
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-inspect", "error", "d/f.vff", makeError(Code::kIoOpen, "d/f.vff: not a regular file")),
            "vff-inspect: error: d/f.vff: io-open (1001): not a regular file");
  // Another file named first (a glTF's buffer), a longer name that starts with the path, or a
  // message without the path stay whole.
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "m.gltf", makeError(Code::kIoOpen, "m.gltf.bin: missing")),
            "vff-bake: error: m.gltf: io-open (1001): m.gltf.bin: missing");
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "m.glb", makeError(Code::kMeshEmpty, "the mesh has no triangles")),
            "vff-bake: error: m.glb: mesh-empty (10004): the mesh has no triangles");
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "", makeError(Code::kIoOpen, "m.glb: gone")),
            "vff-bake: error: io-open (1001): m.glb: gone");
  // A JSON reader's LINE:COLUMN after the path joins the place; a path followed by other text after
  // its colon stays whole.
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "s.json",
                                       makeError(Code::kSceneJson, "s.json:2:14: fields[0]: syntax error")),
            "vff-bake: error: s.json:2:14: scene-json (11001): fields[0]: syntax error");
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "s.json", makeError(Code::kSceneJson, "s.json:2x: odd")),
            "vff-bake: error: s.json: scene-json (11001): s.json:2x: odd");
  EXPECT_EQ(vff::cli::formatDiagnostic("vff-bake", "error", "s.json", makeError(Code::kSceneJson, "s.json:2:: odd")),
            "vff-bake: error: s.json: scene-json (11001): s.json:2:: odd");
}

TEST(Diagnostics, CountsTakeTheirNumber) {
  EXPECT_EQ(vff::cli::count(1, "field"), "1 field");
  EXPECT_EQ(vff::cli::count(0, "field"), "0 fields");
  EXPECT_EQ(vff::cli::count(2, "instance"), "2 instances");
  EXPECT_EQ(vff::cli::count(1, "mesh", "meshes"), "1 mesh");
  EXPECT_EQ(vff::cli::count(3, "mesh", "meshes"), "3 meshes");
}

TEST(Diagnostics, OnlyRegularFilesAreInputs) {
  // A fresh folder of this run, in the system's temporary folder.
  std::string dir = (std::filesystem::temp_directory_path() / "vff-diag-XXXXXX").string();
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  const std::string fifo = dir + "/f.vff", file = dir + "/r.vff";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  vff::Status st = vff::cli::checkRegularFile(fifo);  // (a blocking open would never return)
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, Code::kIoOpen);
  EXPECT_EQ(st.error().message, fifo + ": not a regular file");
  st = vff::cli::checkRegularFile(dir);
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().message, dir + ": not a regular file");
  st = vff::cli::checkRegularFile(file);
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().message, file + ": No such file or directory");
  FILE* f = std::fopen(file.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  EXPECT_TRUE(vff::cli::checkRegularFile(file));
  ::unlink(file.c_str());
  ::unlink(fifo.c_str());
  ::rmdir(dir.c_str());
}

}  // namespace
