// PlanarSquarePoses and RefinePose against the truth of synthetic views and
// against OpenCV's SOLVEPNP_IPPE and solvePnPRefineLM on the same corners.
#include "calibration/planar_pose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>
#include <string>

namespace hairrig {
namespace {

// A 30 mm square on a tilted plane of the model, 20 mm off its origin.
std::array<Eigen::Vector3d, 4> TiltedSquare() {
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d offset(20, -10, 5);
  std::array<Eigen::Vector3d, 4> square;
  const double half = 15;
  const double signs[4][2] = {{-1, 1}, {1, 1}, {1, -1}, {-1, -1}};
  for (size_t i = 0; i < 4; ++i)
    square[i] = tilt * Eigen::Vector3d(signs[i][0] * half, signs[i][1] * half, 0) + offset;
  return square;
}

// cam_from_model looking at the model origin from `distance_mm`, in a direction set by the seed.
Rigid3d RandomView(std::mt19937& rng, double distance_mm) {
  std::uniform_real_distribution<double> angle(-0.9, 0.9), shift(-40, 40);
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(angle(rng) * 3, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  return Rigid3d(r, Eigen::Vector3d(shift(rng), shift(rng), distance_mm));
}

std::array<Eigen::Vector2d, 4> Project(const Rigid3d& pose,
                                       const std::array<Eigen::Vector3d, 4>& points,
                                       std::mt19937* rng = nullptr, double noise = 0) {
  std::normal_distribution<double> n(0, noise);
  std::array<Eigen::Vector2d, 4> out;
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d y = pose * points[i];
    out[i] = y.head<2>() / y.z();
    if (rng) out[i] += Eigen::Vector2d(n(*rng), n(*rng));
  }
  return out;
}

double AngleBetween(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation);
}

Rigid3d FromOpenCv(const cv::Mat& rvec, const cv::Mat& tvec) {
  return Rigid3d::FromAngleAxis(
      Eigen::Vector3d(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)),
      Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

// Both of OpenCV's IPPE poses and ours agree for `truth` seen with `noise`.
void ExpectOpenCvsIppe(const std::array<Eigen::Vector3d, 4>& square, const Rigid3d& truth,
                       std::mt19937& rng, double noise, const std::string& label) {
  std::vector<cv::Point3d> object;
  for (const auto& p : square) object.emplace_back(p.x(), p.y(), p.z());
  const auto image = Project(truth, square, &rng, noise);
  std::vector<cv::Point2d> cv_image;
  for (const auto& u : image) cv_image.emplace_back(u.x(), u.y());
  std::vector<cv::Mat> rvecs, tvecs;
  cv::solvePnPGeneric(object, cv_image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvecs, tvecs,
                      false, cv::SOLVEPNP_IPPE);
  const std::vector<Rigid3d> ours = PlanarSquarePoses(square, image);
  ASSERT_EQ(ours.size(), rvecs.size()) << label;
  for (size_t h = 0; h < ours.size(); ++h) {
    const Rigid3d theirs = FromOpenCv(rvecs[h], tvecs[h]);
    EXPECT_LT(AngleBetween(ours[h], theirs), 1e-7) << label << " hypothesis " << h;
    EXPECT_LT((ours[h].translation - theirs.translation).norm(), 1e-4)
        << label << " hypothesis " << h;
  }
}

TEST(PlanarSquarePoses, RecoversTheTruePoseFromExactCorners) {
  std::mt19937 rng(7);
  const auto square = TiltedSquare();
  for (int trial = 0; trial < 200; ++trial) {
    const Rigid3d truth = RandomView(rng, 400 + 100 * (trial % 8));
    const std::vector<Rigid3d> poses = PlanarSquarePoses(square, Project(truth, square));
    ASSERT_FALSE(poses.empty()) << trial;
    EXPECT_LT(AngleBetween(poses[0], truth), 1e-8) << trial;
    EXPECT_LT((poses[0].translation - truth.translation).norm(), 1e-6) << trial;
  }
}

TEST(PlanarSquarePoses, GivesOpenCvsIppeSolutionsFromNoisyCorners) {
  std::mt19937 rng(11);
  const auto square = TiltedSquare();
  const Eigen::Vector3d normal = (square[1] - square[0]).cross(square[3] - square[0]).normalized();
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Rigid3d truth = RandomView(rng, 500);
    // A tag seen within 15 deg of edge-on gives no usable pose (OpenCV's two
    // then lie behind the camera; ours are left out): not compared.
    const double facing = (truth.rotation * normal).dot((truth * square[0]).normalized());
    if (std::abs(facing) < std::sin(15 * M_PI / 180)) continue;
    ++compared;
    // About 1 px at a focal length of 1000 px.
    ExpectOpenCvsIppe(square, truth, rng, 1e-3, "trial " + std::to_string(trial));
  }
  EXPECT_GT(compared, 150);
}

// Seen square on and within a degree of it, where the two singular values of
// the Jacobian's block are nearly equal. (With noise, one small tag seen
// square on leaves its tilt uncertain by degrees: only OpenCV's answer is
// compared then.)
TEST(PlanarSquarePoses, GivesOpenCvsIppeSolutionsForATagSeenSquareOn) {
  std::mt19937 rng(5);
  const auto square = TiltedSquare();
  const Eigen::Vector3d centre = (square[0] + square[1] + square[2] + square[3]) / 4;
  const Eigen::Vector3d normal = (square[1] - square[0]).cross(square[3] - square[0]).normalized();
  for (double tilt_deg : {0.0, 0.01, 0.1, 1.0}) {
    const Eigen::Vector3d side = normal.unitOrthogonal();
    const Eigen::Vector3d eye =
        centre + 500 * (Eigen::AngleAxisd(tilt_deg * M_PI / 180, side) * normal);
    const Rigid3d truth = LookAt(eye, centre, side);
    for (double noise : {0.0, 1e-4}) {
      ExpectOpenCvsIppe(
          square, truth, rng, noise,
          "tilt " + std::to_string(tilt_deg) + " deg, noise " + std::to_string(noise));
    }
    const std::vector<Rigid3d> exact = PlanarSquarePoses(square, Project(truth, square));
    ASSERT_FALSE(exact.empty());
    EXPECT_LT(AngleBetween(exact[0], truth), 1e-7) << tilt_deg;
  }
}

TEST(PlanarSquarePoses, RefusesCornersOffOnePlaneAndDegenerateOnes) {
  const auto square = TiltedSquare();
  const auto image =
      Project(Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 500)), square);
  auto bent = square;
  bent[2].z() += 1.0;
  EXPECT_TRUE(PlanarSquarePoses(bent, image).empty());
  auto collapsed = square;
  collapsed[1] = collapsed[0];
  collapsed[2] = collapsed[3];
  EXPECT_TRUE(PlanarSquarePoses(collapsed, image).empty());
  auto collinear = square;
  collinear[1] = 0.5 * (square[0] + square[2]);  // on the diagonal: three corners on one line
  EXPECT_TRUE(PlanarSquarePoses(collinear, image).empty());
  auto nan_image = image;
  nan_image[3].x() = NAN;
  EXPECT_TRUE(PlanarSquarePoses(square, nan_image).empty());
}

