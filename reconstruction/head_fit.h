// A head for the strands when nobody gives one: an ellipsoid and its scalp
// fitted to what the segmented views see of the subject (the head/skin and
// hair labels of hair_segmentation.h).
//
//  1. The subject's visual hull (visual_hull.h) from the labels: head or hair
//     is the subject, the box is carved like the backdrop (else the hull
//     keeps the box's volume and skin pixels' rays stop on it).
//  2. Surface samples: every `stride_px`-th head or hair pixel of each view
//     cast onto the hull's front surface, pooled on a `voxel_mm` grid, each
//     cell labelled skin or hair by the majority of its samples.
//  3. The ellipsoid (centre and radii along the object frame's axes): every
//     surface sample lies outside it (the hull holds the head, and hair lies
//     on it), the skin samples lie on it (a Cauchy loss: the neck and the
//     mannequin's base are skin that is not the skull), the hair samples
//     near it (a weaker Cauchy loss), and radii near a typical adult head's
//     (a Gaussian prior, so that the hair-covered back of the head has a
//     size). A grid search over the centre, then Ceres, with the face along
//     x and along y, the cheaper kept. The centre must lie inside the hull
//     and within the largest typical radius of the skin: elsewhere an
//     ellipsoid in empty space contradicts no sample, and the skin's
//     saturating loss hardly grows with the distance.
//  4. The scalp: centred on the ellipsoid; the face direction is where the
//     skin on the ellipsoid is (horizontal mean); the hairline is ScalpSpec's
//     typical one. The skin the views see does not bound the hairline: a
//     parting shows skin on the crown, bangs hide the forehead and long hair
//     the nape (on the demo capture the highest skin per sector was 10 to
//     70 deg off the true hairline). No parting: the views cannot tell a
//     bare line from a wig's parting.
//
// Frames and units: the views' object frame must be in mm with +z up (the
// turntable frame of a capture): the prior, the grids and the horizontal face
// direction assume it, so a COLMAP model's arbitrary frame does not do. The
// ellipsoid's axes are the frame's: a head turned 45 deg about z gets radii
// in between its width and depth (a HeadSpec ellipsoid has no rotation).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/head_spec.h"
#include "core/status.h"
#include "core/transform.h"
#include "reconstruction/views.h"

namespace hairrig {

struct HeadFitView {
  CameraIntrinsics camera;
  Rigid3d cam_from_object;
  cv::Mat1b label;  // SegmentLabel per pixel (hair_segmentation.h), the camera's size
};

struct HeadFitOptions {
  double voxel_mm = 3.0;  // the hull's and the samples' grid
  // A voxel stays in the hull unless more than this many views see it off
  // the subject (the box in front of the head, a segmentation error).
  int max_empty_views = 2;
  int stride_px = 4;           // every n-th pixel of each view, in both directions
  double skin_scale_mm = 5.0;  // the Cauchy scale of a skin sample's distance to the ellipsoid
  // Hair lies close over the scalp where it is short (the crown) and far
  // from it where it hangs: a hair sample's distance costs a Cauchy of this
  // scale, weighted against a skin sample's.
  double hair_scale_mm = 10.0;
  double hair_weight = 0.05;
  double outside_scale_mm = 1.0;  // a sample inside the ellipsoid costs (depth / this)^2 ...
  double outside_huber_mm = 3.0;  // ... up to this depth, then linearly (a stray sample)
  // The prior: a typical adult head's radii (x, y, z with the face along y;
  // swapped in x and y when the face is along x), sigma `radii_sigma_mm`,
  // weighted as `prior_samples` samples.
  Eigen::Vector3d typical_radii_mm{78, 95, 110};
  double radii_sigma_mm = 12.0;
  double prior_samples = 2000;
  int min_skin_samples = 30;  // fewer: no fit (the views show no skin)
  int threads = 2;

  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct HeadFitSummary {
  HeadSpec head;  // the ellipsoid (no mesh) and its scalp
  int views = 0;
  int64_t skin_samples = 0, hair_samples = 0;  // surface cells of each label
  double skin_on_surface_share = 0;            // skin samples within skin_scale_mm of the ellipsoid
  double inside_share = 0;     // samples more than 2 voxels inside it (should be ~0)
  bool face_measured = false;  // false: the skin is all around, face_dir kept at -y

  nlohmann::json ToJson() const;
  std::string BriefReport() const;  // a few lines for the CLI
};

// The distance (mm) from p to `head`'s ellipsoid along the ray from its
// centre: positive outside, negative inside; what the fit minimises.
double EllipsoidRadialDistance(const HeadSpec& head, const Eigen::Vector3d& p);

// InvalidArgument for bad options, fewer than two views or a label of
// another size than its camera; FailedPrecondition when the hull is empty
// (labels and calibration disagree), the views show fewer than
// min_skin_samples of skin, or no plausible centre settles (give the head
// instead).
Result<HeadFitSummary> FitHeadToViews(const std::vector<HeadFitView>& views,
                                      const HeadFitOptions& options);

// The same from the labels the point stage wrote for these views
// (<reconstruction_dir>/masks/<view name>_label.png, point_reconstruction.h);
// a view without its labels is left out. NotFound when fewer than two views
// have labels (run the points stage first); CorruptData naming a label file
// that is not 8-bit of its camera's size; otherwise as FitHeadToViews.
Result<HeadFitSummary> FitHeadToReconstruction(const std::vector<ReconstructionView>& views,
                                               const std::string& reconstruction_dir,
                                               const HeadFitOptions& options);

}  // namespace hairrig
