#include <gtest/gtest.h>

#include <algorithm>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff {
namespace {

namespace fs = std::filesystem;

class WriterFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vff_writer_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  size_t entries() const { return size_t(std::distance(fs::directory_iterator(dir_), fs::directory_iterator())); }
  fs::path dir_;
};

TEST_F(WriterFile, WritesAtomicallyAndOpensMapped) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter);
  auto dist = test::syntheticDistance(f);
  const std::string path = (dir_ / "a.vff").string();
  ASSERT_TRUE(writeFile(path, f, dist).ok());
  EXPECT_EQ(entries(), 1u);  // no temporary left behind
  auto file = File::open(path);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_EQ(file->info().fileSize, fs::file_size(path));
  EXPECT_TRUE(validateFile(path).valid());
  // The bytes equal the in-memory writer's.
  auto mem = writeMemory(f, dist);
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> disk((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(disk, *mem);
}

// The thread count changes nothing in the bytes; progress counts every map of both planes, in order,
// ending at the total.
TEST_F(WriterFile, ThreadsKeepTheBytesAndProgressReachesTheTotal) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16);
  auto dist = test::syntheticDistance(f);
  auto norm = test::syntheticNormals(f, dist);
  std::vector<std::vector<uint8_t>> outs;
  for (unsigned threads : {1u, 3u, 0u}) {
    WriteOptions o;
    o.codec = Codec::kZstd;
    o.mapsPerBlock = 1;
    o.threads = threads;
    std::vector<uint64_t> seen;
    o.progress = [&](uint64_t done, uint64_t total) {
      EXPECT_EQ(total, uint64_t(f.mapCount) * 2);
      seen.push_back(done);
    };
    auto w = Writer::createInMemory(f, o);
    ASSERT_TRUE(w) << w.error().toString();
    ASSERT_TRUE(w->writeMaps(Plane::kDistance, dist));
    ASSERT_TRUE(w->writeMaps(Plane::kNormal, norm));
    auto bytes = w->finishToMemory();
    ASSERT_TRUE(bytes) << bytes.error().toString();
    outs.push_back(std::move(*bytes));
    ASSERT_FALSE(seen.empty());
    EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
    EXPECT_EQ(seen.back(), uint64_t(f.mapCount) * 2);
  }
  EXPECT_EQ(outs[0], outs[1]);
  EXPECT_EQ(outs[0], outs[2]);
}

TEST_F(WriterFile, AbandonedWriterLeavesOldFileAndNoTemporary) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter);
  auto dist = test::syntheticDistance(f);
  const std::string path = (dir_ / "keep.vff").string();
  { std::ofstream(path) << "old contents"; }
  {
    auto w = Writer::create(path, f);
    ASSERT_TRUE(w.ok());
    ASSERT_TRUE(w->writeMaps(Plane::kDistance, std::span<const uint8_t>(dist).subspan(0, 64)).ok());
    EXPECT_EQ(entries(), 2u);  // the destination and the temporary
  }  // destroyed without finish()
  EXPECT_EQ(entries(), 1u);
  std::ifstream in(path);
  std::string s((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(s, "old contents");
}

TEST_F(WriterFile, MissingFolderIsAnIoError) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter);
  auto w = Writer::create((dir_ / "no" / "such" / "x.vff").string(), f);
  ASSERT_FALSE(w.ok());
  EXPECT_EQ(w.error().code, Code::kIoWrite);
  EXPECT_NE(w.error().message.find("x.vff"), std::string::npos);
}

TEST_F(WriterFile, OpenErrorsNameTheFile) {
  auto r = File::open((dir_ / "missing.vff").string());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, Code::kIoOpen);
  EXPECT_NE(r.error().message.find("missing.vff"), std::string::npos);
  const std::string empty = (dir_ / "empty.vff").string();
  { std::ofstream(empty).flush(); }
  EXPECT_EQ(File::open(empty).error().code, Code::kTooSmall);
}

TEST_F(WriterFile, PermissionsFollowUmask) {
  FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter);
  const std::string path = (dir_ / "p.vff").string();
  ASSERT_TRUE(writeFile(path, f, test::syntheticDistance(f)).ok());
  struct stat st {};
  ASSERT_EQ(stat(path.c_str(), &st), 0);
  const mode_t mask = umask(0);
  umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask);
}

}  // namespace
}  // namespace vff
