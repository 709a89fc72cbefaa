#include "calibration/bundle_adjustment.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "calibration/corner_cost.h"
#include "core/transform.h"

namespace hairrig {

namespace {

constexpr double kDegToRad = kPi / 180;

// A box point in the turntable mode's camera frame:
// cam_from_world * Rz(theta) * turntable_from_box * p_box.
template <typename T>
CornerVec3<T> TurntablePoint(const T* q_cam_from_world, const T* t_cam_from_world,
                             const T* theta_rad, const T* q_turntable_from_box,
                             const T* t_turntable_from_box, const CornerVec3<T>& p_box) {
  const CornerVec3<T> p_tt = PosedPoint(q_turntable_from_box, t_turntable_from_box, p_box);
  const T c = cos(theta_rad[0]), s = sin(theta_rad[0]);
  const CornerVec3<T> p_world(c * p_tt.x() - s * p_tt.y(), s * p_tt.x() + c * p_tt.y(), p_tt.z());
  return PosedPoint(q_cam_from_world, t_cam_from_world, p_world);
}

// A box corner in the turntable mode (TurntablePoint).
struct TurntableCorner {
  Eigen::Vector2d observed;
  Eigen::Vector3d p_box;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_world, const T* t_cam_from_world,
                  const T* theta_rad, const T* q_turntable_from_box, const T* t_turntable_from_box,
                  T* residual) const {
    const CornerVec3<T> p_cam =
        TurntablePoint(q_cam_from_world, t_cam_from_world, theta_rad, q_turntable_from_box,
                       t_turntable_from_box, CornerVec3<T>(p_box.cast<T>()));
    return ProjectResidual(intrinsics, p_cam, observed, residual);
  }
};

// Point (a, b) of a tag's own frame on the box being refined: TagPointInBox
// with the delta blocks of the tag's face and of the tag.
struct RefinedBoxPoint {
  const BoxFace* face = nullptr;
  const BoxTag* tag = nullptr;
  double a_mm = 0, b_mm = 0;
  template <typename T>
  CornerVec3<T> operator()(const T* face_delta, const T* tag_delta) const {
    return TagPointInBox(*face, *tag, a_mm, b_mm, face_delta, tag_delta);
  }
};

// TurntableCorner with the corner on the box being refined.
struct TurntableRefinedCorner {
  Eigen::Vector2d observed;
  RefinedBoxPoint point;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_world, const T* t_cam_from_world,
                  const T* theta_rad, const T* q_turntable_from_box, const T* t_turntable_from_box,
                  const T* face_delta, const T* tag_delta, T* residual) const {
    const CornerVec3<T> p_cam =
        TurntablePoint(q_cam_from_world, t_cam_from_world, theta_rad, q_turntable_from_box,
                       t_turntable_from_box, point(face_delta, tag_delta));
    return ProjectResidual(intrinsics, p_cam, observed, residual);
  }
};

// PosedCorner (calibration/corner_cost.h) with the corner on the box being refined.
struct PosedRefinedCorner {
  Eigen::Vector2d observed;
  RefinedBoxPoint point;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_box, const T* t_cam_from_box,
                  const T* face_delta, const T* tag_delta, T* residual) const {
    return ProjectResidual(intrinsics,
                           PosedPoint(q_cam_from_box, t_cam_from_box, point(face_delta, tag_delta)),
                           observed, residual);
  }
};

// A Gaussian prior holding a box delta block (3 values) at 0: delta / sd,
// scaled by the corner noise (*sigma_px) as IntrinsicsPrior is. Held values
// (sd 0) give 0.
struct BoxDeltaPrior {
  std::array<double, 3> inverse_sd;
  const double* sigma_px;
  template <typename T>
  bool operator()(const T* delta, T* residual) const {
    for (size_t i = 0; i < 3; ++i) residual[i] = delta[i] * T(inverse_sd[i] * *sigma_px);
    return true;
  }
};

// The box refinement's gauge: the observed tags' corners keep their mean
// position (3 rows: the sum of their displacements) and their mean orientation
// (3 rows: the sum of (rest - centroid) x displacement, over the corners' RMS
// radius), each weighted by `weight` per mm. Parameters: the face delta blocks,
// then the tag delta blocks; point i uses blocks face_block[i] and tag_block[i].
struct BoxGauge {
  std::vector<RefinedBoxPoint> points;
  std::vector<int> face_block, tag_block;
  std::vector<Eigen::Vector3d> rest;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double radius_mm = 1;
  double weight = 1;
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    CornerVec3<T> sum_moved = CornerVec3<T>::Zero(), sum_turned = CornerVec3<T>::Zero();
    for (size_t i = 0; i < points.size(); ++i) {
      const CornerVec3<T> moved =
          points[i](parameters[face_block[i]], parameters[tag_block[i]]) - rest[i].cast<T>();
      sum_moved += moved;
      sum_turned += CornerVec3<T>((rest[i] - centroid).cast<T>()).cross(moved);
    }
    for (int k = 0; k < 3; ++k) {
      residual[k] = T(weight) * sum_moved[k];
      residual[3 + k] = T(weight / radius_mm) * sum_turned[k];
    }
    return true;
  }
};

