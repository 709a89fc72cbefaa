#include "reconstruction/point_fusion.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/parallel.h"
#include "reconstruction/mls.h"

namespace hairrig {
namespace {

struct ViewGeometry {
  std::array<double, CameraIntrinsics::kNumParams> params{};
  Eigen::Matrix3d cam_from_object_rotation;
  Eigen::Vector3d cam_from_object_translation;
  Rigid3d object_from_cam;
};

// Does view w's map hold the same segment at p (object frame)?
bool Agrees(const ViewGeometry& g, const LineDepthMap& map, const Eigen::Vector3d& p,
            const Eigen::Vector3f& direction, const FusionOptions& options, double cos_tolerance) {
  const Eigen::Vector3d q = g.cam_from_object_rotation * p + g.cam_from_object_translation;
  if (q.z() <= 1.0) return false;
  double uv[2];
  ProjectCamPoint(g.params.data(), q.data(), uv);
  const int gx = static_cast<int>(std::lround(uv[0] / map.stride_px));
  const int gy = static_cast<int>(std::lround(uv[1] / map.stride_px));
  if (gx < 0 || gy < 0 || gx >= map.depth_mm.cols || gy >= map.depth_mm.rows) return false;
  const float depth = map.depth_mm(gy, gx);
  if (!(depth > 0) || map.cost(gy, gx) > options.max_cost) return false;
  if (std::abs(depth - q.z()) > options.depth_tolerance_mm) return false;
  const cv::Vec3f& d = map.direction(gy, gx);
  return std::abs(direction.dot(Eigen::Vector3f(d[0], d[1], d[2]))) >= cos_tolerance;
}

// The consistent points of reference view r, before merging.
std::vector<OrientedPoint> ConsistentPoints(const std::vector<MvsView>& views,
                                            const std::vector<LineDepthMap>& maps,
                                            const std::vector<ViewGeometry>& geometry, size_t r,
                                            const FusionOptions& options, int64_t* candidates) {
  std::vector<OrientedPoint> out;
  const LineDepthMap& map = maps[r];
  const double cos_tolerance = std::cos(DegToRad(options.angle_tolerance_deg));
  for (int gy = 0; gy < map.depth_mm.rows; ++gy) {
    for (int gx = 0; gx < map.depth_mm.cols; ++gx) {
      const float depth = map.depth_mm(gy, gx);
      const float cost = map.cost(gy, gx);
      if (!(depth > 0) || cost > options.max_cost) continue;
      const cv::Point2d px = GridPixel(map, gx, gy);
      const Result<Eigen::Vector2d> n =
          UndistortPixel(views[r].camera, Eigen::Vector2d(px.x, px.y));
      if (!n.ok()) continue;
      ++*candidates;
      const Eigen::Vector3d p =
          geometry[r].object_from_cam * (Eigen::Vector3d(n->x(), n->y(), 1.0) * depth);
      const cv::Vec3f& d = map.direction(gy, gx);
      OrientedPoint point;
      point.position_mm = p.cast<float>();
      point.direction = Eigen::Vector3f(d[0], d[1], d[2]);
      point.confidence = 1.0f - cost;
      point.views.push_back(static_cast<uint16_t>(r));
      for (size_t w = 0; w < views.size(); ++w) {
        if (w != r && Agrees(geometry[w], maps[w], p, point.direction, options, cos_tolerance))
          point.views.push_back(static_cast<uint16_t>(w));
      }
      if (static_cast<int>(point.views.size()) - 1 < options.min_agreeing_views) continue;
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
  if (min_agreeing_views < 0)
    return InvalidArgument("fusion min_agreeing_views must not be negative");
  if (!(merge_mm >= 0.01)) return InvalidArgument("fusion merge_mm must be at least 0.01");
  if (!(mls_sigma_mm >= 0 && mls_sigma_mm <= 50))
    return InvalidArgument("fusion mls_sigma_mm must be in [0, 50]");
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
  std::vector<int64_t> candidates(views.size(), 0);
  ParallelFor(views.size(), options.threads, [&] {
    return [&](size_t r) {
      per_view[r] = ConsistentPoints(views, maps, geometry, r, options, &candidates[r]);
    };
  });
  std::vector<OrientedPoint> all;
  FusionSummary s;
  for (size_t r = 0; r < views.size(); ++r) {
    s.candidates += candidates[r];
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
  s.points = static_cast<int64_t>(merged.size());
  if (summary != nullptr) *summary = s;
  return merged;
}

}  // namespace hairrig
