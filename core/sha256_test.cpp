#include "core/sha256.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/file_util.h"

namespace hairrig {
namespace {

// Test vectors from FIPS 180-4's examples (NIST CSRC "SHA256.pdf").
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(Sha256Hex("", 0), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc", 3),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  const std::string two_blocks = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
  EXPECT_EQ(Sha256Hex(two_blocks.data(), two_blocks.size()),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  const std::string million_a(1000000, 'a');
  EXPECT_EQ(Sha256Hex(million_a.data(), million_a.size()),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, IncrementalEqualsOneShotForEveryChunking) {
  std::mt19937 rng(5);
  std::vector<uint8_t> data(1000);
  for (auto& b : data) b = static_cast<uint8_t>(rng());
  const std::string expected = Sha256Hex(data.data(), data.size());
  for (size_t chunk : {1, 3, 55, 56, 63, 64, 65, 127, 999}) {
    Sha256 hash;
    for (size_t at = 0; at < data.size(); at += chunk)
      hash.Update(data.data() + at, std::min(chunk, data.size() - at));
    EXPECT_EQ(hash.HexDigest(), expected) << "chunk " << chunk;
  }
}

// Agrees with coreutils' sha256sum, an independent implementation.
TEST(Sha256, MatchesSha256sumOnAFile) {
  const std::string path = ::testing::TempDir() + "/sha256_test.bin";
  std::vector<uint8_t> data(300000);
  std::mt19937 rng(9);
  for (auto& b : data) b = static_cast<uint8_t>(rng());
  ASSERT_TRUE(WriteFileAtomic(path, data.data(), data.size()).ok());
  auto ours = Sha256OfFile(path);
  ASSERT_TRUE(ours.ok()) << ours.status().ToString();
  std::FILE* pipe = ::popen(("sha256sum '" + path + "'").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char out[65] = {};
  ASSERT_EQ(std::fread(out, 1, 64, pipe), 64u);
  ::pclose(pipe);
  EXPECT_EQ(*ours, std::string(out));
  EXPECT_FALSE(Sha256OfFile(path + ".absent").ok());
}

}  // namespace
}  // namespace hairrig
