#include "reconstruction/visual_hull.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "core/parallel.h"

namespace hairrig {
namespace {

// A view prepared for voxel tests: the distance (px) from every pixel to the
// nearest pixel that is not backdrop, so that a voxel's whole footprint is
// tested with one lookup.
struct CarvingView {
  std::array<double, CameraIntrinsics::kNumParams> params{};
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  cv::Mat1f distance_to_subject_px;
  double focal_px = 0;
};

CarvingView PrepareView(const SilhouetteView& v) {
  CarvingView c;
  c.params = v.camera.ToParams();
  c.rotation = v.cam_from_object.RotationMatrix();
  c.translation = v.cam_from_object.translation;
  c.focal_px = std::max(v.camera.fx_px, v.camera.fy_px);
  const cv::Mat1b empty(cv::Mat(v.silhouette == kSilhouetteEmpty));
  cv::distanceTransform(empty, c.distance_to_subject_px, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return c;
}

// What a view says about the ball of `radius_mm` around a point.
enum class Verdict { kOutOfFrame, kSubject, kEmpty };

Verdict Judge(const CarvingView& v, const Eigen::Vector3d& p_object, double radius_mm) {
  const Eigen::Vector3d p = v.rotation * p_object + v.translation;
  if (p.z() <= radius_mm) return Verdict::kOutOfFrame;
  double uv[2];
  ProjectCamPoint(v.params.data(), p.data(), uv);
  const int x = static_cast<int>(std::lround(uv[0])), y = static_cast<int>(std::lround(uv[1]));
  if (x < 0 || y < 0 || x >= v.distance_to_subject_px.cols || y >= v.distance_to_subject_px.rows)
    return Verdict::kOutOfFrame;
  // Empty when the whole ball projects onto the backdrop.
  return v.distance_to_subject_px(y, x) > v.focal_px * radius_mm / p.z() + 0.5 ? Verdict::kEmpty
                                                                               : Verdict::kSubject;
}

bool Survives(const std::vector<CarvingView>& views, const Eigen::Vector3d& p, double radius_mm,
              int max_empty, int min_in_frame) {
  int empty = 0, in_frame = 0;
  for (const CarvingView& v : views) {
    const Verdict verdict = Judge(v, p, radius_mm);
    if (verdict == Verdict::kOutOfFrame) continue;
    ++in_frame;
    if (verdict == Verdict::kEmpty && ++empty > max_empty) return false;
  }
  return in_frame >= min_in_frame;
}

// The point nearest every camera's optical axis (least squares).
Result<Eigen::Vector3d> CommonTarget(const std::vector<SilhouetteView>& views) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const SilhouetteView& v : views) {
    const Rigid3d object_from_cam = v.cam_from_object.Inverse();
    const Eigen::Vector3d d = object_from_cam.rotation * Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * object_from_cam.translation;
  }
  if (std::abs(a.determinant()) < 1e-6)
    return FailedPrecondition("the cameras' optical axes do not meet (all parallel)");
  return Eigen::Vector3d(a.ldlt().solve(b));
}

// Carves a grid of `grid` (occupied pre-filled with where to test) in place.
void Carve(const std::vector<CarvingView>& views, double radius_mm, int max_empty, int min_in_frame,
           int threads, VisualHull* grid) {
  const size_t slice = static_cast<size_t>(grid->nx) * static_cast<size_t>(grid->ny);
  ParallelFor(static_cast<size_t>(grid->nz), threads, [&] {
    return [&](size_t z) {
      for (int y = 0; y < grid->ny; ++y) {
        for (int x = 0; x < grid->nx; ++x) {
          uint8_t& cell =
              grid->occupied[z * slice + static_cast<size_t>(y) * static_cast<size_t>(grid->nx) +
                             static_cast<size_t>(x)];
          if (cell == 0) continue;
          const Eigen::Vector3d p =
              grid->origin_mm + grid->voxel_mm * Eigen::Vector3d(x, y, static_cast<double>(z));
          cell = Survives(views, p, radius_mm, max_empty, min_in_frame) ? 1 : 0;
        }
      }
    };
  });
}

// Bounds (voxel indices, inclusive) of the occupied cells; false when none.
bool OccupiedBounds(const VisualHull& g, Eigen::Vector3i* lo, Eigen::Vector3i* hi) {
  *lo = Eigen::Vector3i(g.nx, g.ny, g.nz);
  *hi = Eigen::Vector3i(-1, -1, -1);
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x)
        if (g.Occupied(x, y, z)) {
          *lo = lo->cwiseMin(Eigen::Vector3i(x, y, z));
          *hi = hi->cwiseMax(Eigen::Vector3i(x, y, z));
        }
  return hi->x() >= 0;
}

}  // namespace

