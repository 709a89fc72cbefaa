#include "core/strand_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include "core/file_util.h"
#include "tests/support/strand_test_util.h"

namespace hairrig {
namespace {

TEST(StrandIo, WriteAndReadFilesThroughTheExtension) {
  StrandSet set;
  set.AddStrand({{0, 0, 0}, {1, 2, 3}, {4.5f, 5, 6}});
  set.AddStrand({{7, 8, 9}});
  const std::string dir = ::testing::TempDir();
  for (const std::string ext : {".hair", ".data", ".ply"}) {
    const std::string path = dir + "/strands" + ext;
    ASSERT_TRUE(WriteStrands(path, set).ok());
    auto back = ReadStrands(path);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ExpectSameGeometry(set, *back);
  }
  EXPECT_FALSE(WriteStrands(dir + "/strands.obj", set).ok());
}

// A file cut at any byte gives an error (or, for ascii PLY cut inside the
// final newline, the same geometry), never a crash or a huge allocation.
TEST(StrandIo, CorruptCountsDoNotAllocateHugeBuffers) {
  std::vector<uint8_t> data = {0xff, 0xff, 0xff, 0x7f, 1, 0, 0, 0};  // 2^31-1 strands
  auto set = DecodeStrands(data, StrandFormat::kData, "huge.data");
  EXPECT_EQ(set.status().code(), StatusCode::kCorruptData);
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nelement strand 1\nproperty ushort nsegs\nend_header\n";
  auto p = DecodeStrands(std::vector<uint8_t>(ply.begin(), ply.end()), StrandFormat::kPlyBinary,
                         "huge.ply");
  EXPECT_EQ(p.status().code(), StatusCode::kCorruptData);
}

// A bare 128-byte .hair header claiming 2^32-1 strands of one point each: refused
// from the header alone (it used to allocate 16 GB of counts first).
TEST(StrandIo, HairHeaderCountsAreCheckedBeforeAllocating) {
  std::vector<uint8_t> header(128, 0);
  std::memcpy(header.data(), "HAIR", 4);
  const uint32_t huge = 0xffffffffu, points_only = 2;
  std::memcpy(header.data() + 4, &huge, 4);  // strands
  std::memcpy(header.data() + 8, &huge, 4);  // points
  std::memcpy(header.data() + 12, &points_only, 4);
  auto set = DecodeStrands(header, StrandFormat::kHair, "huge.hair");
  EXPECT_EQ(set.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(set.status().message().find("huge.hair: header claims 4294967295 strands"),
            std::string::npos)
      << set.status().ToString();
}

// An element without properties takes no bytes per record: its count is
// refused by the header check (it used to loop over 9e18 empty records).
TEST(StrandIo, PlyElementWithRecordsButNoPropertiesIsRefused) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement junk 9000000000000000000\nelement vertex 1\nproperty float "
      "x\n"
      "property float y\nproperty float z\nelement strand 1\nproperty int nsegs\nend_header\n0 0 "
      "0\n0\n";
  auto set = DecodeStrands(std::vector<uint8_t>(ply.begin(), ply.end()), StrandFormat::kPlyAscii,
                           "junk.ply");
  EXPECT_EQ(set.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(set.status().message().find("element 'junk'"), std::string::npos)
      << set.status().ToString();
}

// Counts of all elements together are bounded by the body, not each alone.
TEST(StrandIo, PlyElementCountsAreBoundedTogether) {
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nelement strand 5\nproperty uint nsegs\nend_header\n" +
      std::string(24 + 4, '\0');
  auto set = DecodeStrands(std::vector<uint8_t>(ply.begin(), ply.end()), StrandFormat::kPlyBinary,
                           "short.ply");
  EXPECT_EQ(set.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(set.status().message().find("element 'strand' claims 5 records"), std::string::npos)
      << set.status().ToString();
}

TEST(StrandIo, NanPointsAreRefused) {
  StrandSet set;
  set.AddStrand({{0, 0, 0}, {std::nanf(""), 0, 0}});
  auto bytes = EncodeStrands(set, StrandFormat::kData);
  EXPECT_FALSE(bytes.ok());
  StrandSet ok;
  ok.AddStrand({{0, 0, 0}, {1, 0, 0}});
  auto good = EncodeStrands(ok, StrandFormat::kData);
  std::vector<uint8_t> poisoned = *good;
  const float nan = std::nanf("");
  std::memcpy(poisoned.data() + 8, &nan, 4);
  auto back = DecodeStrands(poisoned, StrandFormat::kData, "nan.data");
  EXPECT_EQ(back.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(back.status().message().find("not finite"), std::string::npos);
}

// Replaces every occurrence of `from` in `bytes` by `to` (same length or text).
std::vector<uint8_t> Replaced(std::vector<uint8_t> bytes, const std::string& from,
                              const std::string& to) {
  std::string text(bytes.begin(), bytes.end());
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return std::vector<uint8_t>(text.begin(), text.end());
}

std::string FloatBytes(float v) {
  std::string out(4, '\0');
  std::memcpy(out.data(), &v, 4);
  return out;
}

// A coordinate near float's largest (3.4e38), where differences between
// points overflow, is refused on reading in every format, naming the file, the
// strand and the vertex in it; so is an infinite one.
TEST(StrandIo, CoordinatesThatOverflowAreRefusedWithStrandAndVertex) {
  constexpr float kMarker = 1234.5f;  // appears once in each encoding
  StrandSet set;
  set.AddStrand({{0, 0, 0}, {1, 0, 0}});
  set.AddStrand({{0, 1, 0}, {1, 1, 0}, {2, 1, 0}});
  set.AddStrand({{0, 2, 0}, {1, 2, 0}, {2, 2, kMarker}, {3, 2, 0}});
  for (const StrandFormat format : {StrandFormat::kData, StrandFormat::kHair,
                                    StrandFormat::kPlyBinary, StrandFormat::kPlyAscii}) {
    auto good = EncodeStrands(set, format);
    ASSERT_TRUE(good.ok()) << good.status().ToString();
    const bool ascii = format == StrandFormat::kPlyAscii;
    const std::string name = std::string("big.") + StrandFormatName(format);
    const struct {
      float binary;
      const char* text;
      const char* expected;
    } cases[] = {{3.4e38f, "3.4e38", "overflow"},
                 {-2e9f, "-2e9", "overflow"},
                 {std::numeric_limits<float>::infinity(), "1e39", "not finite"}};
    for (const auto& bad : cases) {
      const auto bytes = Replaced(*good, ascii ? "1234.5" : FloatBytes(kMarker),
                                  ascii ? bad.text : FloatBytes(bad.binary));
      ASSERT_NE(bytes, *good) << name;
      const auto read = DecodeStrands(bytes, format, name);
      ASSERT_FALSE(read.ok()) << name << " with " << bad.text;
      EXPECT_EQ(read.status().code(), StatusCode::kCorruptData);
      EXPECT_NE(read.status().message().find(name + ": strand 2 vertex 2 (point 7): z "),
                std::string::npos)
          << read.status().ToString();
      EXPECT_NE(read.status().message().find(bad.expected), std::string::npos)
          << read.status().ToString();
    }
    // Large but harmless (1000 km) is read.
    const auto far =
        Replaced(*good, ascii ? "1234.5" : FloatBytes(kMarker), ascii ? "1e9" : FloatBytes(1e9f));
    EXPECT_TRUE(DecodeStrands(far, format, name).ok()) << name;
  }
}

}  // namespace
}  // namespace hairrig
