// The visual hull of a sphere seen by cameras on a ring around it: the hull
// holds the sphere, and its front surface seen from a camera lies on the
// sphere where that camera sees the sphere's silhouette-forming band, whether
// the ring is whole or only a third of a turn (the views of part of a capture).
#include "reconstruction/visual_hull.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "tests/support/plane_scene_testing.h"

namespace hairrig {
namespace {

using plane_scene::CentredCamera;

constexpr int kWidth = 320, kHeight = 240;
constexpr double kRadiusMm = 80;
const Eigen::Vector3d kCentre(5, -10, 20);

SilhouetteView RingView(double azimuth_deg, double elevation_mm) {
  SilhouetteView v;
  v.camera = CentredCamera(kWidth, kHeight, 420);
  const double a = DegToRad(azimuth_deg);
  const Eigen::Vector3d eye(700 * std::sin(a), elevation_mm, -700 * std::cos(a));
  v.cam_from_object = LookAt(eye, kCentre, Eigen::Vector3d::UnitY());
  v.silhouette = cv::Mat1b(kHeight, kWidth, uint8_t{kSilhouetteEmpty});
  const Rigid3d object_from_cam = v.cam_from_object.Inverse();
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const Result<Eigen::Vector2d> n = UndistortPixel(v.camera, Eigen::Vector2d(x, y));
      const Eigen::Vector3d dir =
          (object_from_cam.rotation * Eigen::Vector3d(n->x(), n->y(), 1)).normalized();
      const Eigen::Vector3d to_centre = kCentre - object_from_cam.translation;
      const double along = to_centre.dot(dir);
      if ((to_centre - along * dir).norm() <= kRadiusMm) v.silhouette(y, x) = kSilhouetteSubject;
    }
  }
  return v;
}

std::vector<SilhouetteView> Ring(double first_deg, double last_deg, int count) {
  std::vector<SilhouetteView> views;
  for (int k = 0; k < count; ++k) {
    const double azimuth = first_deg + (last_deg - first_deg) * k / std::max(1, count - 1);
    views.push_back(RingView(azimuth, k % 2 == 0 ? -150 : 150));
  }
  return views;
}

// The median, over the sphere's pixels, of |hull depth - sphere depth| in view 0.
double FrontDepthError(const VisualHull& hull, const SilhouetteView& view) {
  const cv::Mat1f depth = HullDepthMap(hull, view.camera, view.cam_from_object, view.silhouette, 2);
  std::vector<double> errors;
  for (int y = 0; y < kHeight; y += 2) {
    for (int x = 0; x < kWidth; x += 2) {
      if (view.silhouette(y, x) != kSilhouetteSubject) continue;
      const Result<Eigen::Vector2d> n = UndistortPixel(view.camera, Eigen::Vector2d(x, y));
      const Eigen::Vector3d ray(n->x(), n->y(), 1);
      const Eigen::Vector3d c = view.cam_from_object * kCentre;
      // Nearest intersection of the ray s * ray with the sphere, as a depth.
      const double a = ray.squaredNorm(), b = -2 * ray.dot(c),
                   q = c.squaredNorm() - kRadiusMm * kRadiusMm;
      const double disc = b * b - 4 * a * q;
      if (disc < 0 || depth(y, x) <= 0) {
        errors.push_back(1e9);
        continue;
      }
      errors.push_back(std::abs(depth(y, x) - (-b - std::sqrt(disc)) / (2 * a)));
    }
  }
  std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2),
                   errors.end());
  return errors[errors.size() / 2];
}

TEST(VisualHull, HoldsTheSphereAndIsBoundedByIt) {
  const std::vector<SilhouetteView> views = Ring(0, 360.0 * 11 / 12, 12);
  VisualHullOptions options;
  options.voxel_mm = 4;
  const Result<VisualHull> hull = CarveVisualHull(views, options);
  ASSERT_TRUE(hull.ok()) << hull.status().ToString();
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(60, 0, 0), Eigen::Vector3d(0, -60, 0),
        Eigen::Vector3d(0, 0, 60), Eigen::Vector3d(-40, 40, -40)}) {
    EXPECT_TRUE(hull->OccupiedAt(kCentre + offset)) << offset.transpose();
  }
  // A 12-view hull of a sphere is a polyhedron around it: nothing far out.
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(130, 0, 0), Eigen::Vector3d(0, 0, -130), Eigen::Vector3d(0, 0, 130)}) {
    EXPECT_FALSE(hull->OccupiedAt(kCentre + offset)) << offset.transpose();
  }
  const double error = FrontDepthError(*hull, views[0]);
  std::printf("whole ring: median front depth error %.2f mm\n", error);
  EXPECT_LT(error, 8.0);
}

