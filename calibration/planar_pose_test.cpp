// PlanarSquarePoses and RefinePose against the truth of synthetic views and
// against OpenCV's SOLVEPNP_IPPE and solvePnPRefineLM on the same corners.
#include "calibration/planar_pose.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace hairrig {
namespace {

// A 30 mm square on a tilted plane of the model, 20 mm off its origin.
std::array<Eigen::Vector3d, 4> TiltedSquare() {
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d offset(20, -10, 5);
  std::array<Eigen::Vector3d, 4> square;
  const double half = 15;
  const double signs[4][2] = {{-1, 1}, {1, 1}, {1, -1}, {-1, -1}};
  for (size_t i = 0; i < 4; ++i) square[i] = tilt * Eigen::Vector3d(signs[i][0] * half, signs[i][1] * half, 0) + offset;
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

std::array<Eigen::Vector2d, 4> Project(const Rigid3d& pose, const std::array<Eigen::Vector3d, 4>& points,
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

double AngleBetween(const Rigid3d& a, const Rigid3d& b) { return a.rotation.angularDistance(b.rotation); }

Rigid3d FromOpenCv(const cv::Mat& rvec, const cv::Mat& tvec) {
  const Eigen::Vector3d aa(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const double angle = aa.norm();
  const Eigen::Quaterniond q = angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, aa / angle))
                                         : Eigen::Quaterniond::Identity();
  return Rigid3d(q, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
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
  std::vector<cv::Point3d> object;
  for (const auto& p : square) object.emplace_back(p.x(), p.y(), p.z());
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  const Eigen::Vector3d normal = (square[1] - square[0]).cross(square[3] - square[0]).normalized();
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Rigid3d truth = RandomView(rng, 500);
    // A tag seen within 15 deg of edge-on gives no usable pose (OpenCV's two
    // then lie behind the camera; ours are left out): not compared.
    const double facing = (truth.rotation * normal).dot((truth * square[0]).normalized());
    if (std::abs(facing) < std::sin(15 * M_PI / 180)) continue;
    ++compared;
    const auto image = Project(truth, square, &rng, 1e-3);  // about 1 px at a focal length of 1000 px
    std::vector<cv::Point2d> cv_image;
    for (const auto& u : image) cv_image.emplace_back(u.x(), u.y());
    std::vector<cv::Mat> rvecs, tvecs;
    cv::solvePnPGeneric(object, cv_image, identity, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE);
    const std::vector<Rigid3d> ours = PlanarSquarePoses(square, image);
    ASSERT_EQ(ours.size(), rvecs.size()) << trial;
    for (size_t h = 0; h < ours.size(); ++h) {
      const Rigid3d theirs = FromOpenCv(rvecs[h], tvecs[h]);
      EXPECT_LT(AngleBetween(ours[h], theirs), 1e-7) << trial << " hypothesis " << h;
      EXPECT_LT((ours[h].translation - theirs.translation).norm(), 1e-4) << trial << " hypothesis " << h;
    }
  }
  EXPECT_GT(compared, 150);
}

TEST(PlanarSquarePoses, RefusesCornersOffOnePlaneAndDegenerateOnes) {
  const auto square = TiltedSquare();
  const auto image = Project(Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 500)), square);
  auto bent = square;
  bent[2].z() += 1.0;
  EXPECT_TRUE(PlanarSquarePoses(bent, image).empty());
  auto collapsed = square;
  collapsed[1] = collapsed[0];
  collapsed[2] = collapsed[3];
  EXPECT_TRUE(PlanarSquarePoses(collapsed, image).empty());
  auto nan_image = image;
  nan_image[3].x() = NAN;
  EXPECT_TRUE(PlanarSquarePoses(square, nan_image).empty());
}

TEST(RefinePose, ConvergesToOpenCvsMinimumAndRepeatsBitForBit) {
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
    const Rigid3d start(Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, -1, 0.2).normalized())) *
                            truth.rotation,
                        truth.translation + Eigen::Vector3d(5, -4, 20));
    const PoseRefinement ours = RefinePose(points, image, start);
    const Eigen::Vector3d aa = start.AngleAxis();
    cv::Mat rvec = (cv::Mat_<double>(3, 1) << aa.x(), aa.y(), aa.z());
    cv::Mat tvec = (cv::Mat_<double>(3, 1) << start.translation.x(), start.translation.y(), start.translation.z());
    cv::solvePnPRefineLM(cv_points, cv_image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec,
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-15));
    const Rigid3d theirs = FromOpenCv(rvec, tvec);
    EXPECT_LT(AngleBetween(ours.cam_from_model, theirs), 1e-9) << trial;
    EXPECT_LT((ours.cam_from_model.translation - theirs.translation).norm(), 1e-6) << trial;
    EXPECT_LT(ours.rms, 3e-3) << trial;  // the noise's RMS per point is 1.4e-3
    EXPECT_GT(ours.iterations, 1) << trial;

    // The same points in other allocations give the same bits.
    const std::vector<double> spacer(static_cast<size_t>(trial) + 1, 0.0);
    const std::vector<Eigen::Vector3d> points_copy(points);
    const std::vector<Eigen::Vector2d> image_copy(image);
    const PoseRefinement again = RefinePose(points_copy, image_copy, start);
    EXPECT_EQ(again.cam_from_model.rotation.coeffs(), ours.cam_from_model.rotation.coeffs()) << trial;
    EXPECT_EQ(again.cam_from_model.translation, ours.cam_from_model.translation) << trial;
  }
}

}  // namespace
}  // namespace hairrig