Status VisualHullOptions::Check() const {
  if (!(voxel_mm > 0.1 && voxel_mm <= 50))
    return InvalidArgument("hull voxel_mm must be in (0.1, 50]");
  if (!(search_voxel_mm >= voxel_mm && search_voxel_mm <= 100))
    return InvalidArgument("hull search_voxel_mm must be in [voxel_mm, 100]");
  if (!(search_radius_mm > search_voxel_mm && search_radius_mm <= 5000))
    return InvalidArgument("hull search_radius_mm must be in (search_voxel_mm, 5000]");
  if (max_empty_views < 0) return InvalidArgument("hull max_empty_views must not be negative");
  if (!(max_empty_share >= 0 && max_empty_share <= 0.5))
    return InvalidArgument("hull max_empty_share must be in [0, 0.5]");
  if (!(min_in_frame_share >= 0 && min_in_frame_share <= 1))
    return InvalidArgument("hull min_in_frame_share must be in [0, 1]");
  if (threads < 1) return InvalidArgument("hull threads must be at least 1");
  return Status::Ok();
}

int MaxEmptyViews(const VisualHullOptions& options, int views) {
  return std::max(options.max_empty_views,
                  static_cast<int>(std::floor(options.max_empty_share * views + 1e-9)));
}

bool VisualHull::OccupiedAt(const Eigen::Vector3d& p_object) const {
  const Eigen::Vector3d g = (p_object - origin_mm) / voxel_mm;
  return Occupied(static_cast<int>(std::lround(g.x())), static_cast<int>(std::lround(g.y())),
                  static_cast<int>(std::lround(g.z())));
}

int64_t VisualHull::OccupiedCount() const {
  return std::count(occupied.begin(), occupied.end(), uint8_t{1});
}