// The views of a third of a turn: space in front of the subject that the
// views at the far end of the arc do not have in their frame must not stay
// in the hull.
TEST(VisualHull, ViewsOfPartOfATurnKeepTheFrontOnTheSubject) {
  const std::vector<SilhouetteView> views = Ring(0, 120, 7);
  VisualHullOptions options;
  options.voxel_mm = 4;
  const Result<VisualHull> hull = CarveVisualHull(views, options);
  ASSERT_TRUE(hull.ok()) << hull.status().ToString();
  EXPECT_TRUE(hull->OccupiedAt(kCentre));
  const double error = FrontDepthError(*hull, views[3]);
  std::printf("a third of a turn: median front depth error %.2f mm\n", error);
  EXPECT_LT(error, 15.0);
  // Half-way from the first camera to the sphere: in every view's frame
  // only near that camera, so not the subject's.
  const Eigen::Vector3d eye0 = views[0].cam_from_object.Inverse().translation;
  EXPECT_FALSE(hull->OccupiedAt(0.5 * (eye0 + kCentre)));
}

// Blanks, in `view`'s silhouette, the disc of `radius_px` around the
// projection of `p`: a wisp the segmentation missed there.
void MissWisp(const Eigen::Vector3d& p, int radius_px, SilhouetteView* view) {
  const Eigen::Vector3d p_cam = view->cam_from_object * p;
  Eigen::Vector2d uv;
  ASSERT_TRUE(ProjectChecked(view->camera, p_cam, &uv));
  cv::circle(view->silhouette, cv::Point(static_cast<int>(uv.x()), static_cast<int>(uv.y())),
             radius_px, cv::Scalar(kSilhouetteEmpty), cv::FILLED);
}

// A segmentation misses thin wisps in some views: on a ring of 34 views a
// tolerance of 6 % lets 2 of them miss a wisp on the subject's surface
// without carving it; a third view carves it, as every view does with no
// tolerance, and on a ring of 12 views every view carves.
TEST(VisualHull, AFewViewsMissingAWispDoNotCarveIt) {
  VisualHullOptions tolerant;
  tolerant.max_empty_share = 0.06;
  tolerant.voxel_mm = 4;
  ASSERT_EQ(MaxEmptyViews(tolerant, 34), 2);
  ASSERT_EQ(MaxEmptyViews(tolerant, 12), 0);
  ASSERT_EQ(MaxEmptyViews(VisualHullOptions{}, 34), 0);
  std::vector<SilhouetteView> views = Ring(0, 360.0 * 33 / 34, 34);
  const Eigen::Vector3d eye1 = views[1].cam_from_object.Inverse().translation;
  const Eigen::Vector3d wisp = kCentre + 70 * (eye1 - kCentre).normalized();
  for (size_t v : {1, 2}) MissWisp(wisp, 6, &views[v]);
  VisualHullOptions options = tolerant;
  Result<VisualHull> hull = CarveVisualHull(views, options);
  ASSERT_TRUE(hull.ok()) << hull.status().ToString();
  EXPECT_TRUE(hull->OccupiedAt(wisp));
  options.max_empty_share = 0;
  hull = CarveVisualHull(views, options);
  ASSERT_TRUE(hull.ok()) << hull.status().ToString();
  EXPECT_FALSE(hull->OccupiedAt(wisp)) << "every view carves without the tolerance";
  options.max_empty_share = tolerant.max_empty_share;
  MissWisp(wisp, 6, &views[3]);
  hull = CarveVisualHull(views, options);
  ASSERT_TRUE(hull.ok()) << hull.status().ToString();
  EXPECT_FALSE(hull->OccupiedAt(wisp)) << "a third view carves it";
}

TEST(VisualHull, RefusesABadShare) {
  VisualHullOptions options;
  options.min_in_frame_share = 1.5;
  EXPECT_EQ(CarveVisualHull(Ring(0, 90, 3), options).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace hairrig