// A Gaussian prior on a camera's intrinsics: (k - k_prior) / sd, scaled by
// the corner noise (*sigma_px) so that it weighs like the corner residuals,
// whose variance the covariance is scaled by. Held parameters (sd 0) give 0.
struct IntrinsicsPrior {
  std::array<double, CameraIntrinsics::kNumParams> prior;
  std::array<double, CameraIntrinsics::kNumParams> inverse_sd;
  const double* sigma_px;
  template <typename T>
  bool operator()(const T* intrinsics, T* residual) const {
    for (int i = 0; i < CameraIntrinsics::kNumParams; ++i)
      residual[i] = (intrinsics[i] - T(prior[static_cast<size_t>(i)])) *
                    T(inverse_sd[static_cast<size_t>(i)] * *sigma_px);
    return true;
  }
};

bool HasStddev(const std::array<double, CameraIntrinsics::kNumParams>& sd) {
  for (double v : sd)
    if (v > 0) return true;
  return false;
}

// A pose as two Ceres parameter blocks in Blocks' arena: quaternion (Eigen
// order x, y, z, w) and translation.
struct PoseBlock {
  double* q = nullptr;
  double* t = nullptr;
  void Set(const Rigid3d& pose) {
    const Eigen::Quaterniond r = pose.rotation.normalized();
    q[0] = r.x(), q[1] = r.y(), q[2] = r.z(), q[3] = r.w();
    t[0] = pose.translation.x(), t[1] = pose.translation.y(), t[2] = pose.translation.z();
  }
  Rigid3d ToRigid() const {
    return Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
  }
};

// Every parameter block of the problem, all in one arena laid out in a fixed
// order (intrinsics per camera, view poses, turntable_from_box, cam_from_world
// per camera, stop angles, then with box refinement the face and tag deltas):
// Ceres orders parameter blocks by address in places (the blocks of an
// elimination group, the covariance's), so blocks in separate allocations
// could give results whose last bits vary from run to run.
struct Blocks {
  Blocks(const BundleAdjustmentInput& input, bool turntable_mode, bool refine_box)
      : turntable(turntable_mode), box(&input.box) {
    std::set<int> stops, tags, faces;
    for (const CalibrationView& v : input.views) {
      stops.insert(v.stop);
      for (const TagObservation& tag : v.tags) {
        const BoxTag* t = refine_box ? box->FindTag(tag.id) : nullptr;
        if (t != nullptr) tags.insert(t->id), faces.insert(t->face);
      }
    }
    const size_t cameras = input.cameras.size(), views = turntable ? 0 : input.views.size();
    const size_t poses = views + (turntable ? 1 + cameras : 0);
    arena.assign(cameras * CameraIntrinsics::kNumParams + poses * 7 +
                     (turntable ? stops.size() : 0) + 3 * (tags.size() + faces.size()),
                 0.0);
    double* next = arena.data();
    auto take = [&next](size_t n) { return std::exchange(next, next + n); };
    auto take_pose = [&take]() { return PoseBlock{take(4), take(3)}; };
    for (size_t c = 0; c < cameras; ++c) intrinsics.push_back(take(CameraIntrinsics::kNumParams));
    for (size_t v = 0; v < views; ++v) view_poses.push_back(take_pose());
    if (turntable) {
      turntable_from_box = take_pose();
      for (size_t c = 0; c < cameras; ++c) cam_from_world.push_back(take_pose());
      for (int stop : stops) stop_rad[stop] = take(1);
    }
    for (int face : faces) face_delta[face] = take(3);
    for (int id : tags) tag_delta[id] = take(3);
  }
  Blocks(const Blocks&) = delete;
  Blocks& operator=(const Blocks&) = delete;

  bool turntable = false;
  const CalibBox* box = nullptr;
  std::vector<double> arena;              // sized once: the pointers below point into it
  std::vector<double*> intrinsics;        // per camera, CameraIntrinsics::kNumParams each
  std::vector<PoseBlock> view_poses;      // free mode, per view
  PoseBlock turntable_from_box;           // turntable mode
  std::vector<PoseBlock> cam_from_world;  // turntable mode, per camera
  std::map<int, double*> stop_rad;        // turntable mode, per stop
  std::map<int, double*> face_delta;      // box refinement, per face index: offset, tilts (rad)
  std::map<int, double*> tag_delta;       // box refinement, per tag id: du, dv, turn (rad)

  bool Refined(const TagObservation& tag) const { return tag_delta.count(tag.id) > 0; }

  // Corner k of an observed tag on the box being refined (RefinedBoxPoint).
  RefinedBoxPoint Point(const TagObservation& tag, size_t k) const {
    const BoxTag* t = box->FindTag(tag.id);
    return {&box->faces[static_cast<size_t>(t->face)], t, kTagCornerSigns[k][0] * 0.5 * t->size_mm,
            kTagCornerSigns[k][1] * 0.5 * t->size_mm};
  }

  // Corner k of an observed tag in the box frame, as the blocks hold it now.
  Eigen::Vector3d Corner(const TagObservation& tag, size_t k) const {
    if (!Refined(tag)) return tag.corners_box_mm[k];
    const RefinedBoxPoint p = Point(tag, k);
    return p(static_cast<const double*>(face_delta.at(p.tag->face)),
             static_cast<const double*>(tag_delta.at(tag.id)));
  }

