#include "calibration/apriltag_detector.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
}

namespace hairrig {

struct TagDetector::Impl {
  TagDetectorOptions options;
  apriltag_family_t* family = nullptr;
  apriltag_detector_t* detector = nullptr;
  ~Impl() {
    if (detector) apriltag_detector_destroy(detector);
    if (family) tag36h11_destroy(family);
  }
};

TagDetector::TagDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TagDetector::~TagDetector() = default;

Status TagDetectorOptions::Check() const {
  if (!(decimate >= 0) || !std::isfinite(decimate))
    return InvalidArgument("decimate must be 0 (auto) or a finite positive factor");
  if (threads < 1) return InvalidArgument("threads must be at least 1");
  if (max_hamming < 0 || max_hamming > 3) {
    return InvalidArgument("max_hamming must lie in 0..3, got " + std::to_string(max_hamming));
  }
  return Status::Ok();
}

Result<std::unique_ptr<TagDetector>> TagDetector::Create(const TagDetectorOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("tag detector"));
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->family = tag36h11_create();
  impl->detector = apriltag_detector_create();
  if (!impl->family || !impl->detector) return Internal("libapriltag could not create a detector");
  apriltag_detector_add_family_bits(impl->detector, impl->family, options.max_hamming);
  impl->detector->nthreads = options.threads;
  impl->detector->refine_edges = true;
  impl->detector->quad_sigma = 0.0f;
  return std::unique_ptr<TagDetector>(new TagDetector(std::move(impl)));
}

Result<std::vector<TagDetection>> TagDetector::Detect(const cv::Mat& image) {
  if (image.empty()) return InvalidArgument("tag detector: empty image");
  cv::Mat gray;
  if (image.type() == CV_8UC1) {
    gray = image.isContinuous() ? image : image.clone();
  } else if (image.type() == CV_8UC3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else {
    return InvalidArgument("tag detector: expected an 8-bit grey or BGR image");
  }
  const int long_side = std::max(gray.cols, gray.rows);
  const double decimate = impl_->options.decimate > 0 ? impl_->options.decimate
                          : long_side <= 1000         ? 1.0
                          : long_side <= 3000         ? 2.0
                                                      : 3.0;
  impl_->detector->quad_decimate = static_cast<float>(decimate);
  // Debian's build exports no image_u8_create: wrap our buffer (not owned by libapriltag).
  image_u8_t wrapped{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]), gray.data};
  zarray_t* found = apriltag_detector_detect(impl_->detector, &wrapped);
  if (found == nullptr) return Internal("libapriltag returned no detection list");
  const double offset = impl_->options.subtract_half_pixel ? kApriltagToOpenCvOffsetPx : 0.0;
  std::vector<TagDetection> detections;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(found, i, &d);
    TagDetection t;
    t.id = d->id;
    t.hamming = d->hamming;
    t.decision_margin = d->decision_margin;
    for (int k = 0; k < 4; ++k)
      t.corners_px[k] = Eigen::Vector2d(d->p[k][0] + offset, d->p[k][1] + offset);
    detections.push_back(t);
  }
  apriltag_detections_destroy(found);
  return detections;
}

}  // namespace hairrig
