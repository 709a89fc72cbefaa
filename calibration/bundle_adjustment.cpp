#include "calibration/bundle_adjustment.h"

#include <cmath>
#include <map>
#include <string>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace hairrig {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180;

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

template <typename T>
bool ProjectResidual(const T* intrinsics, const Vec3<T>& p_cam, const Eigen::Vector2d& observed, T* residual) {
  T uv[2];
  ProjectCamPoint(intrinsics, p_cam.data(), uv);
  residual[0] = uv[0] - T(observed.x());
  residual[1] = uv[1] - T(observed.y());
  return true;
}

// A box corner seen in a view of the free mode: cam_from_box directly.
struct FreeCorner {
  Eigen::Vector2d observed;
  Eigen::Vector3d p_box;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_box, const T* t_cam_from_box, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_from_box);
    const Vec3<T> p_cam = q * p_box.cast<T>() + Eigen::Map<const Vec3<T>>(t_cam_from_box);
    return ProjectResidual(intrinsics, p_cam, observed, residual);
  }
};

// A box corner in the turntable mode: cam_from_world * Rz(theta) * turntable_from_box.
struct TurntableCorner {
  Eigen::Vector2d observed;
  Eigen::Vector3d p_box;
  template <typename T>
  bool operator()(const T* intrinsics, const T* q_cam_from_world, const T* t_cam_from_world, const T* theta_rad,
                  const T* q_turntable_from_box, const T* t_turntable_from_box, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_tb(q_turntable_from_box);
    const Vec3<T> p_tt = q_tb * p_box.cast<T>() + Eigen::Map<const Vec3<T>>(t_turntable_from_box);
    const T c = cos(theta_rad[0]), s = sin(theta_rad[0]);
    const Vec3<T> p_world(c * p_tt.x() - s * p_tt.y(), s * p_tt.x() + c * p_tt.y(), p_tt.z());
    const Eigen::Map<const Eigen::Quaternion<T>> q_cw(q_cam_from_world);
    const Vec3<T> p_cam = q_cw * p_world + Eigen::Map<const Vec3<T>>(t_cam_from_world);
    return ProjectResidual(intrinsics, p_cam, observed, residual);
  }
};

// A pose as Ceres parameter blocks: quaternion (Eigen order x, y, z, w) and translation.
struct PoseBlock {
  double q[4];
  double t[3];
  explicit PoseBlock(const Rigid3d& pose = Rigid3d()) {
    const Eigen::Quaterniond r = pose.rotation.normalized();
    q[0] = r.x(), q[1] = r.y(), q[2] = r.z(), q[3] = r.w();
    t[0] = pose.translation.x(), t[1] = pose.translation.y(), t[2] = pose.translation.z();
  }
  Rigid3d ToRigid() const { return Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2])); }
};

