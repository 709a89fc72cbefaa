#include "sim_hw/quota_storage.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string TestDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("hairrig_quota_storage_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

int FilesIn(const std::string& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

Status Write(CaptureStorage& disk, const std::string& path, const std::string& text) {
  return disk.WriteFileAtomic(path, text.data(), text.size(), {});
}

// The message is the one core/file_util.h builds from errno ENOSPC, because
// the failure comes from inside write(2); the temporary is gone, the old file
// is intact and its bytes are back in the quota.
TEST(QuotaStorage, AWriteBeyondTheQuotaFailsLikeAFullDisk) {
  const std::string dir = TestDir("atomic");
  const std::string path = dir + "/manifest.json";
  QuotaStorage disk({.quota_bytes = 1000});
  ASSERT_TRUE(Write(disk, path, "old").ok());
  EXPECT_EQ(disk.used_bytes(), 3u);
  const Status full = Write(disk, path, std::string(2000, 'x'));
  EXPECT_EQ(full.code(), StatusCode::kIoError);
  EXPECT_EQ(full.message(), IoErrorFromErrno(path + ": write failed", ENOSPC).message());
  EXPECT_NE(full.message().find("No space left on device"), std::string::npos) << full.message();
  EXPECT_EQ(ReadAll(path), "old");
  EXPECT_EQ(FilesIn(dir), 1) << "a temporary was left";
  EXPECT_EQ(disk.used_bytes(), 3u);
  ASSERT_TRUE(Write(disk, path, std::string(600, 'y')).ok());  // replaces the 3 bytes
  EXPECT_EQ(*disk.FreeBytes(dir), 400u);
  disk.Consume(300);
  EXPECT_EQ(*disk.FreeBytes(dir), 100u);
}

TEST(QuotaStorage, AFailedAppendLeavesTheFileAsItWas) {
  const std::string dir = TestDir("append");
  const std::string path = dir + "/journal.jsonl";
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  ASSERT_GE(fd, 0);
  QuotaStorage disk({.quota_bytes = 10});
  const std::string first = "{\"a\":1}\n", second = "{\"b\":2}\n";
  EXPECT_TRUE(disk.AppendDurably(fd, path, first.data(), first.size(), {}).ok());
  const Status full = disk.AppendDurably(fd, path, second.data(), second.size(), {});
  EXPECT_EQ(full.message(), IoErrorFromErrno(path + ": write failed", ENOSPC).message());
  EXPECT_EQ(ReadAll(path), first) << "half a record stayed in the file";
  EXPECT_EQ(disk.used_bytes(), first.size());
  ::close(fd);
}

// The sim fault disk_full: a disk that holds N frame files.
TEST(QuotaStorage, HoldsTheGivenNumberOfFrameFiles) {
  const std::string dir = TestDir("frames");
  fs::create_directories(dir + "/frames");
  QuotaStorage disk({.frame_files = 2});
  const std::string frame(5000, 'f');
  EXPECT_TRUE(Write(disk, dir + "/frames/000_CAM.png", frame).ok());
  EXPECT_TRUE(Write(disk, dir + "/frames/001_CAM.png", frame).ok());
  const Status full = Write(disk, dir + "/frames/002_CAM.png", frame);
  EXPECT_EQ(full.message(),
            IoErrorFromErrno(dir + "/frames/002_CAM.png: write failed", ENOSPC).message());
  EXPECT_FALSE(Write(disk, dir + "/frames/003_CAM.png", frame).ok());
  EXPECT_EQ(FilesIn(dir + "/frames"), 2);
  EXPECT_TRUE(Write(disk, dir + "/manifest.json", "{}").ok()) << "small files still fit";
}

}  // namespace
}  // namespace hairrig
