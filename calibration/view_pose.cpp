#include "calibration/view_pose.h"

#include <cmath>
#include <map>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace hairrig {

namespace {

bool CornersFinite(const TagDetection& d) {
  for (const auto& c : d.corners_px) {
    if (!c.allFinite()) return false;
  }
  return true;
}

// Corner reprojection RMS of one tag under a pose (pixels, full camera model).
double TagRmsPx(const TagObservation& tag, const Rigid3d& cam_from_box, const CameraIntrinsics& intrinsics) {
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector2d uv;
    if (!ProjectChecked(intrinsics, cam_from_box * tag.corners_box_mm[static_cast<size_t>(k)], &uv)) return INFINITY;
    sum += (uv - tag.corners_px[static_cast<size_t>(k)]).squaredNorm();
  }
  return std::sqrt(sum / 4);
}

Rigid3d FromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(r, rotation);
  return Rigid3d(rotation, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

std::string Summary(const std::vector<RejectedTag>& rejected) {
  std::string text;
  for (const RejectedTag& r : rejected) text += (text.empty() ? "" : "; ") + ("tag " + std::to_string(r.id) + ": " + r.reason);
  return text.empty() ? "no tag of the box was detected" : text;
}

}  // namespace

ViewObservations MatchToBox(const std::vector<TagDetection>& detections, const CalibBox& box) {
  ViewObservations out;
  std::map<int, int> seen;
  for (const TagDetection& d : detections) ++seen[d.id];
  for (const TagDetection& d : detections) {
    const BoxTag* tag = box.FindTag(d.id);
    if (!tag) {
      out.rejected.push_back({d.id, "not on the calibration box (another tag in view?)"});
    } else if (seen[d.id] > 1) {
      out.rejected.push_back({d.id, "seen " + std::to_string(seen[d.id]) + " times in one view (a reflection or a second copy?)"});
    } else if (!CornersFinite(d)) {
      out.rejected.push_back({d.id, "corners are not finite"});
    } else {
      out.tags.push_back({d.id, d.corners_px, tag->corners_box_mm});
    }
  }
  return out;
}

Result<ViewPose> EstimateViewPose(const ViewObservations& observations, const CameraIntrinsics& intrinsics,
                                  const ViewPoseOptions& options) {
  HR_RETURN_IF_ERROR(intrinsics.Validate());
  ViewPose pose;
  pose.rejected = observations.rejected;
  // Undistorted (normalised) corners, so that PnP sees a pinhole camera.
  std::vector<const TagObservation*> usable;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const TagObservation& tag : observations.tags) {
    std::array<Eigen::Vector2d, 4> normalised;
    bool ok = true;
    for (int k = 0; k < 4 && ok; ++k) {
      auto n = UndistortPixel(intrinsics, tag.corners_px[static_cast<size_t>(k)]);
      ok = n.ok();
      if (ok) normalised[static_cast<size_t>(k)] = *n;
    }
    if (!ok) {
      pose.rejected.push_back({tag.id, "a corner cannot be undistorted (outside the lens model's range)"});
      continue;
    }
    usable.push_back(&tag);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& p = tag.corners_box_mm[static_cast<size_t>(k)];
      object.emplace_back(p.x(), p.y(), p.z());
      image.emplace_back(normalised[static_cast<size_t>(k)].x(), normalised[static_cast<size_t>(k)].y());
    }
  }
  if (static_cast<int>(usable.size()) < options.min_tags) {
    return FailedPrecondition("view pose: " + std::to_string(usable.size()) + " usable tag(s), " +
                              std::to_string(options.min_tags) + " needed (" + Summary(pose.rejected) + ")");
  }
  // Hypotheses from single tags (IPPE: both poses of a planar square), each
  // scored by how many tags agree with it: a RANSAC over tags, exhaustive
  // because a view holds at most a few dozen.
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  Rigid3d rough;
  size_t best_inliers = 0;
  double best_error = INFINITY;
  for (size_t t = 0; t < usable.size(); ++t) {
    const std::vector<cv::Point3d> tag_object(object.begin() + static_cast<long>(4 * t), object.begin() + static_cast<long>(4 * t + 4));
    const std::vector<cv::Point2d> tag_image(image.begin() + static_cast<long>(4 * t), image.begin() + static_cast<long>(4 * t + 4));
    std::vector<cv::Mat> rvecs, tvecs;
    cv::solvePnPGeneric(tag_object, tag_image, identity, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE);
    for (size_t h = 0; h < rvecs.size(); ++h) {
      const Rigid3d candidate = FromRvecTvec(rvecs[h], tvecs[h]);
      size_t inliers = 0;
      double error = 0;
      for (const TagObservation* tag : usable) {
        const double rms = TagRmsPx(*tag, candidate, intrinsics);
        if (rms < options.ransac_threshold_px) {
          ++inliers;
          error += rms;
        }
      }
      if (inliers > best_inliers || (inliers == best_inliers && error < best_error)) {
        best_inliers = inliers;
        best_error = error;
        rough = candidate;
      }
    }
  }
  cv::Mat rvec, tvec;
  std::vector<cv::Point3d> kept_object;
  std::vector<cv::Point2d> kept_image;
  std::vector<const TagObservation*> kept;
  // Refine on the hypothesis' inliers, then judge every tag under the refined pose.
  for (int pass = 0; pass < 2; ++pass) {
    kept.clear();
    kept_object.clear();
    kept_image.clear();
    for (size_t t = 0; t < usable.size(); ++t) {
      const double rms = TagRmsPx(*usable[t], rough, intrinsics);
      const double limit = pass == 0 ? options.ransac_threshold_px : options.max_tag_rms_px;
      if (rms > limit) {
        if (pass == 1) {
          pose.rejected.push_back({usable[t]->id, "corners disagree with the box model (" + std::to_string(rms) +
                                                      " px RMS under the view's pose)"});
        }
        continue;
      }
      kept.push_back(usable[t]);
      for (int k = 0; k < 4; ++k) {
        kept_object.push_back(object[4 * t + static_cast<size_t>(k)]);
        kept_image.push_back(image[4 * t + static_cast<size_t>(k)]);
      }
    }
    if (static_cast<int>(kept.size()) < options.min_tags) break;
    Eigen::Vector3d aa = rough.AngleAxis();
    rvec = (cv::Mat_<double>(3, 1) << aa.x(), aa.y(), aa.z());
    tvec = (cv::Mat_<double>(3, 1) << rough.translation.x(), rough.translation.y(), rough.translation.z());
    cv::solvePnPRefineLM(kept_object, kept_image, identity, cv::noArray(), rvec, tvec);
    rough = FromRvecTvec(rvec, tvec);
  }
  if (static_cast<int>(kept.size()) < options.min_tags) {
    return FailedPrecondition("view pose: " + std::to_string(kept.size()) + " tag(s) agree with the box, " +
                              std::to_string(options.min_tags) + " needed (" + Summary(pose.rejected) + ")");
  }
  pose.cam_from_box = rough;
  double sum = 0;
  for (const TagObservation* tag : kept) {
    const double rms = TagRmsPx(*tag, pose.cam_from_box, intrinsics);
    sum += rms * rms;
  }
  pose.rms_px = std::sqrt(sum / static_cast<double>(kept.size()));
  pose.tags_used = static_cast<int>(kept.size());
  return pose;
}

}  // namespace hairrig
