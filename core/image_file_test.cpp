#include "core/image_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "tests/support/image_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string TestDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("hairrig_image_file_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

Result<ImageHeader> Parse(const std::string& bytes, const std::string& name = "x") {
  return ParseImageHeader(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), name);
}

void ExpectSize(const Result<ImageHeader>& header, const std::string& format, uint64_t width,
                uint64_t height) {
  ASSERT_TRUE(header.ok()) << format << ": " << header.status().ToString();
  EXPECT_EQ(header->format, format);
  EXPECT_EQ(header->width_px, width) << format;
  EXPECT_EQ(header->height_px, height) << format;
}

// `image` encoded by OpenCV as `ext`; empty when OpenCV was built without that codec.
std::vector<uint8_t> Encode(const std::string& ext, const cv::Mat& image,
                            const std::vector<int>& params = {}) {
  std::vector<uint8_t> bytes;
  try {
    if (!cv::imencode(ext, image, bytes, params)) bytes.clear();
  } catch (const cv::Exception&) {
    bytes.clear();
  }
  return bytes;
}

// OpenCV's own encoders, 37 x 23 px so that width and height cannot be swapped unseen.
TEST(ImageFile, HeadersOfEveryFormatOpenCvWritesGiveTheirSize) {
  const cv::Mat image(23, 37, CV_8UC3, cv::Scalar(10, 200, 30));
  cv::Mat floats;
  image.convertTo(floats, CV_32FC3, 1.0 / 255);
  struct Case {
    std::string ext, format;
    cv::Mat image;
    std::vector<int> params;
  };
  const std::vector<Case> cases = {
      {".png", "PNG", image, {}},
      {".jpg", "JPEG", image, {}},
      {".jpg", "JPEG", image, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {".tiff", "TIFF", image, {}},
      {".bmp", "BMP", image, {}},
      {".ppm", "PNM", image, {}},
      {".pgm", "PNM", cv::Mat(23, 37, CV_8UC1, cv::Scalar(7)), {}},
      {".pfm", "PNM", floats, {}},
      {".webp", "WebP", image, {}},                               // lossless: VP8L
      {".webp", "WebP", image, {cv::IMWRITE_WEBP_QUALITY, 80}}};  // lossy: VP8
  int parsed = 0;
  for (const Case& c : cases) {
    const std::vector<uint8_t> bytes = Encode(c.ext, c.image, c.params);
    if (bytes.empty() && c.format == "WebP") continue;  // an OpenCV without libwebp
    ASSERT_FALSE(bytes.empty()) << c.ext;
    ExpectSize(ParseImageHeader(bytes.data(), bytes.size(), "x" + c.ext), c.format, 37, 23);
    ++parsed;
  }
  EXPECT_GE(parsed, 8);
}

// Layouts OpenCV does not write: a big-endian TIFF, a JPEG whose frame header
// comes after 120 kB of metadata, a BMP stored top-down, a PNM with a comment.
TEST(ImageFile, HandWrittenHeadersGiveTheirSize) {
  // MM, IFD at 8: 2 entries, ImageWidth SHORT 300, ImageLength LONG 70000.
  const std::string tiff(
      "MM\0*\0\0\0\x08\0\x02"
      "\x01\x00\0\x03\0\0\0\x01\x01\x2c\0\0"
      "\x01\x01\0\x04\0\0\0\x01\0\x01\x11\x70"
      "\0\0\0\0",
      8 + 2 + 24 + 4);
  ExpectSize(Parse(tiff), "TIFF", 300, 70000);

  std::string jpeg("\xFF\xD8", 2);
  // Two APP1 segments of 60000 bytes, then SOF2 (progressive) of 4000 x 3000 px.
  for (int k = 0; k < 2; ++k) jpeg += std::string("\xFF\xE1\xEA\x62", 4) + std::string(60000, '\0');
  jpeg += std::string("\xFF\xC2\x00\x11\x08\x0B\xB8\x0F\xA0", 9);
  jpeg += std::string(20, '\0');
  ExpectSize(Parse(jpeg), "JPEG", 4000, 3000);
  const std::string jpeg_file = WriteBytes(TestDir("jpeg") + "/metadata.jpg", jpeg);
  ExpectSize(ReadImageHeader(jpeg_file), "JPEG", 4000, 3000);

  std::string bmp("BM", 2);
  // BITMAPINFOHEADER, 320 x -240 px (rows top-down).
  bmp += std::string(12, '\0') + std::string("\x28\0\0\0", 4);
  bmp += std::string("\x40\x01\0\0", 4) + std::string("\x10\xFF\xFF\xFF", 4);
  ExpectSize(Parse(bmp), "BMP", 320, 240);

  ExpectSize(Parse("P6\n# from a scanner\n 640\t480\n255\n"), "PNM", 640, 480);
  ExpectSize(Parse(PngClaiming(100000, 100000)), "PNG", 100000, 100000);
}

TEST(ImageFile, BrokenHeadersAreCorruptDataNamingTheFile) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {PngClaiming(640, 480).substr(0, 20), "ends inside its PNG IHDR chunk"},
      {PngClaiming(0, 480), "PNG header claims 0 x 480 px"},
      {"GIF89a....", "not an image format this project reads"},
      {"", "not an image format this project reads"},
      {std::string("\xFF\xD8\xFF\xDA\0\x02", 6), "JPEG without a frame header"},
      {std::string("II*\0\x08\0\0\0\0\0\0\0\0\0\0\0", 16), "TIFF without ImageWidth"},
      {"P5\n# no size\n", "PNM header without its width and height"}};
  for (const auto& [bytes, what] : cases) {
    const auto header = Parse(bytes, "view_07.png");
    EXPECT_EQ(header.status().code(), StatusCode::kCorruptData) << what;
    EXPECT_NE(header.status().message().find("view_07.png: "), std::string::npos)
        << header.status().ToString();
    EXPECT_NE(header.status().message().find(what), std::string::npos)
        << header.status().ToString();
  }
}