  Rigid3d CamFromBox(const CalibrationView& v, size_t view_index) const {
    if (!turntable) return view_poses[view_index].ToRigid();
    return cam_from_world[static_cast<size_t>(v.camera)].ToRigid() *
           WorldFromTurntable(*stop_rad.at(v.stop) / kDegToRad) * turntable_from_box.ToRigid();
  }

  // The blocks (pointer, ambient size) a view's pose and projections depend on.
  std::vector<std::pair<double*, int>> Of(const CalibrationView& v, size_t view_index) {
    std::vector<std::pair<double*, int>> out{
        {intrinsics[static_cast<size_t>(v.camera)], CameraIntrinsics::kNumParams}};
    if (!turntable) {
      out.insert(out.end(), {{view_poses[view_index].q, 4}, {view_poses[view_index].t, 3}});
    } else {
      PoseBlock& cw = cam_from_world[static_cast<size_t>(v.camera)];
      out.insert(out.end(), {{cw.q, 4},
                             {cw.t, 3},
                             {stop_rad.at(v.stop), 1},
                             {turntable_from_box.q, 4},
                             {turntable_from_box.t, 3}});
    }
    std::set<double*> box_blocks;
    for (const TagObservation& tag : v.tags) {
      if (!Refined(tag)) continue;
      box_blocks.insert(face_delta.at(box->FindTag(tag.id)->face));
      box_blocks.insert(tag_delta.at(tag.id));
    }
    for (double* block : box_blocks) out.emplace_back(block, 3);
    return out;
  }
};

// Sum of the squared corner reprojection errors of one view (px^2).
double ViewSquaredError(const Blocks& blocks, const CalibrationView& v, size_t view_index) {
  const Rigid3d pose = blocks.CamFromBox(v, view_index);
  const CameraIntrinsics k =
      CameraIntrinsics::FromParams(blocks.intrinsics[static_cast<size_t>(v.camera)], 1, 1);
  double sq = 0;
  for (const TagObservation& tag : v.tags)
    for (size_t i = 0; i < 4; ++i)
      sq += (Project(k, pose * blocks.Corner(tag, i)) - tag.corners_px[i]).squaredNorm();
  return sq;
}

// The corner residuals' standard deviation per coordinate (px) for
// `effective_parameters` estimated; NaN without redundancy.
double CornerResidualSigma(const Blocks& blocks, const BundleAdjustmentInput& input,
                           int effective_parameters) {
  double sq = 0, corners = 0;
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    sq += ViewSquaredError(blocks, input.views[vi], vi);
    corners += 4.0 * static_cast<double>(input.views[vi].tags.size());
  }
  const double dof = 2.0 * corners - effective_parameters;
  return dof > 0 ? std::sqrt(sq / dof) : NAN;
}

// What a view's blocks predict: the rotation vector taking `reference` to the
// current cam_from_box (rad), the camera centre in the box frame (mm) and the
// projections of the view's observed corners (px).
Eigen::VectorXd Predict(const Blocks& blocks, const CalibrationView& v, size_t view_index,
                        const Rigid3d& reference) {
  const Rigid3d pose = blocks.CamFromBox(v, view_index);
  const CameraIntrinsics k =
      CameraIntrinsics::FromParams(blocks.intrinsics[static_cast<size_t>(v.camera)], 1, 1);
  Eigen::VectorXd out(6 + 8 * static_cast<Eigen::Index>(v.tags.size()));
  const Eigen::AngleAxisd delta(pose.rotation * reference.rotation.conjugate());
  out.head<3>() = delta.angle() * delta.axis();
  out.segment<3>(3) = pose.Inverse().translation;
  Eigen::Index row = 6;
  for (const TagObservation& tag : v.tags) {
    for (size_t i = 0; i < 4; ++i) {
      out.segment<2>(row) = Project(k, pose * blocks.Corner(tag, i));
      row += 2;
    }
  }
  return out;
}

// The standard deviations of a box delta block's three values (mm or rad); 0
// for held values, NaN where the covariance has no block.
std::array<double, 3> DeltaStddev(const ceres::Covariance& covariance, ceres::Problem& problem,
                                  const double* block, double sigma_px) {
  if (problem.IsParameterBlockConstant(const_cast<double*>(block))) return {0, 0, 0};
  Eigen::Matrix3d cov;  // symmetric: Ceres' row-major order reads the same
  if (!covariance.GetCovarianceBlock(block, block, cov.data())) return {NAN, NAN, NAN};
  std::array<double, 3> sd;
  for (Eigen::Index i = 0; i < 3; ++i)
    sd[static_cast<size_t>(i)] = sigma_px * std::sqrt(std::max(0.0, cov(i, i)));
  return sd;
}

