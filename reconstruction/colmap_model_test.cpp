#include "reconstruction/colmap_model.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
    for (const char* image : {"a.jpg", "b.jpg"}) std::ofstream(dir / "images" / image) << "x";
  }
  Result<ReconstructionInput> Read() const {
    return ReadColmapModel(dir.string(), ColmapReadOptions{(dir / "images").string(), ""});
  }
};

const char* kImages =
    "# comment\n"
    "1 1 0 0 0 10 20 1000 1 a.jpg\n"
    "\n"
    "2 0.7071067811865476 0 0.7071067811865476 0 0 0 900 2 b.jpg\n"
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
  auto quaternion = Model("quat", ok_cameras, "1 2 0 0 0 0 0 1000 1 a.jpg\n\n").Read();
  EXPECT_NE(quaternion.status().message().find("has norm 2"), std::string::npos)
      << quaternion.status().message();
  auto missing = ReadColmapModel("/nonexistent-model", {});
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

TEST(ColmapModel, AMissingImageIsLeftOutAndNamed) {
  const Model m("missing", "1 PINHOLE 640 480 500 500 320 240\n2 PINHOLE 640 480 500 500 320 240\n",
                kImages);
  fs::remove(m.dir / "images" / "b.jpg");
  auto input = m.Read();
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  ASSERT_EQ(input->views.size(), 1u);
  ASSERT_EQ(input->left_out.size(), 1u);
  EXPECT_NE(input->left_out[0].find("b: "), std::string::npos) << input->left_out[0];
  fs::remove(m.dir / "images" / "a.jpg");
  EXPECT_EQ(m.Read().status().code(), StatusCode::kNotFound);
}

}  // namespace
}  // namespace hairrig
