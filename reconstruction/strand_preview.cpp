#include "reconstruction/strand_preview.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/camera_model.h"
#include "core/image_file.h"

namespace hairrig {

namespace {

// A segment's colour: red x, green y, blue z of its unit direction's magnitudes (BGR).
cv::Scalar DirectionColour(const Eigen::Vector3f& from, const Eigen::Vector3f& to) {
  const Eigen::Vector3f d = (to - from).normalized().cwiseAbs();
  return cv::Scalar(40 + 200 * d.z(), 40 + 200 * d.y(), 40 + 200 * d.x());
}

size_t StrandStep(const StrandSet& set, int max_strands) {
  return std::max<size_t>(1, set.num_strands() / static_cast<size_t>(std::max(max_strands, 1)));
}

}  // namespace

namespace {

// One strand edge of a preview view: its end points in pixels, its depth
// (larger is nearer the viewer) and its colour.
struct PreviewEdge {
  cv::Point2f a, b;
  float depth;
  cv::Scalar colour;
};

// The edges of `set` seen from azimuth a (0: from -y, the face side; +z up),
// orthographic about `centre`, nearest last (the painter's order).
std::vector<PreviewEdge> ViewEdges(const StrandSet& set, size_t step, double azimuth_rad,
                                   const Eigen::Vector3f& centre, double scale,
                                   const cv::Point2f& origin) {
  const Eigen::Vector3f right(static_cast<float>(std::cos(azimuth_rad)),
                              static_cast<float>(std::sin(azimuth_rad)), 0);
  const Eigen::Vector3f towards_viewer = right.cross(Eigen::Vector3f::UnitZ());
  const std::vector<size_t> offsets = set.Offsets();
  const auto project = [&](const Eigen::Vector3f& p) {
    const Eigen::Vector3f d = p - centre;
    return origin + cv::Point2f(static_cast<float>(scale * d.dot(right)),
                                static_cast<float>(-scale * d.z()));
  };
  std::vector<PreviewEdge> edges;
  for (size_t s = 0; s < set.num_strands(); s += step) {
    for (size_t k = offsets[s] + 1; k < offsets[s + 1]; ++k) {
      const Eigen::Vector3f& p = set.points_mm[k - 1];
      const Eigen::Vector3f& q = set.points_mm[k];
      edges.push_back({project(p), project(q), (0.5f * (p + q) - centre).dot(towards_viewer),
                       DirectionColour(p, q)});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const PreviewEdge& x, const PreviewEdge& y) { return x.depth < y.depth; });
  return edges;
}

// InvalidArgument unless view_px lies in 16..4096.
Status CheckViewPx(int view_px) {
  if (view_px < 16 || view_px > 4096)
    return InvalidArgument("view_px must lie in 16..4096, got " + std::to_string(view_px));
  return Status::Ok();
}

}  // namespace

Status StrandPreviewOptions::Check() const {
  for (double azimuth : azimuths_deg) {
    if (!std::isfinite(azimuth)) return InvalidArgument("azimuths_deg must be finite");
  }
  HR_RETURN_IF_ERROR(CheckViewPx(view_px));
  if (max_strands < 1)
    return InvalidArgument("max_strands must be at least 1, got " + std::to_string(max_strands));
  return Status::Ok();
}

Status StrandOverlayOptions::Check() const {
  HR_RETURN_IF_ERROR(CheckViewPx(view_px));
  if (max_strands < 1)
    return InvalidArgument("max_strands must be at least 1, got " + std::to_string(max_strands));
  if (!(opacity >= 0 && opacity <= 1)) return InvalidArgument("opacity must lie in [0, 1]");
  return Status::Ok();
}

Result<cv::Mat> RenderStrandPreview(const std::vector<const StrandSet*>& models,
                                    const std::vector<std::string>& labels,
                                    const StrandPreviewOptions& o) {
  HR_RETURN_IF_ERROR(o.Check().WithContext("strand preview"));
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const StrandSet* m : models)
    for (const Eigen::Vector3f& p : m->points_mm) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (!(lo.array() <= hi.array()).all()) lo = hi = Eigen::Vector3f::Zero();
  const Eigen::Vector3f centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * (hi - lo).norm(), 1.0f);
  const double scale = 0.5 * o.view_px / radius * 0.95;
  const int cols = static_cast<int>(o.azimuths_deg.size());
  cv::Mat3b canvas(static_cast<int>(models.size()) * o.view_px, std::max(cols, 1) * o.view_px,
                   cv::Vec3b(24, 24, 24));
  for (size_t m = 0; m < models.size(); ++m) {
    const StrandSet& set = *models[m];
    for (int c = 0; c < cols; ++c) {
      const cv::Point2f origin(static_cast<float>(c * o.view_px + o.view_px / 2),
                               static_cast<float>(static_cast<int>(m) * o.view_px + o.view_px / 2));
      for (const PreviewEdge& e :
           ViewEdges(set, StrandStep(set, o.max_strands), o.azimuths_deg[c] * M_PI / 180, centre,
                     scale, origin)) {
        // Depth cueing: the far side at 35 % brightness, the near side at full.
        const double brightness = 0.35 + 0.65 * std::clamp(0.5 + 0.5 * e.depth / radius, 0.0, 1.0);
        cv::line(canvas, e.a, e.b, e.colour * brightness, 1, cv::LINE_AA);
      }
    }
    if (m < labels.size()) {
      cv::putText(canvas, labels[m], cv::Point(8, static_cast<int>(m) * o.view_px + 22),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
  }
  return cv::Mat(canvas);
}

namespace {

// The square about the strands' region in the view, grown by a fifth on every
// side and kept inside the image (the whole image when no strand is in front).
cv::Rect StrandRegion(const std::vector<cv::Point2f>& drawn, const cv::Size& image) {
  if (drawn.empty()) return cv::Rect(cv::Point(0, 0), image);
  const cv::Rect box = cv::boundingRect(drawn);
  const int side = std::max(box.width, box.height) * 7 / 5;
  const cv::Rect grown(box.x + box.width / 2 - side / 2, box.y + box.height / 2 - side / 2, side,
                       side);
  const cv::Rect clipped = grown & cv::Rect(cv::Point(0, 0), image);
  return clipped.area() > 0 ? clipped : cv::Rect(cv::Point(0, 0), image);
}

// The view's image with the strands drawn over it, cropped about them and
// scaled to `view_px` wide.
Result<cv::Mat3b> OverlayOneView(const ReconstructionView& view, const StrandSet& strands,
                                 const StrandOverlayOptions& o) {
  Result<cv::Mat> read = ReadImageFile(view.image_path, cv::IMREAD_COLOR);
  if (!read.ok()) return read.status().WithContext("the image of view " + view.name);
  const cv::Mat3b image = *read;
  cv::Mat3b lines = image.clone();
  const std::vector<size_t> offsets = strands.Offsets();
  const auto pixel = [&](const Eigen::Vector3f& p, cv::Point2f* uv) {
    Eigen::Vector2d px;
    if (!ProjectChecked(view.camera, view.cam_from_object * p.cast<double>(), &px)) return false;
    *uv = cv::Point2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
    return true;
  };
  std::vector<cv::Point2f> drawn;
  const int thickness = std::max(1, image.cols / 600);
  for (size_t s = 0; s < strands.num_strands(); s += StrandStep(strands, o.max_strands)) {
    for (size_t k = offsets[s] + 1; k < offsets[s + 1]; ++k) {
      cv::Point2f a, b;
      if (!pixel(strands.points_mm[k - 1], &a) || !pixel(strands.points_mm[k], &b)) continue;
      cv::line(lines, a, b, DirectionColour(strands.points_mm[k - 1], strands.points_mm[k]),
               thickness, cv::LINE_AA);
      drawn.push_back(b);
    }
  }
  cv::Mat3b blended;
  cv::addWeighted(lines, o.opacity, image, 1 - o.opacity, 0, blended);
  const cv::Rect region = StrandRegion(drawn, image.size());
  const double scale = static_cast<double>(o.view_px) / region.width;
  cv::Mat3b out;
  cv::resize(blended(region), out,
             cv::Size(o.view_px, static_cast<int>(std::lround(region.height * scale))), 0, 0,
             cv::INTER_AREA);
  cv::putText(out, view.name, cv::Point(8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return out;
}

}  // namespace

Result<cv::Mat> RenderStrandsOverViews(const std::vector<ReconstructionView>& views,
                                       const StrandSet& strands, const StrandOverlayOptions& o) {
  HR_RETURN_IF_ERROR(o.Check().WithContext("strands over views"));
  std::vector<cv::Mat3b> tiles;
  for (const ReconstructionView& view : views) {
    HR_ASSIGN_OR_RETURN(cv::Mat3b tile, OverlayOneView(view, strands, o));
    tiles.push_back(tile);
  }
  if (tiles.empty()) return cv::Mat();
  int height = 0;
  for (const cv::Mat3b& t : tiles) height = std::max(height, t.rows);
  cv::Mat3b canvas(height, o.view_px * static_cast<int>(tiles.size()), cv::Vec3b(0, 0, 0));
  for (size_t i = 0; i < tiles.size(); ++i) {
    tiles[i].copyTo(
        canvas(cv::Rect(static_cast<int>(i) * o.view_px, 0, tiles[i].cols, tiles[i].rows)));
  }
  return cv::Mat(canvas);
}

}  // namespace hairrig