// Box refinement's standard deviations, into the moves and the refined box.
void FillBoxUncertainties(const ceres::Covariance& covariance, ceres::Problem& problem,
                          const Blocks& blocks, double sigma_px, BundleAdjustmentResult* result) {
  for (FaceRefinement& move : result->face_moves) {
    const auto sd = DeltaStddev(covariance, problem, blocks.face_delta.at(move.face), sigma_px);
    move.moved_sd_mm = sd[0];
    move.tilted_sd_deg = std::max(sd[1], sd[2]) / kDegToRad;
    BoxFace& face = result->box.faces[static_cast<size_t>(move.face)];
    face.offset_sd_mm = move.moved_sd_mm;
    face.tilt_sd_deg = move.tilted_sd_deg;
  }
  for (TagRefinement& move : result->tag_moves) {
    const auto sd = DeltaStddev(covariance, problem, blocks.tag_delta.at(move.id), sigma_px);
    move.moved_sd_mm = {sd[0], sd[1]};
    move.turned_sd_deg = sd[2] / kDegToRad;
    for (BoxTag& tag : result->box.tags) {
      if (tag.id != move.id) continue;
      tag.center_sd_mm = move.moved_sd_mm;
      tag.turn_sd_deg = move.turned_sd_deg;
    }
  }
}

// The standard deviations of the estimated intrinsics and the ViewUncertainty
// of every view, from one covariance of the estimate (in the ambient
// coordinates of the blocks, scaled by the residuals' variance; a held block
// contributes nothing and keeps standard deviations of 0). Views are
// propagated through Predict by central differences. A rank-deficient problem
// leaves NaN.
void FillUncertainties(ceres::Problem& problem, Blocks& blocks, const BundleAdjustmentInput& input,
                       BundleAdjustmentResult* result) {
  const double sigma_px = result->residual_sigma_px;
  if (!std::isfinite(sigma_px)) return;
  std::vector<ViewUncertainty>& out = result->view_uncertainty;
  std::vector<std::vector<std::pair<double*, int>>> view_blocks(input.views.size());
  std::set<std::pair<const double*, const double*>> pairs;
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    for (const auto& block : blocks.Of(input.views[vi], vi)) {
      if (problem.HasParameterBlock(block.first) && !problem.IsParameterBlockConstant(block.first))
        view_blocks[vi].push_back(block);
    }
    for (const auto& a : view_blocks[vi])
      for (const auto& b : view_blocks[vi])
        pairs.emplace(std::min(a.first, b.first), std::max(a.first, b.first));
  }
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  options.null_space_rank = -1;
  ceres::Covariance covariance(options);
  const bool ok = covariance.Compute(
      std::vector<std::pair<const double*, const double*>>(pairs.begin(), pairs.end()), &problem);
  for (size_t c = 0; c < blocks.intrinsics.size(); ++c) {
    const double* intr = blocks.intrinsics[c];
    if (!problem.HasParameterBlock(intr) || problem.IsParameterBlockConstant(intr)) {
      result->intrinsics_covariance[c].setZero();
      continue;
    }
    IntrinsicsCovariance block;  // symmetric: Ceres' row-major order reads the same
    const bool have = ok && covariance.GetCovarianceBlock(intr, intr, block.data());
    if (have) result->intrinsics_covariance[c] = sigma_px * sigma_px * block;
    for (int i = 0; i < CameraIntrinsics::kNumParams; ++i)
      result->intrinsics_stddev[c][static_cast<size_t>(i)] =
          have ? sigma_px * std::sqrt(std::max(0.0, block(i, i))) : NAN;
  }
  if (!ok) return;
  FillBoxUncertainties(covariance, problem, blocks, sigma_px, result);
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    const CalibrationView& v = input.views[vi];
    if (v.tags.empty()) continue;
    std::vector<const double*> pointers;
    int n = 0;
    for (const auto& block : view_blocks[vi]) pointers.push_back(block.first), n += block.second;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> cov(n, n);
    if (!covariance.GetCovarianceMatrix(pointers, cov.data())) continue;
    const Rigid3d reference = blocks.CamFromBox(v, vi);
    Eigen::MatrixXd jacobian(6 + 8 * static_cast<Eigen::Index>(v.tags.size()), n);
    int column = 0;
    for (const auto& [data, size] : view_blocks[vi]) {
      for (int i = 0; i < size; ++i, ++column) {
        const double saved = data[i];
        const double h = 1e-6 * std::max(1.0, std::abs(saved));
        data[i] = saved + h;
        const Eigen::VectorXd plus = Predict(blocks, v, vi, reference);
        data[i] = saved - h;
        const Eigen::VectorXd minus = Predict(blocks, v, vi, reference);
        data[i] = saved;
        jacobian.col(column) = (plus - minus) / (2 * h);
      }
    }
    const Eigen::MatrixXd predicted = sigma_px * sigma_px * jacobian * cov * jacobian.transpose();
    ViewUncertainty& u = out[vi];
    u.rotation_cov_rad2 = predicted.block<3, 3>(0, 0);
    u.centre_cov_mm2 = predicted.block<3, 3>(3, 3);
    u.rotation_sd_deg = std::sqrt(std::max(0.0, u.rotation_cov_rad2.trace())) / kDegToRad;
    u.centre_sd_mm = std::sqrt(std::max(0.0, u.centre_cov_mm2.trace()));
    const Eigen::Index corners = 4 * static_cast<Eigen::Index>(v.tags.size());
    u.projection_sd_px =
        std::sqrt(std::max(0.0, predicted.bottomRightCorner(2 * corners, 2 * corners).trace() /
                                    static_cast<double>(corners)));
  }
}

