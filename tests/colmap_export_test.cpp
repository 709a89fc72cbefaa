// The COLMAP text model that `hairrig calibrate` exports (calibration/calibration_io.h)
// read by COLMAP itself: `colmap model_converter` turns it into COLMAP's binary
// model and back to text, `colmap model_analyzer` counts it, and the cameras and
// image poses COLMAP writes are the calibration's, in COLMAP's conventions
// (pixel centres at +0.5, poses cam_from_object). Skipped when no `colmap` is
// on the PATH (Debian's package `colmap`, which scripts/install-deps installs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "calibration/calibration_io.h"
#include "tests/support/command_run.h"
#include "tests/support/synthetic_calibration.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using hairrig_test::CommandRun;
using hairrig_test::RunCommand;

// The first executable `name` on the PATH; empty if none.
std::string FindOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec) && access(candidate.c_str(), X_OK) == 0)
      return candidate.string();
  }
  return "";
}

std::string Quoted(const fs::path& p) { return "'" + p.string() + "'"; }

struct ColmapCamera {
  std::string model;
  int width = 0, height = 0;
  std::vector<double> params;
};

struct ColmapImage {
  Eigen::Vector4d qvec;  // w x y z
  Eigen::Vector3d tvec;
  int camera_id = 0;
};

struct ColmapText {
  std::map<int, ColmapCamera> cameras;        // by CAMERA_ID
  std::map<std::string, ColmapImage> images;  // by NAME
};

