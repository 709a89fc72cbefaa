#include <gtest/gtest.h>

#include <filesystem>

#include "core/file_util.h"
#include "core/strand_io.h"
#include "tests/support/strand_test_util.h"

namespace hairrig {
namespace {

const std::string kStrandDir = "../shared/data/strands/";

bool HaveShared() { return std::filesystem::exists(kStrandDir + "Bangs_100.hair"); }

#define REQUIRE_SHARED()                                                                    \
  if (!HaveShared()) {                                                                      \
    GTEST_SKIP() << "../shared/data/strands is absent beside the repository: golden files " \
                    "cannot be checked here";                                               \
  }

TEST(StrandIo, GoldenFilesAgreeWithEachOtherAndTheReadme) {
  REQUIRE_SHARED();
  auto hair = ReadStrands(kStrandDir + "Bangs_100.hair");
  auto data = ReadStrands(kStrandDir + "Bangs_100.data");
  auto ply_bin = ReadStrands(kStrandDir + "Bangs_100_binary.ply");
  auto ply_ascii = ReadStrands(kStrandDir + "Bangs_100_ascii.ply");
  ASSERT_TRUE(hair.ok()) << hair.status().ToString();
  ASSERT_TRUE(data.ok()) << data.status().ToString();
  ASSERT_TRUE(ply_bin.ok()) << ply_bin.status().ToString();
  ASSERT_TRUE(ply_ascii.ok()) << ply_ascii.status().ToString();
  EXPECT_EQ(hair->num_strands(), 100u);
  EXPECT_EQ(hair->num_points(), 1165u);
  ExpectSameGeometry(*hair, *data);
  ExpectSameGeometry(*hair, *ply_bin);
  ExpectSameGeometry(*hair, *ply_ascii);
  const auto lengths = hair->StrandLengths();
  const auto [lo, hi] = std::minmax_element(lengths.begin(), lengths.end());
  EXPECT_NEAR(*lo, 10.7, 0.1);
  EXPECT_NEAR(*hi, 243.0, 1.0);
  EXPECT_EQ(ply_bin->colors.size(), ply_bin->num_points());
}

TEST(StrandIo, BinaryGoldenFilesRoundTripByteForByte) {
  REQUIRE_SHARED();
  for (const std::string name : {"Bangs_100.hair", "Bangs_100.data"}) {
    auto bytes = ReadFileBytes(kStrandDir + name);
    ASSERT_TRUE(bytes.ok());
    auto format = StrandFormatFromPath(name);
    auto set = DecodeStrands(*bytes, *format, name);
    ASSERT_TRUE(set.ok()) << set.status().ToString();
    auto again = EncodeStrands(*set, *format);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(*again, *bytes) << name;
  }
}

TEST(StrandIo, EveryFormatConvertsToEveryOtherWithoutLoss) {
  REQUIRE_SHARED();
  for (const std::string name : {"Bangs_100_binary.ply", "Curly_100.ply"}) {
    auto original = ReadStrands(kStrandDir + name);
    ASSERT_TRUE(original.ok()) << original.status().ToString();
    for (StrandFormat f : {StrandFormat::kHair, StrandFormat::kData, StrandFormat::kPlyBinary,
                           StrandFormat::kPlyAscii}) {
      auto bytes = EncodeStrands(*original, f);
      ASSERT_TRUE(bytes.ok());
      auto back = DecodeStrands(*bytes, f, "converted");
      ASSERT_TRUE(back.ok()) << StrandFormatName(f) << ": " << back.status().ToString();
      ExpectSameGeometry(*original, *back);
      if (f != StrandFormat::kData) {
        EXPECT_EQ(back->colors, original->colors) << StrandFormatName(f);
      }
    }
  }
}

TEST(StrandIo, TruncationAtEveryByteOffsetIsAnErrorNotACrash) {
  REQUIRE_SHARED();
  for (const std::string name :
       {"Bangs_100.hair", "Bangs_100.data", "Bangs_100_binary.ply", "Bangs_100_ascii.ply"}) {
    auto bytes = ReadFileBytes(kStrandDir + name);
    ASSERT_TRUE(bytes.ok());
    auto format = StrandFormatFromPath(name);
    auto full = DecodeStrands(*bytes, *format, name);
    ASSERT_TRUE(full.ok());
    size_t accepted = 0;
    for (size_t cut = 0; cut < bytes->size(); ++cut) {
      const std::vector<uint8_t> part(bytes->begin(),
                                      bytes->begin() + static_cast<std::ptrdiff_t>(cut));
      auto set = DecodeStrands(part, *format, name);
      if (set.ok()) {
        ++accepted;
        ExpectSameGeometry(*full, *set);
      } else {
        ASSERT_EQ(set.status().code(), StatusCode::kCorruptData) << set.status().ToString();
        ASSERT_NE(set.status().message().find(name), std::string::npos);
      }
    }
    std::printf("%s: %zu truncations, %zu accepted with identical geometry\n", name.c_str(),
                bytes->size(), accepted);
    if (name.find("ascii") == std::string::npos) {  // only text can lose just a final newline
      EXPECT_EQ(accepted, 0u) << name;
    }
    EXPECT_LE(accepted, 1u) << name;
  }
}

}  // namespace
}  // namespace hairrig
