#include "core/file_util.h"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
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
      {dir, "is a folder"}, {fifo, "is a FIFO"}, {"/dev/zero", "is a character device"},
      {zero_link, "is a character device"}};
  for (const auto& [path, kind] : cases) {
    const auto bytes = ReadFileBytes(path);
    EXPECT_EQ(bytes.status().code(), StatusCode::kInvalidArgument) << path;
    EXPECT_NE(bytes.status().message().find(path + " " + kind), std::string::npos) << bytes.status().ToString();
    EXPECT_FALSE(ReadJsonFile(path).ok()) << path;
    EXPECT_FALSE(ConfigNode::LoadFile(path).ok()) << path;
    EXPECT_FALSE(Sha256OfFile(path).ok()) << path;
  }
  EXPECT_FALSE(ReadStrands(zero_link).ok());
  EXPECT_FALSE(ReadFileBytes("/dev/urandom").ok());
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

}  // namespace
}  // namespace hairrig
