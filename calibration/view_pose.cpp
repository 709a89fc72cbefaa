#include "calibration/view_pose.h"

#include <cmath>
#include <map>

#include "calibration/planar_pose.h"

namespace hairrig {

namespace {

bool CornersFinite(const TagDetection& d) {
  for (const auto& c : d.corners_px) {
    if (!c.allFinite()) return false;
  }
  return true;
}

// Corner reprojection RMS of one tag under a pose (pixels, full camera model).
double TagRmsPx(const TagObservation& tag, const Rigid3d& cam_from_box,
                const CameraIntrinsics& intrinsics) {
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector2d uv;
    if (!ProjectChecked(intrinsics, cam_from_box * tag.corners_box_mm[static_cast<size_t>(k)], &uv))
      return INFINITY;
    sum += (uv - tag.corners_px[static_cast<size_t>(k)]).squaredNorm();
  }
  return std::sqrt(sum / 4);
}

// A tag's RMS beyond what a box off its model by `tolerance_mm` (one standard
// deviation) may give at the tag's distance: 3 tolerances, in pixels.
double TagMisfitPx(const TagObservation& tag, const Rigid3d& cam_from_box,
                   const CameraIntrinsics& intrinsics, double tolerance_mm) {
  const double rms = TagRmsPx(tag, cam_from_box, intrinsics);
  if (tolerance_mm <= 0 || !std::isfinite(rms)) return rms;
  double depth_mm = 0;
  for (const Eigen::Vector3d& corner : tag.corners_box_mm) depth_mm += (cam_from_box * corner).z();
  depth_mm /= 4;
  if (depth_mm <= 0) return rms;
  const double focal_px = 0.5 * (intrinsics.fx_px + intrinsics.fy_px);
  return std::max(0.0, rms - 3 * tolerance_mm * focal_px / depth_mm);
}

std::string Summary(const std::vector<RejectedTag>& rejected) {
  std::string text;
  for (const RejectedTag& r : rejected)
    text += (text.empty() ? "" : "; ") + ("tag " + std::to_string(r.id) + ": " + r.reason);
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
      out.rejected.push_back({d.id, "seen " + std::to_string(seen[d.id]) +
                                        " times in one view (a reflection or a second copy?)"});
    } else if (!CornersFinite(d)) {
      out.rejected.push_back({d.id, "corners are not finite"});
    } else {
      out.tags.push_back({d.id, d.corners_px, tag->corners_box_mm});
    }
  }
  return out;
}

Status ViewPoseOptions::Check() const {
  if (!(ransac_threshold_px > 0) || !std::isfinite(ransac_threshold_px))
    return InvalidArgument("ransac_threshold_px must be a finite positive number of pixels");
  if (!(max_tag_rms_px > 0) || !std::isfinite(max_tag_rms_px))
    return InvalidArgument("max_tag_rms_px must be a finite positive number of pixels");
  if (!(box_tolerance_mm >= 0) || !std::isfinite(box_tolerance_mm))
    return InvalidArgument("box_tolerance_mm must be a finite number of mm, 0 or more");
  if (min_tags < 1)
    return InvalidArgument("min_tags must be at least 1, got " + std::to_string(min_tags));
  return Status::Ok();
}

Result<ViewPose> EstimateViewPose(const ViewObservations& observations,
                                  const CameraIntrinsics& intrinsics,
                                  const ViewPoseOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("view pose"));
  HR_RETURN_IF_ERROR(intrinsics.Check());
  ViewPose pose;
  pose.rejected = observations.rejected;
  // Undistorted (normalised) corners, so that PnP sees a pinhole camera.
  std::vector<const TagObservation*> usable;
  std::vector<Eigen::Vector3d> object;
  std::vector<Eigen::Vector2d> image;
  std::vector<std::array<Eigen::Vector2d, 4>> usable_normalised;
  for (const TagObservation& tag : observations.tags) {
    std::array<Eigen::Vector2d, 4> normalised;
    bool ok = true;
    for (int k = 0; k < 4 && ok; ++k) {
      auto n = UndistortPixel(intrinsics, tag.corners_px[static_cast<size_t>(k)]);
      ok = n.ok();
      if (ok) normalised[static_cast<size_t>(k)] = *n;
    }
    if (!ok) {
      pose.rejected.push_back(
          {tag.id, "a corner cannot be undistorted (outside the lens model's range)"});
      continue;
    }
    usable.push_back(&tag);
    usable_normalised.push_back(normalised);
    object.insert(object.end(), tag.corners_box_mm.begin(), tag.corners_box_mm.end());
    image.insert(image.end(), normalised.begin(), normalised.end());
  }
  if (static_cast<int>(usable.size()) < options.min_tags) {
    return FailedPrecondition("view pose: " + std::to_string(usable.size()) + " usable tag(s), " +
                              std::to_string(options.min_tags) + " needed (" +
                              Summary(pose.rejected) + ")");
  }
  // Hypotheses from single tags (IPPE: both poses of a planar square), each
  // scored by how many tags agree with it: a RANSAC over tags, exhaustive
  // because a view holds at most a few dozen.
  Rigid3d rough;
  size_t best_inliers = 0;
  double best_error = INFINITY;
  for (size_t t = 0; t < usable.size(); ++t) {
    for (const Rigid3d& candidate :
         PlanarSquarePoses(usable[t]->corners_box_mm, usable_normalised[t])) {
      size_t inliers = 0;
      double error = 0;
      for (const TagObservation* tag : usable) {
        const double rms = TagMisfitPx(*tag, candidate, intrinsics, options.box_tolerance_mm);
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
  if (best_error == INFINITY) {
    return FailedPrecondition(
        "view pose: no tag gives a pose (every tag seen edge-on or degenerate; " +
        std::to_string(usable.size()) + " usable)");
  }
  std::vector<Eigen::Vector3d> kept_object;
  std::vector<Eigen::Vector2d> kept_image;
  std::vector<const TagObservation*> kept;
  // Refine on the hypothesis' inliers, then judge every tag under the refined pose.
  for (int pass = 0; pass < 2; ++pass) {
    kept.clear();
    kept_object.clear();
    kept_image.clear();
    for (size_t t = 0; t < usable.size(); ++t) {
      const double misfit = TagMisfitPx(*usable[t], rough, intrinsics, options.box_tolerance_mm);
      const double limit = pass == 0 ? options.ransac_threshold_px : options.max_tag_rms_px;
      if (misfit > limit) {
        if (pass == 1) {
          pose.rejected.push_back(
              {usable[t]->id, "corners disagree with the box model (" +
                                  std::to_string(TagRmsPx(*usable[t], rough, intrinsics)) +
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
    rough = RefinePose(kept_object, kept_image, rough).cam_from_model;
  }
  if (static_cast<int>(kept.size()) < options.min_tags) {
    return FailedPrecondition("view pose: " + std::to_string(kept.size()) +
                              " tag(s) agree with the box, " + std::to_string(options.min_tags) +
                              " needed (" + Summary(pose.rejected) + ")");
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
