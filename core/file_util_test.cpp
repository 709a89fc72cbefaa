#include "core/file_util.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "core/config.h"
#include "core/json_file.h"
#include "core/sha256.h"
#include "core/strand_io.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string TestDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("hairrig_file_util_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// Every file reader of the project goes through ReadFileChunks: a folder, a
// FIFO (opening one used to wait for a writer forever) and a device (reading
// /dev/zero never ended) are refused before a byte is read.
TEST(FileUtil, OnlyRegularFilesAreRead) {
  const std::string dir = TestDir("kinds");
  const std::string fifo = dir + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string zero_link = dir + "/frame.hair";
  fs::create_symlink("/dev/zero", zero_link);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {dir, "is a folder"},
      {fifo, "is a FIFO"},
      {"/dev/zero", "is a character device"},
      {zero_link, "is a character device"}};
  for (const auto& [path, kind] : cases) {
    const auto bytes = ReadFileBytes(path);
    EXPECT_EQ(bytes.status().code(), StatusCode::kInvalidArgument) << path;
    EXPECT_NE(bytes.status().message().find(path + " " + kind), std::string::npos)
        << bytes.status().ToString();
    EXPECT_FALSE(ReadJsonFile(path).ok()) << path;
    EXPECT_FALSE(ConfigNode::LoadFile(path).ok()) << path;
    EXPECT_FALSE(Sha256OfFile(path).ok()) << path;
  }
  EXPECT_FALSE(ReadStrands(zero_link).ok());
  EXPECT_FALSE(ReadFileBytes("/dev/urandom").ok());
}

// The capture journal is opened for appending this way: a FIFO under its name
// used to block the open until a reader came, forever.
TEST(FileUtil, AppendingOpensRegularFilesOnly) {
  const std::string dir = TestDir("append");
  const std::string fifo = dir + "/journal.jsonl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, kind] : std::vector<std::pair<std::string, std::string>>{
           {fifo, "is a FIFO"}, {dir, "is a folder"}, {"/dev/null", "is a character device"}}) {
    const Result<int> fd = OpenRegularFileForAppend(path);
    EXPECT_EQ(fd.status().code(), StatusCode::kInvalidArgument) << path;
    EXPECT_NE(fd.status().message().find(path + " " + kind), std::string::npos)
        << fd.status().ToString();
    if (fd.ok()) ::close(*fd);
  }
  const std::string file = dir + "/new.jsonl";
  Result<int> fd = OpenRegularFileForAppend(file);
  ASSERT_TRUE(fd.ok()) << fd.status().ToString();
  EXPECT_EQ(::write(*fd, "a", 1), 1);
  ::close(*fd);
  fd = OpenRegularFileForAppend(file);
  ASSERT_TRUE(fd.ok()) << fd.status().ToString();
  EXPECT_EQ(::fcntl(*fd, F_GETFL) & O_NONBLOCK, 0);
  EXPECT_EQ(::write(*fd, "b", 1), 1);
  ::close(*fd);
  EXPECT_EQ(*ReadFileText(file, 10), "ab");
}

// The reader that needs only part of a file opens it with the same checks.
TEST(FileUtil, OpeningForReadTakesRegularFilesOnly) {
  const std::string dir = TestDir("open_read");
  const std::string fifo = dir + "/image.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Result<int> refused = OpenRegularFileForRead(fifo);
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find(fifo + " is a FIFO"), std::string::npos)
      << refused.status().ToString();
  if (refused.ok()) ::close(*refused);
  const std::string file = dir + "/a.txt";
  std::ofstream(file) << "abc";
  EXPECT_EQ(OpenRegularFileForRead(file, 2).status().code(), StatusCode::kOutOfRange);
  const Result<int> fd = OpenRegularFileForRead(file);
  ASSERT_TRUE(fd.ok()) << fd.status().ToString();
  char c = 0;
  EXPECT_EQ(::pread(*fd, &c, 1, 2), 1);
  EXPECT_EQ(c, 'c');
  ::close(*fd);
}

TEST(FileUtil, PathInsideFolder) {
  EXPECT_TRUE(PathIsInside("/cap/frames/000_A.png", "/cap"));
  EXPECT_TRUE(PathIsInside("/cap/./frames/../rig.yaml", "/cap"));
  EXPECT_FALSE(PathIsInside("/cap/../etc/passwd", "/cap"));
  EXPECT_FALSE(PathIsInside("/capture2/x", "/cap"));
  EXPECT_FALSE(PathIsInside("/cap", "/cap"));
  EXPECT_FALSE(PathIsInside("/etc/passwd", "/cap"));
}