TEST(RefinePose, ConvergesToOpenCvsMinimum) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1e-3);
  std::uniform_real_distribution<double> spread(-60, 60);
  for (int trial = 0; trial < 50; ++trial) {
    const Rigid3d truth = RandomView(rng, 600);
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector2d> image;
    std::vector<cv::Point3d> cv_points;
    std::vector<cv::Point2d> cv_image;
    for (int i = 0; i < 24; ++i) {
      points.emplace_back(spread(rng), spread(rng), spread(rng));
      const Eigen::Vector3d y = truth * points.back();
      image.push_back(y.head<2>() / y.z() + Eigen::Vector2d(noise(rng), noise(rng)));
      cv_points.emplace_back(points.back().x(), points.back().y(), points.back().z());
      cv_image.emplace_back(image.back().x(), image.back().y());
    }
    const Rigid3d start(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, -1, 0.2).normalized())) *
            truth.rotation,
        truth.translation + Eigen::Vector3d(5, -4, 20));
    const PoseRefinement ours = RefinePose(points, image, start);
    const Eigen::Vector3d aa = start.AngleAxis();
    cv::Mat rvec = (cv::Mat_<double>(3, 1) << aa.x(), aa.y(), aa.z());
    cv::Mat tvec = (cv::Mat_<double>(3, 1) << start.translation.x(), start.translation.y(),
                    start.translation.z());
    cv::solvePnPRefineLM(
        cv_points, cv_image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec,
        cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-15));
    const Rigid3d theirs = FromOpenCv(rvec, tvec);
    EXPECT_LT(AngleBetween(ours.cam_from_model, theirs), 1e-9) << trial;
    EXPECT_LT((ours.cam_from_model.translation - theirs.translation).norm(), 1e-6) << trial;
    EXPECT_LT(ours.rms, 3e-3) << trial;  // the noise's RMS per point is 1.4e-3
    EXPECT_GT(ours.iterations, 1) << trial;
  }
}

}  // namespace
}  // namespace hairrig