Status ValidateInput(const BundleAdjustmentInput& input) {
  if (input.cameras.empty()) return InvalidArgument("bundle adjustment: no camera");
  std::vector<int> views_of(input.cameras.size(), 0);
  size_t corners = 0;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    const Status s = input.cameras[c].Validate();
    if (!s.ok()) return s.WithContext("bundle adjustment: camera " + std::to_string(c));
  }
  for (size_t v = 0; v < input.views.size(); ++v) {
    const CalibrationView& view = input.views[v];
    if (view.camera < 0 || view.camera >= static_cast<int>(input.cameras.size())) {
      return InvalidArgument("bundle adjustment: view " + std::to_string(v) + " names camera " +
                             std::to_string(view.camera) + ", which does not exist");
    }
    if (view.stop < 0 || !std::isfinite(view.turntable_deg)) {
      return InvalidArgument("bundle adjustment: view " + std::to_string(v) + " has a bad stop or turntable angle");
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

}  // namespace

Result<BundleAdjustmentResult> RunBundleAdjustment(const BundleAdjustmentInput& input,
                                                   const BundleAdjustmentOptions& options) {
  HR_RETURN_IF_ERROR(ValidateInput(input));
  const bool turntable = options.mode == CalibrationMode::kTurntable;
  ceres::Problem problem;
  std::vector<std::array<double, CameraIntrinsics::kNumParams>> intrinsics;
  for (const CameraIntrinsics& c : input.cameras) intrinsics.push_back(c.ToParams());
  std::vector<PoseBlock> view_poses;
  for (const CalibrationView& v : input.views) view_poses.emplace_back(v.cam_from_box_init);

  // Turntable mode: cameras from their best-observed view, angles from the encoder.
  PoseBlock turntable_from_box(input.turntable_from_box_init);
  std::vector<PoseBlock> cam_from_world(input.cameras.size());
  std::map<int, double> stop_rad;
  if (turntable) {
    std::vector<size_t> best_tags(input.cameras.size(), 0);
    for (const CalibrationView& v : input.views) {
      stop_rad.emplace(v.stop, v.turntable_deg * kDegToRad);
      if (v.tags.size() <= best_tags[static_cast<size_t>(v.camera)]) continue;
      best_tags[static_cast<size_t>(v.camera)] = v.tags.size();
      cam_from_world[static_cast<size_t>(v.camera)] = PoseBlock(
          v.cam_from_box_init * input.turntable_from_box_init.Inverse() * WorldFromTurntable(v.turntable_deg).Inverse());
    }
  }

  ceres::LossFunction* loss = new ceres::HuberLoss(options.huber_px);  // shared; the problem deletes it once
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    const CalibrationView& v = input.views[vi];
    double* intr = intrinsics[static_cast<size_t>(v.camera)].data();
    for (const TagObservation& tag : v.tags) {
      for (size_t k = 0; k < 4; ++k) {
        if (turntable) {
          auto* cost = new ceres::AutoDiffCostFunction<TurntableCorner, 2, 9, 4, 3, 1, 4, 3>(
              new TurntableCorner{tag.corners_px[k], tag.corners_box_mm[k]});
          PoseBlock& cw = cam_from_world[static_cast<size_t>(v.camera)];
          problem.AddResidualBlock(cost, loss, intr, cw.q, cw.t, &stop_rad[v.stop], turntable_from_box.q,
                                   turntable_from_box.t);
        } else {
          auto* cost = new ceres::AutoDiffCostFunction<FreeCorner, 2, 9, 4, 3>(
              new FreeCorner{tag.corners_px[k], tag.corners_box_mm[k]});
          problem.AddResidualBlock(cost, loss, intr, view_poses[vi].q, view_poses[vi].t);
        }
      }
    }
  }
  // Manifolds and the gauge.
  for (auto& intr : intrinsics) {
    if (!problem.HasParameterBlock(intr.data())) continue;
    if (options.fix_intrinsics) {
      problem.SetParameterBlockConstant(intr.data());
    } else {
      problem.SetManifold(intr.data(), new ceres::SubsetManifold(CameraIntrinsics::kNumParams, {8}));  // k3 held
    }
  }
  if (turntable) {
    for (PoseBlock& cw : cam_from_world) {
      if (problem.HasParameterBlock(cw.q)) problem.SetManifold(cw.q, new ceres::EigenQuaternionManifold);
    }
    problem.SetManifold(turntable_from_box.q, new ceres::EigenQuaternionManifold);
    problem.SetManifold(turntable_from_box.t, new ceres::SubsetManifold(3, {2}));  // height along the axis
    problem.SetParameterBlockConstant(&stop_rad.begin()->second);                 // the turn about the axis
  } else {
    for (PoseBlock& p : view_poses) {
      if (problem.HasParameterBlock(p.q)) problem.SetManifold(p.q, new ceres::EigenQuaternionManifold);
    }
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = turntable ? ceres::DENSE_QR : ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = options.threads;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    return FailedPrecondition("bundle adjustment did not converge: " + summary.message);
  }

  BundleAdjustmentResult result;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    result.cameras.push_back(CameraIntrinsics::FromParams(intrinsics[c].data(), input.cameras[c].width_px,
                                                          input.cameras[c].height_px));
  }
  if (turntable) {
    result.turntable_from_box = turntable_from_box.ToRigid();
    for (const PoseBlock& cw : cam_from_world) result.cam_from_world.push_back(cw.ToRigid());
    int last_stop = stop_rad.empty() ? -1 : stop_rad.rbegin()->first;
    result.stop_deg.assign(static_cast<size_t>(last_stop + 1), NAN);
    for (const auto& [stop, rad] : stop_rad) result.stop_deg[static_cast<size_t>(stop)] = rad / kDegToRad;
  }
  double total_sq = 0;
  size_t total_corners = 0;
  for (size_t vi = 0; vi < input.views.size(); ++vi) {
    const CalibrationView& v = input.views[vi];
    const Rigid3d pose = turntable ? result.cam_from_world[static_cast<size_t>(v.camera)] *
                                         WorldFromTurntable(result.stop_deg[static_cast<size_t>(v.stop)]) *
                                         result.turntable_from_box
                                   : view_poses[vi].ToRigid();
    result.cam_from_box.push_back(pose);
    double sq = 0;
    for (const TagObservation& tag : v.tags) {
      for (size_t k = 0; k < 4; ++k) {
        sq += (Project(result.cameras[static_cast<size_t>(v.camera)], pose * tag.corners_box_mm[k]) - tag.corners_px[k])
                  .squaredNorm();
      }
    }
    const size_t corners = 4 * v.tags.size();
    result.view_rms_px.push_back(corners ? std::sqrt(sq / static_cast<double>(corners)) : NAN);
    total_sq += sq;
    total_corners += corners;
  }
  result.rms_px = std::sqrt(total_sq / static_cast<double>(total_corners));
  const double dof = 2.0 * static_cast<double>(total_corners) - summary.num_effective_parameters;
  result.residual_sigma_px = dof > 0 ? std::sqrt(total_sq / dof) : NAN;
  result.intrinsics_stddev.assign(input.cameras.size(), {});
  if (!options.fix_intrinsics && dof > 0) {
    // Covariance of the intrinsics (the gauge is fixed, so it exists); a
    // rank-deficient problem leaves the standard deviations at NaN.
    ceres::Covariance::Options covariance_options;
    covariance_options.algorithm_type = ceres::DENSE_SVD;
    covariance_options.null_space_rank = -1;
    ceres::Covariance covariance(covariance_options);
    std::vector<std::pair<const double*, const double*>> blocks;
    for (const auto& intr : intrinsics) blocks.emplace_back(intr.data(), intr.data());
    const bool ok = covariance.Compute(blocks, &problem);
    for (size_t c = 0; c < intrinsics.size(); ++c) {
      double block[CameraIntrinsics::kNumParams * CameraIntrinsics::kNumParams];
      const bool have = ok && covariance.GetCovarianceBlock(intrinsics[c].data(), intrinsics[c].data(), block);
      for (int i = 0; i < CameraIntrinsics::kNumParams; ++i) {
        result.intrinsics_stddev[c][static_cast<size_t>(i)] =
            have ? result.residual_sigma_px * std::sqrt(std::max(0.0, block[i * CameraIntrinsics::kNumParams + i]))
                 : NAN;
      }
    }
  }
  return result;
}

}  // namespace hairrig