// A PNG claiming 100000 x 100000 px is refused from its header: OpenCV's own
// size check throws, which would end the process (std::terminate).
TEST(ImageFile, AnImageClaimingTooManyPixelsIsRefusedBeforeDecoding) {
  const std::string path = WriteBytes(TestDir("huge") + "/huge.png", PngClaiming(100000, 100000));
  const std::string claim = path + ": its PNG header claims 100000 x 100000 px, more than the";
  const Result<cv::Mat> read = ReadImageFile(path, cv::IMREAD_COLOR);
  EXPECT_EQ(read.status().code(), StatusCode::kOutOfRange);
  EXPECT_NE(read.status().message().find(claim), std::string::npos) << read.status().ToString();
  const Status checked = CheckImageFile(path);
  EXPECT_EQ(checked.code(), StatusCode::kOutOfRange);
  EXPECT_NE(checked.message().find(claim), std::string::npos) << checked.ToString();
  EXPECT_NE(checked.message().find("(100 megapixels)"), std::string::npos) << checked.ToString();
  EXPECT_TRUE(CheckImageFile(path, uint64_t{100000} * 100000).ok());
  EXPECT_FALSE(CheckImageFile(path, uint64_t{100000} * 100000 - 1).ok());

  // Past this project's limit, OpenCV's own size check (1 gigapixel) throws
  // cv::Exception; the exception becomes a Status carrying its text.
  const Result<cv::Mat> thrown =
      ReadImageFile(path, cv::IMREAD_COLOR, std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(thrown.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(thrown.status().message().find(path + ": cannot be decoded ("), std::string::npos)
      << thrown.status().ToString();
  EXPECT_NE(thrown.status().message().find("CV_IO_MAX_IMAGE_PIXELS"), std::string::npos)
      << thrown.status().ToString();
}

// A FIFO (opening it for reading waits for a writer) and a device (/dev/zero
// never ends) are refused without blocking.
TEST(ImageFile, OnlyRegularFilesAreOpened) {
  const std::string dir = TestDir("kinds");
  const std::string fifo = dir + "/view.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string zero_link = dir + "/zero.png";
  fs::create_symlink("/dev/zero", zero_link);
  const auto start = std::chrono::steady_clock::now();
  for (const std::string& path : {fifo, zero_link, dir}) {
    EXPECT_EQ(ReadImageFile(path, cv::IMREAD_COLOR).status().code(), StatusCode::kInvalidArgument)
        << path;
    const Status checked = CheckImageFile(path);
    EXPECT_EQ(checked.code(), StatusCode::kInvalidArgument) << path;
    EXPECT_NE(checked.message().find(path + " is "), std::string::npos) << checked.ToString();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  const Result<cv::Mat> missing = ReadImageFile(dir + "/absent.png", cv::IMREAD_COLOR);
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_EQ(missing.status().message(), dir + "/absent.png is missing");
}

size_t OpenDescriptors() {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

// ReadImageHeader closes the file whatever the header gives: a size, a
// truncated or unknown format.
TEST(ImageFile, ReadingHeadersLeavesNoDescriptorOpen) {
  const std::string dir = TestDir("descriptors");
  const std::vector<std::string> files = {
      WriteBytes(dir + "/good.png", PngClaiming(640, 480)),
      WriteBytes(dir + "/cut.png", PngClaiming(640, 480).substr(0, 20)),
      WriteBytes(dir + "/text.png", "not an image")};
  const size_t before = OpenDescriptors();
  for (int round = 0; round < 20; ++round)
    for (const std::string& file : files) (void)ReadImageHeader(file);
  EXPECT_EQ(OpenDescriptors(), before);
}

TEST(ImageFile, ReadsWhatItWrote) {
  const std::string path = TestDir("round_trip") + "/view.png";
  cv::Mat image(23, 37, CV_8UC3, cv::Scalar(10, 200, 30));
  image.at<cv::Vec3b>(5, 30) = cv::Vec3b(1, 2, 3);
  ASSERT_TRUE(WriteImageAtomic(path, image).ok());
  ExpectSize(ReadImageHeader(path), "PNG", 37, 23);
  const Result<cv::Mat> read = ReadImageFile(path, cv::IMREAD_UNCHANGED);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(cv::norm(*read, image, cv::NORM_INF), 0);
  const Result<cv::Mat> grey = ReadImageFile(path, cv::IMREAD_GRAYSCALE);
  ASSERT_TRUE(grey.ok()) << grey.status().ToString();
  EXPECT_EQ(grey->type(), CV_8UC1);
  const std::string text = WriteBytes(path + ".txt", "not an image");
  EXPECT_EQ(ReadImageFile(text, cv::IMREAD_COLOR).status().code(), StatusCode::kCorruptData);
}

}  // namespace
}  // namespace hairrig