Status ValidateInput(const BundleAdjustmentInput& input) {
  if (input.cameras.empty()) return InvalidArgument("bundle adjustment: no camera");
  std::vector<int> views_of(input.cameras.size(), 0);
  size_t corners = 0;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    const Status s = input.cameras[c].Check();
    if (!s.ok()) return s.WithContext("bundle adjustment: camera " + std::to_string(c));
  }
  for (size_t v = 0; v < input.views.size(); ++v) {
    const CalibrationView& view = input.views[v];
    if (view.camera < 0 || view.camera >= static_cast<int>(input.cameras.size())) {
      return InvalidArgument("bundle adjustment: view " + std::to_string(v) + " names camera " +
                             std::to_string(view.camera) + ", which does not exist");
    }
    if (view.stop < 0 || !std::isfinite(view.turntable_deg)) {
      return InvalidArgument("bundle adjustment: view " + std::to_string(v) +
                             " has a bad stop or turntable angle");
    }
    if (!view.tags.empty()) ++views_of[static_cast<size_t>(view.camera)];
    corners += 4 * view.tags.size();
  }
  for (size_t c = 0; c < views_of.size(); ++c) {
    if (views_of[c] == 0) {
      return InvalidArgument("bundle adjustment: camera " + std::to_string(c) +
                             " has no view with tags: check its frames, exposure and focus");
    }
  }
  if (corners == 0) return InvalidArgument("bundle adjustment: no tag corner observed in any view");
  return Status::Ok();
}

// Box refinement needs every observed tag on the input box.
Status CheckBoxHasObservedTags(const BundleAdjustmentInput& input) {
  for (size_t v = 0; v < input.views.size(); ++v) {
    for (const TagObservation& tag : input.views[v].tags) {
      if (input.box.FindTag(tag.id) == nullptr) {
        return InvalidArgument("bundle adjustment: view " + std::to_string(v) + " observes tag " +
                               std::to_string(tag.id) +
                               ", which the box to refine does not have: give the box the tags "
                               "were matched to");
      }
    }
  }
  return Status::Ok();
}

// The parameter blocks' initial values: the input's, the turntable mode's derived from them.
void InitialiseBlocks(const BundleAdjustmentInput& input, bool turntable, Blocks& b) {
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    const auto params = input.cameras[c].ToParams();
    std::copy(params.begin(), params.end(), b.intrinsics[c]);
  }
  for (size_t v = 0; v < b.view_poses.size(); ++v)
    b.view_poses[v].Set(input.views[v].cam_from_box_init);

  // Turntable mode: cameras from their best-observed view, angles from the encoder.
  auto& turntable_from_box = b.turntable_from_box;
  auto& cam_from_world = b.cam_from_world;
  auto& stop_rad = b.stop_rad;
  if (turntable) {
    turntable_from_box.Set(input.turntable_from_box_init);
    for (PoseBlock& cw : cam_from_world) cw.Set(Rigid3d());
    std::set<int> stops_set;
    std::vector<size_t> best_tags(input.cameras.size(), 0);
    for (const CalibrationView& v : input.views) {
      if (stops_set.insert(v.stop).second)
        *stop_rad.at(v.stop) = v.turntable_deg * kDegToRad;  // the first view's
      if (v.tags.size() <= best_tags[static_cast<size_t>(v.camera)]) continue;
      best_tags[static_cast<size_t>(v.camera)] = v.tags.size();
      cam_from_world[static_cast<size_t>(v.camera)].Set(
          v.cam_from_box_init * input.turntable_from_box_init.Inverse() *
          WorldFromTurntable(v.turntable_deg).Inverse());
    }
  }
}

// One corner's residual on the box being refined.
void AddRefinedCornerResidual(const CalibrationView& v, size_t view_index,
                              const TagObservation& tag, size_t k, ceres::LossFunction* loss,
                              Blocks& b, ceres::Problem& problem) {
  double* intr = b.intrinsics[static_cast<size_t>(v.camera)];
  const RefinedBoxPoint point = b.Point(tag, k);
  double* face = b.face_delta.at(point.tag->face);
  double* tag_block = b.tag_delta.at(tag.id);
  if (b.turntable) {
    auto* cost = new ceres::AutoDiffCostFunction<TurntableRefinedCorner, 2, 9, 4, 3, 1, 4, 3, 3, 3>(
        new TurntableRefinedCorner{tag.corners_px[k], point});
    PoseBlock& cw = b.cam_from_world[static_cast<size_t>(v.camera)];
    problem.AddResidualBlock(cost, loss, intr, cw.q, cw.t, b.stop_rad.at(v.stop),
                             b.turntable_from_box.q, b.turntable_from_box.t, face, tag_block);
  } else {
    auto* cost = new ceres::AutoDiffCostFunction<PosedRefinedCorner, 2, 9, 4, 3, 3, 3>(
        new PosedRefinedCorner{tag.corners_px[k], point});
    PoseBlock& pose = b.view_poses[view_index];
    problem.AddResidualBlock(cost, loss, intr, pose.q, pose.t, face, tag_block);
  }
}

