#include "reconstruction/colmap_model.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "tests/support/image_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

struct Model {
  fs::path dir;
  Model(const std::string& name, const std::string& cameras, const std::string& images) {
    dir = fs::temp_directory_path() / ("hairrig_colmap_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir / "images");
    std::ofstream(dir / "cameras.txt") << cameras;
    std::ofstream(dir / "images.txt") << images;
    for (const char* image : {"a.png", "b.png"}) Write(dir / "images" / image, PngClaiming(64, 48));
  }
  static void Write(const fs::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
  }
  Result<ReconstructionInput> Read(const std::string& masks_dir = "") const {
    return ReadColmapModel(dir.string(), ColmapReadOptions{(dir / "images").string(), masks_dir});
  }
};

const char* kImages =
    "# comment\n"
    "1 1 0 0 0 10 20 1000 1 a.png\n"
    "\n"
    "2 0.7071067811865476 0 0.7071067811865476 0 0 0 900 2 b.png\n"
    "100.0 200.0 -1\n";

TEST(ColmapModel, ReadsEachSupportedCameraModelWithPixelCentresMoved) {
  const Model m("models",
                "1 OPENCV 1200 1600 1750 1751 600.5 800.5 -0.03 0.012 0.0002 -0.0001\n"
                "2 SIMPLE_RADIAL 640 480 500 320 240 0.01\n",
                kImages);
  auto input = m.Read();
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  ASSERT_EQ(input->views.size(), 2u);
  const ReconstructionView& a = input->views[0];
  EXPECT_EQ(a.name, "a");
  EXPECT_DOUBLE_EQ(a.camera.fy_px, 1751);
  EXPECT_DOUBLE_EQ(a.camera.cx_px, 600.0);  // COLMAP's 600.5: the centre of pixel 600
  EXPECT_DOUBLE_EQ(a.camera.cy_px, 800.0);
  EXPECT_DOUBLE_EQ(a.camera.p2, -0.0001);
  EXPECT_NEAR((a.cam_from_object.translation - Eigen::Vector3d(10, 20, 1000)).norm(), 0, 1e-12);
  const ReconstructionView& b = input->views[1];
  EXPECT_DOUBLE_EQ(b.camera.fx_px, 500);
  EXPECT_DOUBLE_EQ(b.camera.fy_px, 500);
  EXPECT_DOUBLE_EQ(b.camera.k1, 0.01);
  EXPECT_NEAR(RadToDeg(Eigen::AngleAxisd(b.cam_from_object.rotation).angle()), 90, 1e-9);
}

TEST(ColmapModel, ErrorsNameTheFileAndLine) {
  const std::string ok_cameras =
      "1 PINHOLE 640 480 500 500 320 240\n2 PINHOLE 640 480 500 500 320 240\n";
  auto unknown = Model("unknown", "# c\n1 FISHEYE 640 480 500 320 240 0.1\n", kImages).Read();
  EXPECT_EQ(unknown.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(unknown.status().message().find("cameras.txt:2: camera model 'FISHEYE'"),
            std::string::npos)
      << unknown.status().message();
  auto short_line = Model("short", ok_cameras, "1 1 0 0 0 10 20 1000 1\n\n").Read();
  EXPECT_NE(short_line.status().message().find("images.txt:1: expected IMAGE_ID"),
            std::string::npos)
      << short_line.status().message();
  auto nan = Model("nan", "1 PINHOLE 640 480 nan 500 320 240\n", kImages).Read();
  EXPECT_NE(
      nan.status().message().find("cameras.txt:1: a camera parameter 'nan' is not a finite number"),
      std::string::npos)
      << nan.status().message();
  auto params = Model("params", "1 OPENCV 640 480 500 500 320 240\n", kImages).Read();
  EXPECT_NE(params.status().message().find("OPENCV takes 8 parameters, the line has 4"),
            std::string::npos)
      << params.status().message();
  auto no_camera = Model("nocam", "1 PINHOLE 640 480 500 500 320 240\n", kImages).Read();
  EXPECT_NE(no_camera.status().message().find("images.txt:4: camera 2 is not in cameras.txt"),
            std::string::npos)
      << no_camera.status().message();
  auto quaternion = Model("quat", ok_cameras, "1 2 0 0 0 0 0 1000 1 a.png\n\n").Read();
  EXPECT_NE(quaternion.status().message().find("has norm 2"), std::string::npos)
      << quaternion.status().message();
  auto missing = ReadColmapModel("/nonexistent-model", {"/nonexistent-model/images", ""});
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

TEST(ColmapModel, AMissingImageIsLeftOutAndNamed) {
  const Model m("missing", "1 PINHOLE 640 480 500 500 320 240\n2 PINHOLE 640 480 500 500 320 240\n",
                kImages);
  fs::remove(m.dir / "images" / "b.png");
  auto input = m.Read();
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  ASSERT_EQ(input->views.size(), 1u);
  ASSERT_EQ(input->left_out.size(), 1u);
  EXPECT_NE(input->left_out[0].find("b: "), std::string::npos) << input->left_out[0];
  fs::remove(m.dir / "images" / "a.png");
  EXPECT_EQ(m.Read().status().code(), StatusCode::kNotFound);
}

const char* kCameras = "1 PINHOLE 64 48 50 50 32 24\n2 PINHOLE 64 48 50 50 32 24\n";

// An image line of camera 1 and an empty points line.
std::string ImageLine(int id, const std::string& name) {
  return std::to_string(id) + " 1 0 0 0 0 0 1000 1 " + name + "\n\n";
}

void ExpectRefused(const Result<ReconstructionInput>& input, StatusCode code,
                   const std::vector<std::string>& parts) {
  ASSERT_FALSE(input.ok()) << "accepted " << input->views.size() << " views, the first "
                           << input->views[0].image_path;
  EXPECT_EQ(input.status().code(), code) << input.status().ToString();
  for (const std::string& part : parts) {
    EXPECT_NE(input.status().message().find(part), std::string::npos)
        << "no '" << part << "' in " << input.status().ToString();
  }
}

// An absolute NAME, one with '..' and a symlink out of the folder would each
// have an image outside the images folder read.
TEST(ColmapModel, NamesLeavingTheImagesFolderAreRefused) {
  const Model m("escape", kCameras, "");
  const fs::path outside = m.dir / "outside.png";
  Model::Write(outside, PngClaiming(64, 48));
  fs::create_symlink("../outside.png", m.dir / "images" / "link.png");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {outside.string(), "' is absolute"},
      {"../outside.png", "' has a '..' component"},
      {"sub/../../outside.png", "' has a '..' component"},
      {"link.png", "link.png leads to " + fs::canonical(outside).string() + ", outside "}};
  for (const auto& [name, why] : cases) {
    Model::Write(m.dir / "images.txt", ImageLine(1, "a.png") + ImageLine(2, name));
    ExpectRefused(m.Read(), StatusCode::kCorruptData,
                  {"images.txt:3: image NAME '" + name + "'", why});
  }
  Model::Write(m.dir / "images.txt", ImageLine(1, "a\x01.png"));
  ExpectRefused(m.Read(), StatusCode::kCorruptData,
                {"images.txt:1: image NAME has a control character (byte 1)"});
  // A symlink that stays inside is followed; the view reads its target.
  fs::create_symlink("a.png", m.dir / "images" / "alias.png");
  Model::Write(m.dir / "images.txt", ImageLine(1, "alias.png"));
  const auto inside = m.Read();
  ASSERT_TRUE(inside.ok()) << inside.status().ToString();
  EXPECT_EQ(inside->views[0].image_path, fs::canonical(m.dir / "images" / "a.png").string());
  EXPECT_EQ(inside->views[0].name, "alias");

  // A mask is looked for inside the masks folder only.
  fs::create_directories(m.dir / "masks");
  fs::create_symlink("../outside.png", m.dir / "masks" / "a.png");
  Model::Write(m.dir / "images.txt", ImageLine(1, "a.png"));
  ExpectRefused(m.Read((m.dir / "masks").string()), StatusCode::kCorruptData,
                {"images.txt:1: image NAME 'a.png', its mask: ", ", outside "});
}

// A FIFO named by images.txt, or in place of images.txt, is refused without
// being opened for a blocking read (that waits for a writer forever).
TEST(ColmapModel, AFifoIsRefusedAtOnce) {
  const Model m("fifo", kCameras, ImageLine(1, "a.png") + ImageLine(2, "b.png"));
  const fs::path fifo = m.dir / "images" / "b.png";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  ExpectRefused(m.Read(), StatusCode::kInvalidArgument,
                {"images.txt:3: image NAME 'b.png': ", "b.png is a FIFO (named pipe)"});
  fs::remove(fifo);
  Model::Write(fifo, PngClaiming(64, 48));
  fs::remove(m.dir / "images.txt");
  ASSERT_EQ(::mkfifo((m.dir / "images.txt").c_str(), 0600), 0);
  ExpectRefused(m.Read(), StatusCode::kInvalidArgument, {"images.txt is a FIFO (named pipe)"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

// A PNG claiming 100000 x 100000 px is refused from its header, before
// anything decodes it (OpenCV's size check throws).
TEST(ColmapModel, ImagesAreCheckedFromTheirHeaders) {
  const Model m("huge", kCameras, kImages);
  Model::Write(m.dir / "images" / "b.png", PngClaiming(100000, 100000));
  ExpectRefused(m.Read(), StatusCode::kOutOfRange,
                {"images.txt:4: image NAME 'b.png': ",
                 "b.png: its PNG header claims 100000 x 100000 px, more than the 100000000 px"});
  Model::Write(m.dir / "images" / "b.png", "not an image");
  ExpectRefused(m.Read(), StatusCode::kCorruptData,
                {"images.txt:4: image NAME 'b.png': ", "not an image format"});
}

TEST(ColmapModel, RepeatsAreRefusedAtTheFirst) {
  const Model m("repeats", kCameras, "");
  fs::create_directories(m.dir / "images" / "left");
  Model::Write(m.dir / "images" / "left" / "a.png", PngClaiming(64, 48));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {ImageLine(1, "a.png") + ImageLine(1, "b.png"), "images.txt:3: IMAGE_ID 1 repeats line 1"},
      {ImageLine(1, "a.png") + ImageLine(2, "b.png") + ImageLine(3, "a.png"),
       "images.txt:5: image NAME 'a.png' repeats line 1"},
      {ImageLine(1, "a.png") + ImageLine(2, "./a.png"),
       "images.txt:3: image NAME './a.png' repeats line 1"},
      {ImageLine(1, "a.png") + ImageLine(2, "left/a.png"),
       "images.txt:3: image NAME 'left/a.png' gives the view name 'a' of line 1 too"}};
  for (const auto& [images, message] : cases) {
    Model::Write(m.dir / "images.txt", images);
    ExpectRefused(m.Read(), StatusCode::kCorruptData, {message});
  }
  Model::Write(m.dir / "images.txt", ImageLine(1, "a.png"));
  Model::Write(m.dir / "cameras.txt",
               "1 PINHOLE 64 48 50 50 32 24\n# again\n1 PINHOLE 640 480 500 500 320 240\n");
  ExpectRefused(m.Read(), StatusCode::kCorruptData, {"cameras.txt:3: CAMERA_ID 1 repeats line 1"});
}

// 12,000 copies of one entry: refused at the second, not reconstructed for minutes.
TEST(ColmapModel, ThousandsOfRepeatsAreRefusedQuickly) {
  std::string images;
  for (int k = 0; k < 12000; ++k) images += ImageLine(1, "a.png");
  const Model m("many", kCameras, images);
  const auto start = std::chrono::steady_clock::now();
  ExpectRefused(m.Read(), StatusCode::kCorruptData, {"images.txt:3: IMAGE_ID 1 repeats line 1"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

}  // namespace
}  // namespace hairrig
