#include "reconstruction/strand_preview.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace hairrig {

cv::Mat RenderStrandPreview(const std::vector<const StrandSet*>& models, const std::vector<std::string>& labels,
                            const StrandPreviewOptions& o) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const StrandSet* m : models)
    for (const Eigen::Vector3f& p : m->points_mm) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (!(lo.array() <= hi.array()).all()) lo = hi = Eigen::Vector3f::Zero();
  const Eigen::Vector3f centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * (hi - lo).norm(), 1.0f);
  const double scale = 0.5 * o.view_px / radius * 0.95;
  const int cols = static_cast<int>(o.azimuths_deg.size());
  cv::Mat3b canvas(static_cast<int>(models.size()) * o.view_px, std::max(cols, 1) * o.view_px, cv::Vec3b(24, 24, 24));
  for (size_t m = 0; m < models.size(); ++m) {
    const StrandSet& set = *models[m];
    const std::vector<size_t> offsets = set.Offsets();
    const size_t step = std::max<size_t>(1, set.num_strands() / static_cast<size_t>(std::max(o.max_strands, 1)));
    for (int c = 0; c < cols; ++c) {
      const double a = o.azimuths_deg[c] * M_PI / 180;
      // The camera looks at the centre from azimuth a (0: from -y, the face side), +z up.
      const Eigen::Vector3f right(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0);
      const cv::Point2f origin(static_cast<float>(c * o.view_px + o.view_px / 2),
                               static_cast<float>(static_cast<int>(m) * o.view_px + o.view_px / 2));
      const auto project = [&](const Eigen::Vector3f& p) {
        const Eigen::Vector3f d = p - centre;
        return origin + cv::Point2f(static_cast<float>(scale * d.dot(right)), static_cast<float>(-scale * d.z()));
      };
      for (size_t s = 0; s < set.num_strands(); s += step) {
        for (size_t k = offsets[s] + 1; k < offsets[s + 1]; ++k) {
          const Eigen::Vector3f d = (set.points_mm[k] - set.points_mm[k - 1]).normalized().cwiseAbs();
          const cv::Scalar colour(40 + 200 * d.z(), 40 + 200 * d.y(), 40 + 200 * d.x());
          cv::line(canvas, project(set.points_mm[k - 1]), project(set.points_mm[k]), colour, 1, cv::LINE_AA);
        }
      }
    }
    if (m < labels.size()) {
      cv::putText(canvas, labels[m], cv::Point(8, static_cast<int>(m) * o.view_px + 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
  }
  return canvas;
}

}  // namespace hairrig