// The residual blocks: one per observed corner, view by view, under one shared Huber loss.
void AddCornerResiduals(const BundleAdjustmentInput& input, const BundleAdjustmentOptions& options,
                        bool turntable, Blocks& b, ceres::Problem& problem) {
  auto& intrinsics = b.intrinsics;
  auto& view_poses = b.view_poses;
  auto& turntable_from_box = b.turntable_from_box;
  auto& cam_from_world = b.cam_from_world;
  auto& stop_rad = b.stop_rad;
  ceres::LossFunction* loss =
      new ceres::HuberLoss(options.huber_px);  // shared; the problem deletes it once
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    const CalibrationView& v = input.views[vi];
    double* intr = intrinsics[static_cast<size_t>(v.camera)];
    for (const TagObservation& tag : v.tags) {
      for (size_t k = 0; k < 4; ++k) {
        if (b.Refined(tag)) {
          AddRefinedCornerResidual(v, vi, tag, k, loss, b, problem);
        } else if (turntable) {
          auto* cost = new ceres::AutoDiffCostFunction<TurntableCorner, 2, 9, 4, 3, 1, 4, 3>(
              new TurntableCorner{tag.corners_px[k], tag.corners_box_mm[k]});
          PoseBlock& cw = cam_from_world[static_cast<size_t>(v.camera)];
          problem.AddResidualBlock(cost, loss, intr, cw.q, cw.t, stop_rad.at(v.stop),
                                   turntable_from_box.q, turntable_from_box.t);
        } else {
          auto* cost = new ceres::AutoDiffCostFunction<PosedCorner, 2, 9, 4, 3>(
              new PosedCorner{tag.corners_px[k], tag.corners_box_mm[k]});
          problem.AddResidualBlock(cost, loss, intr, view_poses[vi].q, view_poses[vi].t);
        }
      }
    }
  }
}

// The intrinsics' manifolds (k3 held), holds and priors; true when a prior is soft.
bool HoldIntrinsics(const BundleAdjustmentInput& input, const BundleAdjustmentOptions& options,
                    Blocks& b, double* prior_sigma_px, ceres::Problem& problem) {
  auto& intrinsics = b.intrinsics;
  bool soft_prior = false;
  for (size_t c = 0; c < intrinsics.size(); ++c) {
    double* intr = intrinsics[c];
    if (!problem.HasParameterBlock(intr)) continue;
    const bool has_sd = c < input.prior_stddev.size() && HasStddev(input.prior_stddev[c]);
    if (!options.fix_intrinsics) {
      problem.SetManifold(intr,
                          new ceres::SubsetManifold(CameraIntrinsics::kNumParams, {8}));  // k3 held
    } else if (options.hard_prior || !has_sd) {
      problem.SetParameterBlockConstant(intr);
    } else {
      IntrinsicsPrior prior{{}, {}, prior_sigma_px};
      std::copy(intr, intr + CameraIntrinsics::kNumParams, prior.prior.begin());
      std::vector<int> held;
      for (int i = 0; i < CameraIntrinsics::kNumParams; ++i) {
        const double sd = input.prior_stddev[c][static_cast<size_t>(i)];
        prior.inverse_sd[static_cast<size_t>(i)] = sd > 0 ? 1.0 / sd : 0.0;
        if (!(sd > 0)) held.push_back(i);
      }
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<IntrinsicsPrior, CameraIntrinsics::kNumParams,
                                          CameraIntrinsics::kNumParams>(new IntrinsicsPrior(prior)),
          nullptr, intr);
      if (!held.empty())
        problem.SetManifold(intr, new ceres::SubsetManifold(CameraIntrinsics::kNumParams, held));
      soft_prior = true;
    }
  }
  return soft_prior;
}

// A delta block's prior with standard deviations `sd` (0: held exactly).
void HoldBoxDelta(double* block, const std::array<double, 3>& sd, const double* sigma_px,
                  ceres::Problem& problem) {
  BoxDeltaPrior prior{{}, sigma_px};
  std::vector<int> held;
  for (size_t i = 0; i < 3; ++i) {
    prior.inverse_sd[i] = sd[i] > 0 ? 1.0 / sd[i] : 0.0;
    if (!(sd[i] > 0)) held.push_back(static_cast<int>(i));
  }
  if (held.size() == 3) {
    problem.SetParameterBlockConstant(block);
    return;
  }
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<BoxDeltaPrior, 3, 3>(new BoxDeltaPrior(prior)), nullptr,
      block);
  if (!held.empty()) problem.SetManifold(block, new ceres::SubsetManifold(3, held));
}

