#include "reconstruction/point_fusion.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/parallel.h"
#include "reconstruction/mls.h"
#include "reconstruction/point_orientation_field.h"

namespace hairrig {
namespace {

struct ViewGeometry {
  std::array<double, CameraIntrinsics::kNumParams> params{};
  Eigen::Matrix3d cam_from_object_rotation;
  Eigen::Vector3d cam_from_object_translation;
  Rigid3d object_from_cam;
};

// How view w's map holds the segment at p (object frame) along `direction`.
// kEmpty: the view's map holds no depth under max_cost there.
enum class Agreement { kEmpty, kNone, kDepthOnly, kDepthAndDirection };

// One cell of view w's map against the segment at p (depth q_z in that view).
Agreement CellAgreement(const LineDepthMap& map, int gx, int gy, double q_z,
                        const Eigen::Vector3f& direction, const FusionOptions& options,
                        double cos_tolerance) {
  if (gx < 0 || gy < 0 || gx >= map.depth_mm.cols || gy >= map.depth_mm.rows)
    return Agreement::kNone;
  const float depth = map.depth_mm(gy, gx);
  if (!(depth > 0) || map.cost(gy, gx) > options.max_cost) return Agreement::kEmpty;
  if (std::abs(depth - q_z) > options.depth_tolerance_mm) return Agreement::kNone;
  const cv::Vec3f& d = map.direction(gy, gx);
  return std::abs(direction.dot(Eigen::Vector3f(d[0], d[1], d[2]))) >= cos_tolerance
             ? Agreement::kDepthAndDirection
             : Agreement::kDepthOnly;
}

// How view w's map holds the segment at p (object frame) along `direction`:
// at the cell nearest the projection, or where that cell holds no depth, the
// best of the cells within options.agreement_radius_cells of it.
Agreement AgreementOf(const ViewGeometry& g, const LineDepthMap& map, const Eigen::Vector3d& p,
                      const Eigen::Vector3f& direction, const FusionOptions& options,
                      double cos_tolerance) {
  const Eigen::Vector3d q = g.cam_from_object_rotation * p + g.cam_from_object_translation;
  if (q.z() <= 1.0) return Agreement::kNone;
  double uv[2];
  ProjectCamPoint(g.params.data(), q.data(), uv);
  const int gx = static_cast<int>(std::lround(uv[0] / map.stride_px));
  const int gy = static_cast<int>(std::lround(uv[1] / map.stride_px));
  Agreement best = CellAgreement(map, gx, gy, q.z(), direction, options, cos_tolerance);
  const int r = options.agreement_radius_cells;
  if (best != Agreement::kEmpty || r == 0) return best;
  for (int dy = -r; dy <= r && best != Agreement::kDepthAndDirection; ++dy)
    for (int dx = -r; dx <= r && best != Agreement::kDepthAndDirection; ++dx)
      best = std::max(
          best, CellAgreement(map, gx + dx, gy + dy, q.z(), direction, options, cos_tolerance));
  return best;
}

// The plane through view w's camera centre that holds the 2D orientation
// seen at p (object frame), as its unit normal in the object frame: a
// direction X lies in it when its projection moves along the orientation,
// i.e. normal = J^T d_perp with J the projection's Jacobian at p. False where
// p is behind the camera, outside the frame or off the view's hair, or the
// view has no orientation there.
bool OrientationPlaneNormal(const MvsView& view, const ViewGeometry& g, const Eigen::Vector3d& p,
                            Eigen::Vector3d* normal) {
  const Eigen::Vector3d q = g.cam_from_object_rotation * p + g.cam_from_object_translation;
  if (q.z() <= 1.0) return false;
  double uv[2];
  ProjectCamPoint(g.params.data(), q.data(), uv);
  const int x = static_cast<int>(std::lround(uv[0])), y = static_cast<int>(std::lround(uv[1]));
  if (x < 0 || y < 0 || x >= view.orientation_deg.cols || y >= view.orientation_deg.rows ||
      !view.hair(y, x))
    return false;
  const float angle = view.orientation_deg(y, x);
  if (!std::isfinite(angle)) return false;
  const double a = DegToRad(angle);
  const Eigen::Vector2d across(-std::sin(a), std::cos(a));
  const double step = 1e-3 * q.z();  // mm; the Jacobian by forward differences
  Eigen::Vector3d in_cam;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d moved = q;
    moved[k] += step;
    double uv_moved[2];
    ProjectCamPoint(g.params.data(), moved.data(), uv_moved);
    in_cam[k] = across.dot(Eigen::Vector2d(uv_moved[0] - uv[0], uv_moved[1] - uv[1])) / step;
  }
  if (!(in_cam.norm() > 0)) return false;
  *normal = g.cam_from_object_rotation.transpose() * in_cam.normalized();
  return true;
}

// Luo 2013 Sec. 4 Eq. 1 without a surface normal: the unit o minimising
// sum_V (o . m_V)^2 over the views' orientation planes m_V, plus
// kStereoWeight (1 - (o . stereo)^2), which settles the directions the planes
// leave open (views whose planes nearly coincide). A view whose plane is
// further than the fusion's angle tolerance from the stereo's direction sees
// another strand there and is left out (Luo's T_o test); with fewer than two
// planes left the stereo's direction stays.
Eigen::Vector3f MultiviewDirection(const std::vector<MvsView>& views,
                                   const std::vector<ViewGeometry>& geometry,
                                   const Eigen::Vector3d& p, const Eigen::Vector3f& stereo,
                                   const std::vector<uint16_t>& seen_by, double sin_tolerance) {
  constexpr double kStereoWeight = 0.25;
  const Eigen::Vector3d s = stereo.cast<double>().normalized();
  Eigen::Matrix3d tensor = kStereoWeight * (Eigen::Matrix3d::Identity() - s * s.transpose());
  int planes = 0;
  for (uint16_t w : seen_by) {
    Eigen::Vector3d m;
    if (!OrientationPlaneNormal(views[w], geometry[w], p, &m)) continue;
    if (std::abs(m.dot(s)) > sin_tolerance) continue;
    tensor += m * m.transpose();
    ++planes;
  }
  if (planes < 2) return stereo;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(tensor);
  return eigen.eigenvectors().col(0).cast<float>().normalized();  // the smallest eigenvalue's
}

// (1 - cost) (1 - 2^-agreeing): the views that agree say more of a point
// than its cost does (on the demo capture, 24 % of the points that one other
// view confirms lie over 2 mm from every strand, 11 % for two, 5 % for three,
// at any cost).
float PointConfidence(float cost, int agreeing) {
  return (1.0f - cost) * (1.0f - std::ldexp(1.0f, -agreeing));
}

// Counts per reference view: candidate cells, and (cell, other view) pairs
// that agree on the depth, and of those on the direction too.
struct CellCounts {
  int64_t candidates = 0, depth_pairs = 0, direction_pairs = 0, depth_confirmed = 0;
};

// The consistent points of reference view r, before merging.
std::vector<OrientedPoint> ConsistentPoints(const std::vector<MvsView>& views,
                                            const std::vector<LineDepthMap>& maps,
                                            const std::vector<ViewGeometry>& geometry, size_t r,
                                            const FusionOptions& options, CellCounts* counts) {
  std::vector<OrientedPoint> out;
  const LineDepthMap& map = maps[r];
  const double cos_tolerance = std::cos(DegToRad(options.angle_tolerance_deg));
  const double sin_tolerance = std::sin(DegToRad(options.angle_tolerance_deg));
  for (int gy = 0; gy < map.depth_mm.rows; ++gy) {
    for (int gx = 0; gx < map.depth_mm.cols; ++gx) {
      const float depth = map.depth_mm(gy, gx);
      const float cost = map.cost(gy, gx);
      if (!(depth > 0) || cost > options.max_cost) continue;
      const cv::Point2d px = GridPixel(map, gx, gy);
      const Result<Eigen::Vector2d> n =
          UndistortPixel(views[r].camera, Eigen::Vector2d(px.x, px.y));
      if (!n.ok()) continue;
      ++counts->candidates;
      const Eigen::Vector3d p =
          geometry[r].object_from_cam * (Eigen::Vector3d(n->x(), n->y(), 1.0) * depth);
      const cv::Vec3f& d = map.direction(gy, gx);
      OrientedPoint point;
      point.position_mm = p.cast<float>();
      point.direction = Eigen::Vector3f(d[0], d[1], d[2]);
      point.views.push_back(static_cast<uint16_t>(r));
      int64_t depth_pairs = 0;
      for (size_t w = 0; w < views.size(); ++w) {
        if (w == r) continue;
        const Agreement a =
            AgreementOf(geometry[w], maps[w], p, point.direction, options, cos_tolerance);
        depth_pairs += a == Agreement::kDepthOnly || a == Agreement::kDepthAndDirection;
        if (a != Agreement::kDepthAndDirection) continue;
        ++counts->direction_pairs;
        point.views.push_back(static_cast<uint16_t>(w));
      }
      counts->depth_pairs += depth_pairs;
      counts->depth_confirmed += depth_pairs > 0;
      const int agreeing = static_cast<int>(point.views.size()) - 1;
      if (agreeing < options.min_agreeing_views) continue;
      point.confidence = PointConfidence(cost, agreeing);
      if (options.multiview_direction) {
        point.direction =
            MultiviewDirection(views, geometry, p, point.direction, point.views, sin_tolerance);
      }
      std::sort(point.views.begin(), point.views.end());
      out.push_back(std::move(point));
    }
  }
  return out;
}

struct CellKey {
  int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellKeyHash {
  size_t operator()(const CellKey& k) const {
    return static_cast<size_t>(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
  }
};

// Merges points per cell of `cell_mm`: the most confident point stays, with
// every merged point's views.
std::vector<OrientedPoint> MergeByCell(std::vector<OrientedPoint> points, double cell_mm) {
  std::unordered_map<CellKey, size_t, CellKeyHash> cells;
  cells.reserve(points.size());
  std::vector<OrientedPoint> out;
  for (OrientedPoint& p : points) {
    const CellKey key{static_cast<int64_t>(std::floor(p.position_mm.x() / cell_mm)),
                      static_cast<int64_t>(std::floor(p.position_mm.y() / cell_mm)),
                      static_cast<int64_t>(std::floor(p.position_mm.z() / cell_mm))};
    const auto [it, inserted] = cells.try_emplace(key, out.size());
    if (inserted) {
      out.push_back(std::move(p));
      continue;
    }
    OrientedPoint& kept = out[it->second];
    std::vector<uint16_t> views = kept.views;
    views.insert(views.end(), p.views.begin(), p.views.end());
    std::sort(views.begin(), views.end());
    views.erase(std::unique(views.begin(), views.end()), views.end());
    if (p.confidence > kept.confidence) kept = std::move(p);
    kept.views = std::move(views);
  }
  return out;
}

}  // namespace

Status FusionOptions::Check() const {
  if (!(max_cost > 0 && max_cost <= 1)) return InvalidArgument("fusion max_cost must be in (0, 1]");
  if (!(depth_tolerance_mm > 0))
    return InvalidArgument("fusion depth_tolerance_mm must be positive");
  if (!(angle_tolerance_deg > 0 && angle_tolerance_deg <= 90))
    return InvalidArgument("fusion angle_tolerance_deg must be in (0, 90]");
  if (agreement_radius_cells < 0 || agreement_radius_cells > 3)
    return InvalidArgument("fusion agreement_radius_cells must lie in 0..3");
  if (min_agreeing_views < 0)
    return InvalidArgument("fusion min_agreeing_views must not be negative");
  if (!(merge_mm >= 0.01)) return InvalidArgument("fusion merge_mm must be at least 0.01");
  if (!(mls_sigma_mm >= 0 && mls_sigma_mm <= 50))
    return InvalidArgument("fusion mls_sigma_mm must be in [0, 50]");
  if (!(direction_sigma_mm >= 0 && direction_sigma_mm <= 50))
    return InvalidArgument("fusion direction_sigma_mm must be in [0, 50]");
  if (threads < 1) return InvalidArgument("fusion threads must be at least 1");
  return Status::Ok();
}

Result<std::vector<OrientedPoint>> FusePoints(const std::vector<MvsView>& views,
                                              const std::vector<LineDepthMap>& maps,
                                              const FusionOptions& options,
                                              FusionSummary* summary) {
  HR_RETURN_IF_ERROR(options.Check());
  if (views.size() != maps.size())
    return InvalidArgument("fusion: " + std::to_string(views.size()) + " views but " +
                           std::to_string(maps.size()) + " depth maps");
  if (views.size() > 65535) return InvalidArgument("fusion: at most 65,535 views");
  std::vector<ViewGeometry> geometry(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    geometry[v].params = views[v].camera.ToParams();
    geometry[v].cam_from_object_rotation = views[v].cam_from_object.RotationMatrix();
    geometry[v].cam_from_object_translation = views[v].cam_from_object.translation;
    geometry[v].object_from_cam = views[v].cam_from_object.Inverse();
  }
  std::vector<std::vector<OrientedPoint>> per_view(views.size());
  std::vector<CellCounts> counts(views.size());
  ParallelFor(views.size(), options.threads, [&] {
    return [&](size_t r) {
      per_view[r] = ConsistentPoints(views, maps, geometry, r, options, &counts[r]);
    };
  });
  std::vector<OrientedPoint> all;
  FusionSummary s;
  for (size_t r = 0; r < views.size(); ++r) {
    s.candidates += counts[r].candidates;
    s.depth_pairs += counts[r].depth_pairs;
    s.direction_pairs += counts[r].direction_pairs;
    s.depth_confirmed += counts[r].depth_confirmed;
    all.insert(all.end(), std::make_move_iterator(per_view[r].begin()),
               std::make_move_iterator(per_view[r].end()));
    per_view[r].clear();
    per_view[r].shrink_to_fit();
  }
  s.consistent = static_cast<int64_t>(all.size());
  std::vector<OrientedPoint> merged = MergeByCell(std::move(all), options.merge_mm);
  if (options.mls_sigma_mm > 0) {
    merged = SmoothByMls(merged, options.mls_sigma_mm, options.threads);
    s.mls = true;
  }
  if (options.direction_sigma_mm > 0) {
    // Only neighbours whose direction agrees within the fusion's tolerance.
    merged = SmoothDirections(std::move(merged), options.direction_sigma_mm,
                              std::cos(DegToRad(options.angle_tolerance_deg)), options.threads);
    s.smoothed_directions = true;
  }
  s.points = static_cast<int64_t>(merged.size());
  if (summary != nullptr) *summary = s;
  return merged;
}

}  // namespace hairrig