// cameras.txt and images.txt of a COLMAP text model (colmap.github.io/format.html):
// '#' lines are comments; each image line is followed by its line of 2D points.
ColmapText ReadColmapText(const fs::path& dir) {
  ColmapText model;
  std::ifstream cameras(dir / "cameras.txt");
  EXPECT_TRUE(cameras.good()) << dir / "cameras.txt";
  for (std::string line; std::getline(cameras, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    int id = 0;
    ColmapCamera camera;
    in >> id >> camera.model >> camera.width >> camera.height;
    for (double p; in >> p;) camera.params.push_back(p);
    EXPECT_FALSE(in.bad()) << line;
    model.cameras[id] = camera;
  }
  std::ifstream images(dir / "images.txt");
  EXPECT_TRUE(images.good()) << dir / "images.txt";
  for (std::string line; std::getline(images, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    int id = 0;
    ColmapImage image;
    std::string name;
    in >> id >> image.qvec[0] >> image.qvec[1] >> image.qvec[2] >> image.qvec[3] >> image.tvec[0] >>
        image.tvec[1] >> image.tvec[2] >> image.camera_id >> name;
    EXPECT_FALSE(in.fail()) << line;
    model.images[name] = image;
    std::getline(images, line);  // its 2D points
  }
  return model;
}

// What the export of `s` must say, in COLMAP's conventions.
ColmapText ExpectedModel(const hairrig_test::SyntheticCalibration& s) {
  ColmapText model;
  for (size_t c = 0; c < s.result.cameras.size(); ++c) {
    const CameraIntrinsics& k = s.result.cameras[c].intrinsics;
    ColmapCamera camera{k.k3 == 0 ? "OPENCV" : "FULL_OPENCV",
                        k.width_px,
                        k.height_px,
                        {k.fx_px, k.fy_px, k.cx_px + 0.5, k.cy_px + 0.5, k.k1, k.k2, k.p1, k.p2}};
    if (k.k3 != 0) camera.params.insert(camera.params.end(), {k.k3, 0, 0, 0});
    model.cameras[static_cast<int>(c) + 1] = camera;
  }
  const Rigid3d box_from_object = ObjectFromBox(s.result).Inverse();
  for (size_t f = 0; f < s.input.frames.size(); ++f) {
    if (!s.result.frames[f].solved) continue;
    const Rigid3d cam_from_object = s.result.frames[f].cam_from_box * box_from_object;
    const Eigen::Quaterniond& q = cam_from_object.rotation;
    model.images[fs::path(s.input.frames[f].name).filename().string()] = {
        Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()), cam_from_object.translation,
        s.input.frames[f].camera + 1};
  }
  return model;
}

// Equal within what 17 significant digits of text keep.
void ExpectSameValue(double read, double expected, const std::string& what) {
  EXPECT_NEAR(read, expected, 1e-12 * (1 + std::abs(expected))) << what;
}

TEST(ColmapExport, ColmapReadsTheExportedModelAsTheCalibration) {
  const std::string colmap = FindOnPath("colmap");
  if (colmap.empty())
    GTEST_SKIP()
        << "no `colmap` on the PATH (Debian package colmap, installed by scripts/install-deps): "
           "the COLMAP export cannot be read back by COLMAP here";
  const hairrig_test::SyntheticCalibration s = hairrig_test::MakeSyntheticCalibration();
  const fs::path dir = fs::path(::testing::TempDir()) / "colmap_export";
  fs::remove_all(dir);
  ASSERT_TRUE(WriteCalibration((dir / "calibration").string(), s.input, s.result).ok());
  const fs::path exported = dir / "calibration" / "colmap", binary = dir / "binary",
                 text = dir / "text";
  fs::create_directories(binary);  // COLMAP writes into existing folders only
  fs::create_directories(text);

  CommandRun r = RunCommand(colmap + " model_converter --input_path " + Quoted(exported) +
                            " --output_path " + Quoted(binary) + " --output_type BIN");
  ASSERT_EQ(r.exit_code, 0) << "COLMAP refused the exported model:\n" << r.output;
  r = RunCommand(colmap + " model_analyzer --path " + Quoted(binary));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ColmapText expected = ExpectedModel(s);
  EXPECT_EQ(expected.images.size(), s.input.frames.size() - 1) << "the failed view is not exported";
  for (const std::string& count : {"Cameras: " + std::to_string(expected.cameras.size()),
                                   "Registered images: " + std::to_string(expected.images.size())})
    EXPECT_NE(r.output.find(count), std::string::npos) << count << " in\n" << r.output;
  r = RunCommand(colmap + " model_converter --input_path " + Quoted(binary) + " --output_path " +
                 Quoted(text) + " --output_type TXT");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const ColmapText read = ReadColmapText(text);
  ASSERT_EQ(read.cameras.size(), expected.cameras.size());
  for (const auto& [id, camera] : expected.cameras) {
    ASSERT_TRUE(read.cameras.count(id)) << "camera " << id;
    const ColmapCamera& got = read.cameras.at(id);
    EXPECT_EQ(got.model, camera.model) << "camera " << id;
    EXPECT_EQ(got.width, camera.width) << "camera " << id;
    EXPECT_EQ(got.height, camera.height) << "camera " << id;
    ASSERT_EQ(got.params.size(), camera.params.size()) << "camera " << id;
    for (size_t k = 0; k < camera.params.size(); ++k)
      ExpectSameValue(got.params[k], camera.params[k],
                      "camera " + std::to_string(id) + " parameter " + std::to_string(k));
  }
  ASSERT_EQ(read.images.size(), expected.images.size());
  for (const auto& [name, image] : expected.images) {
    ASSERT_TRUE(read.images.count(name)) << name;
    const ColmapImage& got = read.images.at(name);
    EXPECT_EQ(got.camera_id, image.camera_id) << name;
    const double sign = got.qvec.dot(image.qvec) < 0 ? -1 : 1;  // q and -q are one rotation
    for (int k = 0; k < 4; ++k)
      ExpectSameValue(sign * got.qvec[k], image.qvec[k], name + " q[" + std::to_string(k) + "]");
    for (int k = 0; k < 3; ++k)
      ExpectSameValue(got.tvec[k], image.tvec[k], name + " t[" + std::to_string(k) + "] mm");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hairrig