// Box refinement: every face and tag delta block held by its prior (the input
// box's own standard deviations where it states them, else the tolerance's).
void HoldBox(const BoxTolerance& tolerance, Blocks& b, const double* sigma_px,
             ceres::Problem& problem) {
  const auto either = [](double own, double fallback) { return own > 0 ? own : fallback; };
  for (const auto& [index, block] : b.face_delta) {
    const BoxFace& face = b.box->faces[static_cast<size_t>(index)];
    const double tilt_rad = either(face.tilt_sd_deg, tolerance.face_tilt_deg) * kDegToRad;
    HoldBoxDelta(block, {either(face.offset_sd_mm, tolerance.face_offset_mm), tilt_rad, tilt_rad},
                 sigma_px, problem);
  }
  for (const auto& [id, block] : b.tag_delta) {
    const BoxTag& tag = *b.box->FindTag(id);
    HoldBoxDelta(block,
                 {either(tag.center_sd_mm.x(), tolerance.tag_center_mm),
                  either(tag.center_sd_mm.y(), tolerance.tag_center_mm),
                  either(tag.turn_sd_deg, tolerance.tag_turn_deg) * kDegToRad},
                 sigma_px, problem);
  }
}

// Box refinement's gauge (BoxGauge) over every corner of the refined tags.
void FixBoxGauge(Blocks& b, ceres::Problem& problem) {
  BoxGauge gauge;
  std::vector<double*> parameters;
  std::map<const double*, int> index;
  for (auto* blocks : {&b.face_delta, &b.tag_delta}) {
    for (const auto& [key, block] : *blocks) {
      index[block] = static_cast<int>(parameters.size());
      parameters.push_back(block);
    }
  }
  for (const auto& [id, block] : b.tag_delta) {
    TagObservation tag;
    tag.id = id;
    for (size_t k = 0; k < 4; ++k) {
      gauge.points.push_back(b.Point(tag, k));
      gauge.face_block.push_back(index.at(b.face_delta.at(gauge.points.back().tag->face)));
      gauge.tag_block.push_back(index.at(block));
      gauge.rest.push_back(gauge.points.back().tag->corners_box_mm[k]);
    }
  }
  if (gauge.points.empty()) return;
  for (const Eigen::Vector3d& p : gauge.rest) gauge.centroid += p;
  gauge.centroid /= static_cast<double>(gauge.rest.size());
  double sq = 0;
  for (const Eigen::Vector3d& p : gauge.rest) sq += (p - gauge.centroid).squaredNorm();
  gauge.radius_mm = std::max(1.0, std::sqrt(sq / static_cast<double>(gauge.rest.size())));
  // A mean drift of 1 um weighs as much as a corner residual of 1 px.
  gauge.weight = 1e3 / static_cast<double>(gauge.points.size());
  auto* cost = new ceres::DynamicAutoDiffCostFunction<BoxGauge, 4>(new BoxGauge(gauge));
  for (size_t i = 0; i < parameters.size(); ++i) cost->AddParameterBlock(3);
  cost->SetNumResiduals(6);
  problem.AddResidualBlock(cost, nullptr, parameters);
}

// The poses' quaternion manifolds and, in turntable mode, the gauge (box height, first stop).
void FixGauge(bool turntable, Blocks& b, ceres::Problem& problem) {
  auto& view_poses = b.view_poses;
  auto& turntable_from_box = b.turntable_from_box;
  auto& cam_from_world = b.cam_from_world;
  auto& stop_rad = b.stop_rad;
  if (turntable) {
    for (PoseBlock& cw : cam_from_world) {
      if (problem.HasParameterBlock(cw.q))
        problem.SetManifold(cw.q, new ceres::EigenQuaternionManifold);
    }
    problem.SetManifold(turntable_from_box.q, new ceres::EigenQuaternionManifold);
    problem.SetManifold(turntable_from_box.t,
                        new ceres::SubsetManifold(3, {2}));       // height along the axis
    problem.SetParameterBlockConstant(stop_rad.begin()->second);  // the turn about the axis
  } else {
    for (PoseBlock& p : view_poses) {
      if (problem.HasParameterBlock(p.q))
        problem.SetManifold(p.q, new ceres::EigenQuaternionManifold);
    }
  }
}

// The solve; with a soft prior, a second one with the prior weighed against the noise found.
void SolveProblem(const BundleAdjustmentInput& input, const BundleAdjustmentOptions& options,
                  bool turntable, bool soft_prior, const Blocks& b, double* prior_sigma_px,
                  ceres::Problem& problem, ceres::Solver::Summary* summary) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = turntable ? ceres::DENSE_QR : ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = options.threads;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  ceres::Solve(solver, &problem, summary);
  if (soft_prior && summary->IsSolutionUsable()) {
    // Weigh the prior against the corner noise actually found, and solve again.
    *prior_sigma_px = CornerResidualSigma(b, input, summary->num_effective_parameters);
    ceres::Solve(solver, &problem, summary);
  }
}

