// SolveIntrinsicsFromViews on synthetic views of etc/calib-box.yaml: against
// the true camera, and against OpenCV's calibrateCamera on the same planes.
#include "calibration/intrinsics_from_views.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <opencv2/calib3d.hpp>
#include <random>

namespace hairrig {
namespace {

constexpr int kWidth = 1200, kHeight = 1600;

CameraIntrinsics TrueCamera() {
  const double params[CameraIntrinsics::kNumParams] = {2200, 2190,   612,     785, -0.08,
                                                       0.12, 0.0006, -0.0004, 0};
  return CameraIntrinsics::FromParams(params, kWidth, kHeight);
}

// 12 views around the box at 1.2 m, tilted up and down, corners with 0.1 px
// noise (rounded to float, as calibrateCamera takes them); only tags whose
// corners all land in the image and whose face looks at the camera.
std::vector<ViewObservations> SyntheticViews(const CalibBox& box, const CameraIntrinsics& camera,
                                             uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.1);
  std::vector<ViewObservations> views;
  for (int v = 0; v < 12; ++v) {
    const double yaw = 2 * M_PI * v / 12 + 0.2, pitch = (v % 2 ? 0.35 : -0.25);
    const Eigen::Vector3d eye =
        1200 * Eigen::Vector3d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                               std::sin(pitch));
    const Rigid3d cam_from_box = LookAt(eye, Eigen::Vector3d::Zero());
    ViewObservations view;
    for (const BoxTag& tag : box.tags) {
      const Eigen::Vector3d normal = box.faces[static_cast<size_t>(tag.face)].normal_box;
      if (normal.dot(eye - tag.center_box_mm) <= 0) continue;
      TagObservation seen{tag.id, {}, tag.corners_box_mm};
      bool inside = true;
      for (size_t k = 0; k < 4; ++k) {
        const Eigen::Vector2d uv = Project(camera, cam_from_box * tag.corners_box_mm[k]);
        inside = inside && uv.x() > 0 && uv.y() > 0 && uv.x() < kWidth - 1 && uv.y() < kHeight - 1;
        seen.corners_px[k] =
            (uv + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>().cast<double>();
      }
      if (inside) view.tags.push_back(seen);
    }
    views.push_back(view);
  }
  return views;
}

// calibrateCamera (CALIB_FIX_K3) on the same face planes as SolveIntrinsicsFromViews builds.
CameraIntrinsics OpenCvOnSamePlanes(const std::vector<ViewObservations>& views, const CalibBox& box,
                                    double* rms) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const ViewObservations& view : views) {
    std::map<int, std::vector<const TagObservation*>> by_face;
    for (const TagObservation& tag : view.tags) by_face[box.FindTag(tag.id)->face].push_back(&tag);
    for (const auto& [face_index, tags] : by_face) {
      if (tags.size() < 2) continue;
      const BoxFace& face = box.faces[static_cast<size_t>(face_index)];
      object.emplace_back();
      image.emplace_back();
      for (const TagObservation* tag : tags) {
        for (size_t k = 0; k < 4; ++k) {
          const Eigen::Vector3d rel = tag->corners_box_mm[k] - face.center_box_mm;
          object.back().emplace_back(static_cast<float>(rel.dot(face.right_box)),
                                     static_cast<float>(rel.dot(face.down_box)), 0.f);
          image.back().emplace_back(static_cast<float>(tag->corners_px[k].x()),
                                    static_cast<float>(tag->corners_px[k].y()));
        }
      }
    }
  }
  cv::Mat camera_matrix, distortion;
  std::vector<cv::Mat> rvecs, tvecs;
  *rms = cv::calibrateCamera(object, image, cv::Size(kWidth, kHeight), camera_matrix, distortion,
                             rvecs, tvecs, cv::CALIB_FIX_K3);
  return IntrinsicsFromOpenCv(camera_matrix, distortion, kWidth, kHeight);
}

TEST(SolveIntrinsicsFromViews, AgreesWithTheTruthAndWithOpenCvsCalibrateCamera) {
  const Result<CalibBox> box = LoadCalibBox("etc/calib-box.yaml");
  ASSERT_TRUE(box.ok()) << box.status().ToString();
  const CameraIntrinsics truth = TrueCamera();
  for (uint32_t seed : {1u, 2u, 3u}) {
    const std::vector<ViewObservations> views = SyntheticViews(*box, truth, seed);
    std::vector<const ViewObservations*> pointers;
    for (const ViewObservations& v : views) pointers.push_back(&v);
    const Result<IntrinsicsFromViews> ours =
        SolveIntrinsicsFromViews(pointers, *box, kWidth, kHeight);
    ASSERT_TRUE(ours.ok()) << ours.status().ToString();
    double opencv_rms = 0;
    const CameraIntrinsics opencv = OpenCvOnSamePlanes(views, *box, &opencv_rms);
    const CameraIntrinsics& k = ours->intrinsics;
    std::printf(
        "seed %u, %d planes: fx %.6f (OpenCV %.6f, true %.0f), cx %.5f (%.5f, %.0f), k1 %.7f "
        "(%.7f), "
        "RMS %.6f px (%.6f)\n",
        seed, ours->planes, k.fx_px, opencv.fx_px, truth.fx_px, k.cx_px, opencv.cx_px, truth.cx_px,
        k.k1, opencv.k1, ours->rms_px, opencv_rms);
    EXPECT_GE(ours->planes, 12);
    // The same minimum as calibrateCamera's, which stops a little earlier
    // (measured: focal 3.8e-7 apart, principal point 5e-4 px, k1 8e-6).
    EXPECT_NEAR(k.fx_px / opencv.fx_px, 1, 2e-6) << seed;
    EXPECT_NEAR(k.fy_px / opencv.fy_px, 1, 2e-6) << seed;
    EXPECT_NEAR(k.cx_px, opencv.cx_px, 3e-3) << seed;
    EXPECT_NEAR(k.cy_px, opencv.cy_px, 3e-3) << seed;
    EXPECT_NEAR(k.k1, opencv.k1, 5e-5) << seed;
    EXPECT_NEAR(ours->rms_px, opencv_rms, 1e-5 * opencv_rms) << seed;
    // And near the truth, for 0.1 px corner noise.
    EXPECT_NEAR(k.fx_px / truth.fx_px, 1, 5e-3) << seed;
    EXPECT_NEAR(k.cx_px, truth.cx_px, 10) << seed;
    EXPECT_LT(ours->rms_px, 0.15) << seed;  // the noise's RMS per corner is 0.14 px
  }
}

TEST(SolveIntrinsicsFromViews, NamesWhatIsMissingWithTooFewPlanes) {
  const Result<CalibBox> box = LoadCalibBox("etc/calib-box.yaml");
  ASSERT_TRUE(box.ok()) << box.status().ToString();
  const std::vector<ViewObservations> views = SyntheticViews(*box, TrueCamera(), 1);
  const std::vector<const ViewObservations*> one{&views[0]};
  const Result<IntrinsicsFromViews> solved = SolveIntrinsicsFromViews(one, *box, kWidth, kHeight);
  ASSERT_FALSE(solved.ok());
  EXPECT_NE(solved.status().message().find("4 needed"), std::string::npos)
      << solved.status().ToString();
  EXPECT_NE(solved.status().message().find("calibrate-intrinsics"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