TEST(FileUtil, ResolveInsideFollowsSymlinks) {
  const std::string dir = TestDir("resolve");
  fs::create_directories(dir + "/images");
  std::ofstream(dir + "/images/a.png") << "x";
  std::ofstream(dir + "/secret.png") << "x";
  fs::create_symlink("a.png", dir + "/images/inside.png");
  fs::create_symlink("../secret.png", dir + "/images/outside.png");
  const auto inside = ResolveInside(dir + "/images/inside.png", dir + "/images");
  ASSERT_TRUE(inside.ok()) << inside.status().ToString();
  EXPECT_EQ(*inside, fs::canonical(dir + "/images/a.png").string());
  const auto outside = ResolveInside(dir + "/images/outside.png", dir + "/images");
  EXPECT_EQ(outside.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(outside.status().message().find("secret.png, outside"), std::string::npos)
      << outside.status().ToString();
}

TEST(FileUtil, FilesAboveTheLimitAreRefusedBeforeReading) {
  const std::string path = TestDir("limit") + "/big.bin";
  std::ofstream(path) << std::string(100, 'x');
  const auto refused = ReadFileBytes(path, 99);
  EXPECT_EQ(refused.status().code(), StatusCode::kOutOfRange);
  EXPECT_NE(refused.status().message().find(path), std::string::npos);
  const auto read = ReadFileBytes(path, 100);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->size(), 100u);
  EXPECT_EQ(ReadFileText(path, 100).value(), std::string(100, 'x'));
  EXPECT_EQ(ReadFileBytes(path + ".absent").status().code(), StatusCode::kNotFound);
}

// A symlink at the destination is replaced, never written through.
TEST(FileUtil, WriteFileAtomicReplacesASymlinkInsteadOfFollowingIt) {
  const std::string dir = TestDir("symlink");
  const std::string victim = dir + "/victim.txt";
  std::ofstream(victim) << "keep me";
  fs::create_symlink(victim, dir + "/manifest.json");
  ASSERT_TRUE(WriteFileAtomic(dir + "/manifest.json", "new").ok());
  EXPECT_EQ(ReadFileText(victim, 100).value(), "keep me");
  EXPECT_FALSE(fs::is_symlink(dir + "/manifest.json"));
  EXPECT_EQ(ReadFileText(dir + "/manifest.json", 100).value(), "new");
}

// A write(2) that takes `room` bytes, then fails as on a full disk.
WriteCall FullAfter(size_t room) {
  return [room](int fd, const void* data, size_t size) mutable -> ssize_t {
    if (room == 0) {
      errno = ENOSPC;
      return -1;
    }
    const ssize_t n = ::write(fd, data, std::min(size, room));
    if (n > 0) room -= static_cast<size_t>(n);
    return n;
  };
}

// The writers' clean-up after a failed write(2): no temporary, no part of a
// record, the old content intact, and the errno in the message.
TEST(FileUtil, WritersLeaveNothingBehindWhenTheDiskIsFull) {
  const std::string dir = TestDir("full");
  const std::string path = dir + "/manifest.json";
  ASSERT_TRUE(WriteFileAtomic(path, "old").ok());
  const std::string text(100, 'n');
  const Status atomic = WriteFileAtomic(path, text.data(), text.size(), {}, FullAfter(30));
  EXPECT_EQ(atomic.code(), StatusCode::kIoError);
  EXPECT_EQ(atomic.message(), path + ": write failed (" + std::strerror(ENOSPC) + ")");
  EXPECT_EQ(ReadFileText(path, 100).value(), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1)
      << "a temporary was left";

  const std::string journal = dir + "/journal.jsonl";
  const int fd = ::open(journal.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  ASSERT_GE(fd, 0);
  int stages = 0;
  const std::string record = "{\"event\": \"fault\"}\n";
  EXPECT_TRUE(AppendDurably(fd, journal, record.data(), record.size(), [&](const char*) {
                ++stages;
              }).ok());
  EXPECT_EQ(stages, 1);
  const Status append = AppendDurably(fd, journal, record.data(), record.size(), {}, FullAfter(5));
  EXPECT_EQ(append.message(), IoErrorFromErrno(journal + ": write failed", ENOSPC).message());
  EXPECT_EQ(ReadFileText(journal, 100).value(), record) << "part of the record stayed";
  ::close(fd);
}

}  // namespace
}  // namespace hairrig