// Box refinement's moves and the refined box (standard deviations set by FillUncertainties).
void ReadRefinedBox(const BundleAdjustmentInput& input, const Blocks& b,
                    BundleAdjustmentResult* result) {
  if (b.tag_delta.empty()) return;
  result->box_refined = true;
  result->box = input.box;
  for (const auto& [index, delta] : b.face_delta) {
    FaceRefinement move;
    move.face = index;
    move.moved_mm = delta[0];
    move.tilted_u_deg = delta[1] / kDegToRad;
    move.tilted_v_deg = delta[2] / kDegToRad;
    result->face_moves.push_back(move);
    BoxFace& face = result->box.faces[static_cast<size_t>(index)];
    face.offset_mm += move.moved_mm;
    face.tilt_u_deg += move.tilted_u_deg;
    face.tilt_v_deg += move.tilted_v_deg;
  }
  std::map<int, int> views_of;
  for (const CalibrationView& v : input.views)
    for (const TagObservation& tag : v.tags) ++views_of[tag.id];
  for (const auto& [id, delta] : b.tag_delta) {
    TagRefinement move;
    move.id = id;
    move.views = views_of[id];
    move.moved_mm = {delta[0], delta[1]};
    move.turned_deg = delta[2] / kDegToRad;
    result->tag_moves.push_back(move);
    for (BoxTag& tag : result->box.tags) {
      if (tag.id != id) continue;
      tag.center_face_mm += move.moved_mm;
      tag.turn_deg += move.turned_deg;
    }
  }
  PlaceTags(&result->box);
}

// The result: the estimate and its reprojection errors, its uncertainties sized but unset.
BundleAdjustmentResult ReadResult(const BundleAdjustmentInput& input, bool turntable,
                                  const Blocks& b, const ceres::Solver::Summary& summary) {
  auto& intrinsics = b.intrinsics;
  auto& turntable_from_box = b.turntable_from_box;
  auto& cam_from_world = b.cam_from_world;
  auto& stop_rad = b.stop_rad;
  BundleAdjustmentResult result;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    result.cameras.push_back(CameraIntrinsics::FromParams(intrinsics[c], input.cameras[c].width_px,
                                                          input.cameras[c].height_px));
  }
  if (turntable) {
    result.turntable_from_box = turntable_from_box.ToRigid();
    for (const PoseBlock& cw : cam_from_world) result.cam_from_world.push_back(cw.ToRigid());
    int last_stop = stop_rad.empty() ? -1 : stop_rad.rbegin()->first;
    result.stop_deg.assign(static_cast<size_t>(last_stop + 1), NAN);
    for (const auto& [stop, rad] : stop_rad)
      result.stop_deg[static_cast<size_t>(stop)] = *rad / kDegToRad;
  }
  double total_sq = 0;
  size_t total_corners = 0;
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    const CalibrationView& v = input.views[vi];
    result.cam_from_box.push_back(b.CamFromBox(v, vi));
    const double sq = ViewSquaredError(b, v, vi);
    const size_t corners = 4 * v.tags.size();
    result.view_rms_px.push_back(corners ? std::sqrt(sq / static_cast<double>(corners)) : NAN);
    total_sq += sq;
    total_corners += corners;
  }
  result.rms_px = std::sqrt(total_sq / static_cast<double>(total_corners));
  const double dof = 2.0 * static_cast<double>(total_corners) - summary.num_effective_parameters;
  result.residual_sigma_px = dof > 0 ? std::sqrt(total_sq / dof) : NAN;
  result.intrinsics_stddev.assign(input.cameras.size(), {});
  result.intrinsics_covariance.assign(input.cameras.size(), IntrinsicsCovariance::Constant(NAN));
  result.view_uncertainty.assign(input.views.size(), {});
  ReadRefinedBox(input, b, &result);
  return result;
}

}  // namespace

Status BundleAdjustmentOptions::Check() const {
  if (!(huber_px > 0) || !std::isfinite(huber_px))
    return InvalidArgument("huber_px must be a finite positive number of pixels");
  if (max_iterations < 1) {
    return InvalidArgument("max_iterations must be at least 1, got " +
                           std::to_string(max_iterations));
  }
  if (threads < 1)
    return InvalidArgument("threads must be at least 1, got " + std::to_string(threads));
  return box_tolerance.Check().WithContext("box_tolerance");
}

Result<BundleAdjustmentResult> RunBundleAdjustment(const BundleAdjustmentInput& input,
                                                   const BundleAdjustmentOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("bundle adjustment"));
  HR_RETURN_IF_ERROR(ValidateInput(input));
  const bool turntable = options.mode == CalibrationMode::kTurntable;
  const bool refine_box = !options.box_tolerance.Zero();
  if (refine_box) HR_RETURN_IF_ERROR(CheckBoxHasObservedTags(input));
  ceres::Problem problem;
  Blocks b(input, turntable, refine_box);
  InitialiseBlocks(input, turntable, b);
  AddCornerResiduals(input, options, turntable, b, problem);
  double prior_sigma_px =
      1.0;  // the corner noise the priors weigh against; updated after a first solve
  bool soft_prior = HoldIntrinsics(input, options, b, &prior_sigma_px, problem);
  if (refine_box) {
    HoldBox(options.box_tolerance, b, &prior_sigma_px, problem);
    FixBoxGauge(b, problem);
    soft_prior = true;
  }
  FixGauge(turntable, b, problem);
  ceres::Solver::Summary summary;
  SolveProblem(input, options, turntable, soft_prior, b, &prior_sigma_px, problem, &summary);
  if (!summary.IsSolutionUsable()) {
    return FailedPrecondition("bundle adjustment did not converge: " + summary.message);
  }
  BundleAdjustmentResult result = ReadResult(input, turntable, b, summary);
  FillUncertainties(problem, b, input, &result);
  return result;
}

}  // namespace hairrig