Result<VisualHull> CarveVisualHull(const std::vector<SilhouetteView>& views,
                                   const VisualHullOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  if (views.size() < 2) return InvalidArgument("the visual hull needs at least two views");
  for (size_t v = 0; v < views.size(); ++v) {
    if (views[v].silhouette.rows != views[v].camera.height_px ||
        views[v].silhouette.cols != views[v].camera.width_px)
      return InvalidArgument("hull view " + std::to_string(v) +
                             ": its silhouette is not the camera's size");
  }
  HR_ASSIGN_OR_RETURN(const Eigen::Vector3d target, CommonTarget(views));
  std::vector<CarvingView> carving(views.size());
  ParallelFor(views.size(), options.threads,
              [&] { return [&](size_t v) { carving[v] = PrepareView(views[v]); }; });

  // Coarse: each voxel tested with its whole footprint, so nothing of the
  // subject is carved at this scale.
  VisualHull coarse;
  coarse.voxel_mm = options.search_voxel_mm;
  coarse.nx = coarse.ny = coarse.nz =
      2 * static_cast<int>(std::ceil(options.search_radius_mm / coarse.voxel_mm)) + 1;
  coarse.origin_mm = target - Eigen::Vector3d::Constant(coarse.voxel_mm * (coarse.nx / 2));
  coarse.occupied.assign(static_cast<size_t>(coarse.nx) * coarse.ny * coarse.nz, 1);
  const int min_in_frame = std::max(
      1,
      static_cast<int>(std::ceil(options.min_in_frame_share * static_cast<double>(views.size()))));
  const int max_empty = MaxEmptyViews(options, static_cast<int>(views.size()));
  Carve(carving, coarse.voxel_mm * std::sqrt(3.0) / 2, max_empty, min_in_frame, options.threads,
        &coarse);
  Eigen::Vector3i lo, hi;
  if (!OccupiedBounds(coarse, &lo, &hi))
    return FailedPrecondition(
        "the silhouettes share no point: the calibration or the segmentation is wrong");

  // Fine: the coarse survivors' bounds plus a coarse voxel, centres tested.
  VisualHull fine;
  fine.voxel_mm = options.voxel_mm;
  const Eigen::Vector3d lo_mm =
      coarse.origin_mm + coarse.voxel_mm * (lo.cast<double>() - Eigen::Vector3d::Ones());
  const Eigen::Vector3d hi_mm =
      coarse.origin_mm + coarse.voxel_mm * (hi.cast<double>() + Eigen::Vector3d::Ones());
  fine.origin_mm = lo_mm;
  const Eigen::Vector3d extent = (hi_mm - lo_mm) / fine.voxel_mm;
  fine.nx = static_cast<int>(std::ceil(extent.x())) + 1;
  fine.ny = static_cast<int>(std::ceil(extent.y())) + 1;
  fine.nz = static_cast<int>(std::ceil(extent.z())) + 1;
  fine.occupied.assign(static_cast<size_t>(fine.nx) * fine.ny * fine.nz, 0);
  for (int z = 0; z < fine.nz; ++z)
    for (int y = 0; y < fine.ny; ++y)
      for (int x = 0; x < fine.nx; ++x) {
        const Eigen::Vector3d p = fine.origin_mm + fine.voxel_mm * Eigen::Vector3d(x, y, z);
        if (coarse.OccupiedAt(p))
          fine.occupied[(static_cast<size_t>(z) * fine.ny + y) * fine.nx + x] = 1;
      }
  Carve(carving, 0.0, max_empty, min_in_frame, options.threads, &fine);
  if (fine.OccupiedCount() == 0)
    return FailedPrecondition(
        "no voxel survives carving: the calibration or the segmentation is wrong");
  return fine;
}

cv::Mat1f HullDepthMap(const VisualHull& hull, const CameraIntrinsics& camera,
                       const Rigid3d& cam_from_object, const cv::Mat& region, int stride_px) {
  cv::Mat1f depth(camera.height_px, camera.width_px, 0.f);
  const Rigid3d object_from_cam = cam_from_object.Inverse();
  const Eigen::Matrix3d rotation = object_from_cam.RotationMatrix();
  const Eigen::Vector3d centre = object_from_cam.translation;
  const Eigen::Vector3d lo = hull.origin_mm - Eigen::Vector3d::Constant(hull.voxel_mm / 2);
  const Eigen::Vector3d hi = lo + hull.voxel_mm * Eigen::Vector3d(hull.nx, hull.ny, hull.nz);
  const int step = std::max(1, stride_px);
  for (int v = 0; v < camera.height_px; v += step) {
    for (int u = 0; u < camera.width_px; u += step) {
      if (!region.empty() && region.at<uint8_t>(v, u) == 0) continue;
      const Result<Eigen::Vector2d> n = UndistortPixel(camera, Eigen::Vector2d(u, v));
      if (!n.ok()) continue;
      // Points C + z * d have depth z along the optical axis.
      const Eigen::Vector3d d = rotation * Eigen::Vector3d(n->x(), n->y(), 1.0);
      double z_near = 1.0, z_far = std::numeric_limits<double>::max();
      for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (centre[a] < lo[a] || centre[a] > hi[a]) z_far = -1;
          continue;
        }
        double t0 = (lo[a] - centre[a]) / d[a], t1 = (hi[a] - centre[a]) / d[a];
        if (t0 > t1) std::swap(t0, t1);
        z_near = std::max(z_near, t0);
        z_far = std::min(z_far, t1);
      }
      const double dz = hull.voxel_mm / 4 / d.norm();
      for (double z = z_near; z <= z_far; z += dz) {
        if (hull.OccupiedAt(centre + z * d)) {
          depth(v, u) = static_cast<float>(z);
          break;
        }
      }
    }
  }
  return depth;
}

}  // namespace hairrig
