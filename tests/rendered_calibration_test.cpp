// Bundle adjustment (calibration/bundle_adjustment.h) on the default simulated
// capture, rendered here: 2 cameras x 19 stops, tags detected, each view
// initialised by calibration/view_pose.h from deliberately wrong intrinsics
// (focal +1.5 %, principal point off by 5 px, no distortion), then solved in
// the turntable and the free mode and compared with the ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "calibration/bundle_adjustment.h"
#include "calibration/turntable_axis.h"
#include "core/statistics.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/renderer.h"
#include "tests/support/rendered_observations.h"
#include "tests/support/scene_calibration_input.h"

namespace hairrig {
namespace {

CameraIntrinsics WrongIntrinsics(const CameraIntrinsics& truth) {
  CameraIntrinsics c = truth;
  c.fx_px *= 1.015;
  c.fy_px *= 1.015;
  c.cx_px += 4;
  c.cy_px -= 3;
  c.k1 = c.k2 = c.p1 = c.p2 = c.k3 = 0;
  return c;
}

struct Errors {
  double rotation_median_deg, rotation_max_deg, centre_median_mm, centre_max_mm, focal_max_percent,
      rms_px;
};

Errors Compare(const Scene& scene, const BundleAdjustmentInput& input,
               const BundleAdjustmentResult& result, const std::vector<int>& view_index) {
  std::vector<double> rotation, centre;
  for (size_t v = 0; v < input.views.size(); ++v) {
    const ViewGroundTruth truth = MakeViewGroundTruth(scene, view_index[v]);
    rotation.push_back(RotationDifferenceDeg(result.cam_from_box[v], truth.cam_from_box));
    centre.push_back(
        (result.cam_from_box[v].Inverse().translation - truth.cam_from_box.Inverse().translation)
            .norm());
  }
  double focal = 0;
  for (size_t c = 0; c < scene.cameras.size(); ++c) {
    const CameraIntrinsics& t = scene.cameras[c].intrinsics;
    focal = std::max({focal, std::abs(result.cameras[c].fx_px / t.fx_px - 1),
                      std::abs(result.cameras[c].fy_px / t.fy_px - 1)});
  }
  return {Median(rotation), *std::max_element(rotation.begin(), rotation.end()),
          Median(centre),   *std::max_element(centre.begin(), centre.end()),
          100 * focal,      result.rms_px};
}

// The same input solved again while the heap is laid out differently (blocks
// of assorted sizes held) gives the same bits, uncertainties included: the
// solve does not depend on where its parameter blocks lie in memory.
void ExpectSameSolveOnAnotherHeap(const BundleAdjustmentInput& input,
                                  const BundleAdjustmentOptions& options,
                                  const BundleAdjustmentResult& first, const char* name) {
  std::vector<std::vector<char>> held;
  for (size_t i = 0; i < 64; ++i) held.emplace_back(24 + 40 * ((i * 7919) % 97));
  const auto again = RunBundleAdjustment(input, options);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  for (size_t c = 0; c < first.cameras.size(); ++c) {
    EXPECT_EQ(first.cameras[c].ToParams(), again->cameras[c].ToParams()) << name << " camera " << c;
    EXPECT_EQ(first.intrinsics_stddev[c], again->intrinsics_stddev[c]) << name << " camera " << c;
  }
  for (size_t v = 0; v < first.cam_from_box.size(); ++v) {
    EXPECT_EQ(first.cam_from_box[v].translation, again->cam_from_box[v].translation)
        << name << " view " << v;
    EXPECT_EQ(first.cam_from_box[v].rotation.coeffs(), again->cam_from_box[v].rotation.coeffs())
        << name << " view " << v;
    const ViewUncertainty &a = first.view_uncertainty[v], &b = again->view_uncertainty[v];
    if (std::isnan(a.rotation_sd_deg)) continue;
    EXPECT_EQ(a.rotation_sd_deg, b.rotation_sd_deg) << name << " view " << v;
    EXPECT_EQ(a.centre_sd_mm, b.centre_sd_mm) << name << " view " << v;
  }
}

TEST(RenderedCalibration, TurntableAndFreeModesAgainstGroundTruth) {
  auto scene = LoadScene("etc/scenes/default.yaml");
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  auto renderer = Renderer::Create(*scene);
  ASSERT_TRUE(renderer.ok());
  auto detector = TagDetector::Create({});
  ASSERT_TRUE(detector.ok());
  BundleAdjustmentInput input;
  for (const SceneCamera& c : scene->cameras)
    input.cameras.push_back(WrongIntrinsics(c.intrinsics));
  input.turntable_from_box_init = scene->turntable_from_box;
  std::vector<int> view_index;
  const int cameras = static_cast<int>(scene->cameras.size());
  for (int stop = 0; stop < scene->turntable_stops; ++stop) {
    for (int cam = 0; cam < cameras; ++cam) {
      const int view = stop * cameras + cam;
      auto observations = RenderedObservations(**renderer, **detector, cam, stop);
      ASSERT_TRUE(observations.ok()) << observations.status().ToString();
      auto pose = EstimateViewPose(*observations, input.cameras[static_cast<size_t>(cam)]);
      if (!pose.ok()) continue;  // a view that sees too little is left to the others
      CalibrationView v;
      v.camera = cam;
      v.stop = stop;
      v.turntable_deg = scene->StopAngleDeg(stop);
      v.tags = observations->tags;
      v.cam_from_box_init = pose->cam_from_box;
      input.views.push_back(v);
      view_index.push_back(view);
    }
  }
  ASSERT_GE(input.views.size(), 30u);
  // The axis from the circle the camera centres trace, instead of the nominal box pose.
  auto axis = FitTurntableAxis(input.views, scene->turntable_from_box.translation.z(),
                               hairrig_test::SceneBoxYawDeg(*scene));
  ASSERT_TRUE(axis.ok()) << axis.status().ToString();
  const Eigen::Vector3d axis_true =
      scene->turntable_from_box.Inverse().rotation * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d axis_fit =
      axis->turntable_from_box.Inverse().rotation * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d point_true = scene->turntable_from_box.Inverse().translation;
  const Eigen::Vector3d point_fit = axis->turntable_from_box.Inverse().translation;
  const double axis_deg =
      std::acos(std::clamp(axis_true.dot(axis_fit), -1.0, 1.0)) * 180 / 3.14159265358979;
  const double axis_offset_mm =
      ((point_fit - point_true) - (point_fit - point_true).dot(axis_true) * axis_true).norm();
  std::printf(
      "turntable axis from camera %d's circle (radius %.1f mm, RMS %.3f mm): direction %.4f deg, "
      "offset %.3f mm\n",
      axis->camera, axis->radius_mm, axis->circle_rms_mm, axis_deg, axis_offset_mm);
  // Measured: 0.011 deg, 0.075 mm.
  EXPECT_LT(axis_deg, 0.022);
  EXPECT_LT(axis_offset_mm, 0.15);
  // With the box's mounting yaw from the rig config, the whole turntable frame is the scene's.
  const Eigen::AngleAxisd frame_error(scene->turntable_from_box.rotation.inverse() *
                                      axis->turntable_from_box.rotation);
  std::printf("turntable frame rotation error %.4f deg\n",
              frame_error.angle() * 180 / 3.14159265358979);
  EXPECT_LT(frame_error.angle() * 180 / 3.14159265358979, 0.022);  // 0.011 deg measured
  input.turntable_from_box_init = axis->turntable_from_box;
  // Three solves: both modes from the wrong intrinsics, and the turntable mode
  // with the intrinsics held at a prior (the true values stand in for a
  // ChArUco calibration).
  const char* names[3] = {"turntable", "free", "turntable, intrinsics prior"};
  Errors errors[3];
  for (int m = 0; m < 3; ++m) {
    BundleAdjustmentOptions options;
    options.mode = m == 1 ? CalibrationMode::kFree : CalibrationMode::kTurntable;
    BundleAdjustmentInput run = input;
    if (m == 2) {
      options.fix_intrinsics = true;
      for (size_t c = 0; c < run.cameras.size(); ++c) run.cameras[c] = scene->cameras[c].intrinsics;
    }
    auto result = RunBundleAdjustment(run, options);
    ASSERT_TRUE(result.ok()) << result.status().ToString();
    errors[m] = Compare(*scene, run, *result, view_index);
    ExpectSameSolveOnAnotherHeap(run, options, *result, names[m]);
    for (size_t c = 0; c < run.cameras.size() && m < 2; ++c) {
      const CameraIntrinsics& truth = scene->cameras[c].intrinsics;
      const auto& sd = result->intrinsics_stddev[c];
      std::printf(
          "  camera %zu: fx error %+.3f px (sd %.3f), cx error %+.3f px (sd %.3f), cy error %+.3f "
          "px (sd %.3f)\n",
          c, result->cameras[c].fx_px - truth.fx_px, sd[0], result->cameras[c].cx_px - truth.cx_px,
          sd[2], result->cameras[c].cy_px - truth.cy_px, sd[3]);
      // The errors are consistent with the predicted uncertainty (one noise seed: within 4 sigma).
      const double errors_px[3] = {result->cameras[c].fx_px - truth.fx_px,
                                   result->cameras[c].cx_px - truth.cx_px,
                                   result->cameras[c].cy_px - truth.cy_px};
      const size_t index[3] = {0, 2, 3};
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(std::isfinite(sd[index[k]]) && sd[index[k]] > 0);
        EXPECT_LT(std::abs(errors_px[k]), 4 * sd[index[k]])
            << names[m] << " camera " << c << " parameter " << index[k];
      }
    }
    std::printf(
        "%s: %zu views, rotation median %.4f max %.4f deg, centre median %.3f max %.3f mm, focal "
        "%.4f %%, "
        "RMS %.3f px, %d iterations\n",
        names[m], input.views.size(), errors[m].rotation_median_deg, errors[m].rotation_max_deg,
        errors[m].centre_median_mm, errors[m].centre_max_mm, errors[m].focal_max_percent,
        errors[m].rms_px, result->iterations);
  }
  // Measured (turntable / free / prior): rotation median 0.099 / 0.084 /
  // 0.0038 deg, centre median 0.46 / 0.74 / 0.064 mm, focal 0.072 / 0.094 %,
  // RMS 0.10 px everywhere. The box stays near the image centre as it turns,
  // so the principal point trades against the view's rotation (0.099 deg is
  // 3 px at f = 1750 px) at the same RMS: the covariance predicts a
  // principal-point standard deviation of 0.8-1.6 px. Reaching 0.02 deg needs
  // more variety or an intrinsics prior (a ChArUco board's), which then meets it.
  EXPECT_LT(errors[0].rotation_median_deg, 0.15);
  EXPECT_LT(errors[0].centre_median_mm, 0.8);
  EXPECT_LT(errors[0].focal_max_percent, 0.15);
  EXPECT_LT(errors[0].rms_px, 0.2);
  EXPECT_LT(errors[1].rotation_median_deg, 0.17);
  EXPECT_LT(errors[1].centre_median_mm, 1.5);
  EXPECT_LT(errors[0].centre_median_mm, errors[1].centre_median_mm)
      << "turntable mode better than free";
  EXPECT_LT(errors[2].rotation_median_deg, 0.008);
  EXPECT_LT(errors[2].centre_median_mm, 0.13);
  EXPECT_LT(errors[2].rms_px, 0.2);
}

TEST(BundleAdjustment, BadInputIsNamed) {
  BundleAdjustmentInput input;
  EXPECT_NE(RunBundleAdjustment(input, {}).status().message().find("no camera"), std::string::npos);
  CameraIntrinsics c;
  c.width_px = 100, c.height_px = 100, c.fx_px = c.fy_px = 100, c.cx_px = c.cy_px = 50;
  input.cameras = {c, c};
  CalibrationView v;
  v.camera = 0;
  v.tags.push_back(TagObservation{});
  input.views.push_back(v);
  EXPECT_NE(
      RunBundleAdjustment(input, {}).status().message().find("camera 1 has no view with tags"),
      std::string::npos);
  input.views[0].camera = 5;
  EXPECT_NE(RunBundleAdjustment(input, {}).status().message().find("names camera 5"),
            std::string::npos);
  input.views[0].camera = 0;
  input.cameras[1].fx_px = std::nan("");
  EXPECT_FALSE(RunBundleAdjustment(input, {}).ok());
}

}  // namespace
}  // namespace hairrig
