#include "calibration/intrinsics_from_views.h"

#include <ceres/ceres.h>
#include <ceres/product_manifold.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <map>

#include "calibration/corner_cost.h"

namespace hairrig {

namespace {

// One (view, face) pair: tag corners in the face's frame (mm, z = 0) and in the image (px).
struct Plane {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
};

// The tags of one view grouped by face, each face with 2 or more tags a plane.
void AddFacePlanes(const ViewObservations& view, const CalibBox& box, std::vector<Plane>* planes) {
  std::map<int, std::vector<const TagObservation*>> by_face;
  for (const TagObservation& tag : view.tags) {
    const BoxTag* model = box.FindTag(tag.id);
    if (model) by_face[model->face].push_back(&tag);
  }
  for (const auto& [face_index, tags] : by_face) {
    if (tags.size() < 2) continue;  // one square leaves the focal length ambiguous
    const BoxFace& face = box.faces[static_cast<size_t>(face_index)];
    Plane plane;
    for (const TagObservation* tag : tags) {
      for (size_t k = 0; k < 4; ++k) {
        const Eigen::Vector3d rel = tag->corners_box_mm[k] - face.center_box_mm;
        plane.points.emplace_back(rel.dot(face.right_box), rel.dot(face.down_box), 0.0);
        plane.pixels.push_back(tag->corners_px[k]);
      }
    }
    planes->push_back(std::move(plane));
  }
}

// Hartley's normalisation: centroid to the origin, mean distance sqrt(2).
Eigen::Matrix3d Normalisation(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double distance = 0;
  for (const Eigen::Vector2d& p : points) distance += (p - centroid).norm();
  const double scale =
      std::sqrt(2.0) * static_cast<double>(points.size()) / std::max(distance, 1e-12);
  Eigen::Matrix3d t;
  t << scale, 0, -scale * centroid.x(), 0, scale, -scale * centroid.y(), 0, 0, 1;
  return t;
}

Eigen::Vector2d Apply(const Eigen::Matrix3d& t, const Eigen::Vector2d& p) {
  return (t * p.homogeneous()).hnormalized();
}

// The homography taking face points (x, y) to pixels: the normalised direct
// linear transform (the null vector of the stacked constraints, from the
// 9 x 9 normal matrix's smallest eigenvector).
Eigen::Matrix3d PlaneHomography(const Plane& plane) {
  std::vector<Eigen::Vector2d> from, to;
  for (size_t i = 0; i < plane.points.size(); ++i) {
    from.push_back(plane.points[i].head<2>());
    to.push_back(plane.pixels[i]);
  }
  const Eigen::Matrix3d t_from = Normalisation(from), t_to = Normalisation(to);
  Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
  for (size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector2d p = Apply(t_from, from[i]), q = Apply(t_to, to[i]);
    Eigen::Matrix<double, 2, 9> rows;
    rows << p.x(), p.y(), 1, 0, 0, 0, -q.x() * p.x(), -q.x() * p.y(), -q.x(), 0, 0, 0, p.x(), p.y(),
        1, -q.y() * p.x(), -q.y() * p.y(), -q.y();
    normal += rows.transpose() * rows;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eigen(normal);
  const Eigen::Matrix<double, 9, 1> h = eigen.eigenvectors().col(0);
  Eigen::Matrix3d normalised;
  normalised << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return t_to.inverse() * normalised * t_from;
}

// Zhang 2000 Sec. 3.1 with zero skew and the principal point at `centre`:
// each homography's two constraints h1' B h2 = 0 and h1' B h1 = h2' B h2 on
// B = diag(1/fx^2, 1/fy^2, 1) (after moving the principal point to the
// origin) are linear in 1/fx^2 and 1/fy^2; least squares over the planes.
// False when the planes leave the focal lengths unconstrained.
bool FocalLengths(const std::vector<Eigen::Matrix3d>& homographies, const Eigen::Vector2d& centre,
                  double* fx, double* fy) {
  Eigen::Matrix3d shift;
  shift << 1, 0, -centre.x(), 0, 1, -centre.y(), 0, 0, 1;
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (const Eigen::Matrix3d& homography : homographies) {
    Eigen::Matrix3d h = shift * homography;
    h /= h.leftCols<2>().norm();  // every plane weighs alike, wherever it is in the image
    const Eigen::Vector3d h1 = h.col(0), h2 = h.col(1);
    Eigen::Matrix2d a;
    Eigen::Vector2d b;
    a << h1.x() * h2.x(), h1.y() * h2.y(), h1.x() * h1.x() - h2.x() * h2.x(),
        h1.y() * h1.y() - h2.y() * h2.y();
    b << -h1.z() * h2.z(), -(h1.z() * h1.z() - h2.z() * h2.z());
    normal += a.transpose() * a;
    rhs += a.transpose() * b;
  }
  const Eigen::Vector2d inverse_squares = normal.ldlt().solve(rhs);
  if (!(inverse_squares.x() > 0 && inverse_squares.y() > 0)) return false;
  *fx = 1 / std::sqrt(inverse_squares.x());
  *fy = 1 / std::sqrt(inverse_squares.y());
  return std::isfinite(*fx) && std::isfinite(*fy);
}

// Zhang 2000 Sec. 3.1: r1 = K^-1 h1 / |K^-1 h1|, r2 likewise, t = l K^-1 h3
// with l = 2 / (|K^-1 h1| + |K^-1 h2|) (the two norms differ where the
// starting K is off), the sign putting the plane in front of the camera, and
// the nearest rotation to [r1 r2 r1 x r2].
Rigid3d PoseFromHomography(const Eigen::Matrix3d& homography,
                           const Eigen::Matrix3d& camera_matrix) {
  const Eigen::Matrix3d m = camera_matrix.inverse() * homography;
  const double sign = m(2, 2) < 0 ? -1.0 : 1.0;
  const Eigen::Vector3d r1 = sign * m.col(0).normalized(), r2 = sign * m.col(1).normalized();
  const Eigen::Vector3d t = sign * 2 / (m.col(0).norm() + m.col(1).norm()) * m.col(2);
  Eigen::Matrix3d r;
  r << r1, r2, r1.cross(r2);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  if (rotation.determinant() < 0) {
    Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
    flip(2, 2) = -1;
    rotation = svd.matrixU() * flip * svd.matrixV().transpose();
  }
  return Rigid3d(rotation, t);
}

// A face corner under its plane's pose as one block: quaternion (x, y, z, w) then translation.
struct PlaneCorner {
  PosedCorner corner;
  template <typename T>
  bool operator()(const T* intrinsics, const T* pose, T* residual) const {
    return corner(intrinsics, pose, pose + 4, residual);
  }
};

// Zhang 2000 Sec. 3.2-3.3: Levenberg-Marquardt over the intrinsics (k3 held)
// and every plane's pose, the poses eliminated first (Schur). Returns the
// corner reprojection RMS (px); FailedPrecondition when Ceres finds no
// usable solution.
Result<double> RefineOverPlanes(const std::vector<Plane>& planes, double* intrinsics,
                                std::vector<Rigid3d>* poses) {
  // One allocation: Ceres orders an elimination group's blocks by address,
  // which is then the planes' order in every process.
  std::vector<double> pose_blocks(7 * planes.size());
  ceres::Problem problem;
  ceres::ParameterBlockOrdering* ordering = new ceres::ParameterBlockOrdering;
  for (size_t j = 0; j < planes.size(); ++j) {
    double* pose = &pose_blocks[7 * j];
    const Eigen::Quaterniond& r = (*poses)[j].rotation;
    pose[0] = r.x(), pose[1] = r.y(), pose[2] = r.z(), pose[3] = r.w();
    for (int k = 0; k < 3; ++k) pose[4 + k] = (*poses)[j].translation[k];
    for (size_t i = 0; i < planes[j].points.size(); ++i) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<PlaneCorner, 2, CameraIntrinsics::kNumParams, 7>(
              new PlaneCorner{{planes[j].pixels[i], planes[j].points[i]}}),
          nullptr, intrinsics, pose);
    }
    problem.SetManifold(
        pose,
        new ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>(
            ceres::EigenQuaternionManifold(), ceres::EuclideanManifold<3>()));
    ordering->AddElementToGroup(pose, 0);
  }
  problem.SetManifold(intrinsics,
                      new ceres::SubsetManifold(CameraIntrinsics::kNumParams, {8}));  // k3 held
  ordering->AddElementToGroup(intrinsics, 1);

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.linear_solver_ordering.reset(ordering);
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-12;
  options.parameter_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable())
    return FailedPrecondition("intrinsics from views: the refinement over " +
                              std::to_string(planes.size()) + " planes failed (" + summary.message +
                              ")");
  for (size_t j = 0; j < planes.size(); ++j) {
    const double* q = &pose_blocks[7 * j];
    (*poses)[j] =
        Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(q[4], q[5], q[6]));
  }
  size_t corners = 0;
  for (const Plane& plane : planes) corners += plane.points.size();
  return std::sqrt(2 * summary.final_cost /
                   static_cast<double>(corners));  // Ceres' cost is half the sum
}

}  // namespace

CameraIntrinsics IntrinsicsFromOpenCv(const cv::Mat& camera_matrix, const cv::Mat& distortion,
                                      int width_px, int height_px) {
  const auto d = [&](int i) {
    return i < static_cast<int>(distortion.total()) ? distortion.at<double>(i) : 0.0;
  };
  const double params[CameraIntrinsics::kNumParams] = {camera_matrix.at<double>(0, 0),
                                                       camera_matrix.at<double>(1, 1),
                                                       camera_matrix.at<double>(0, 2),
                                                       camera_matrix.at<double>(1, 2),
                                                       d(0),
                                                       d(1),
                                                       d(2),
                                                       d(3),
                                                       d(4)};
  return CameraIntrinsics::FromParams(params, width_px, height_px);
}

Result<IntrinsicsFromViews> SolveIntrinsicsFromViews(
    const std::vector<const ViewObservations*>& views, const CalibBox& box, int width_px,
    int height_px, int min_planes) {
  if (width_px <= 0 || height_px <= 0)
    return InvalidArgument("intrinsics from views: image size " + std::to_string(width_px) + " x " +
                           std::to_string(height_px) + " is not positive");
  std::vector<Plane> planes;
  for (const ViewObservations* view : views) AddFacePlanes(*view, box, &planes);
  if (static_cast<int>(planes.size()) < min_planes) {
    return FailedPrecondition(
        "intrinsics from views: " + std::to_string(planes.size()) +
        " box face(s) seen with 2 or more tags, " + std::to_string(min_planes) +
        " needed; give nominal intrinsics in the rig config (calibration.cameras) or a "
        "prior from calibrate-intrinsics");
  }
  std::vector<Eigen::Matrix3d> homographies;
  for (const Plane& plane : planes) homographies.push_back(PlaneHomography(plane));
  const Eigen::Vector2d centre(0.5 * (width_px - 1), 0.5 * (height_px - 1));
  double fx = 0, fy = 0;
  if (!FocalLengths(homographies, centre, &fx, &fy)) {
    return FailedPrecondition(
        "intrinsics from views: the " + std::to_string(planes.size()) +
        " box faces seen do not determine the focal length (seen nearly head-on?); give "
        "nominal intrinsics in the rig config (calibration.cameras) or a prior from "
        "calibrate-intrinsics");
  }
  Eigen::Matrix3d camera_matrix;
  camera_matrix << fx, 0, centre.x(), 0, fy, centre.y(), 0, 0, 1;
  std::vector<Rigid3d> poses;
  for (const Eigen::Matrix3d& h : homographies)
    poses.push_back(PoseFromHomography(h, camera_matrix));
  double params[CameraIntrinsics::kNumParams] = {fx, fy, centre.x(), centre.y(), 0, 0, 0, 0, 0};
  IntrinsicsFromViews out;
  HR_ASSIGN_OR_RETURN(out.rms_px, RefineOverPlanes(planes, params, &poses));
  out.intrinsics = CameraIntrinsics::FromParams(params, width_px, height_px);
  out.planes = static_cast<int>(planes.size());
  const Status valid = out.intrinsics.Check();
  if (!valid.ok())
    return FailedPrecondition("intrinsics from views: the solution is not usable: " +
                              valid.message());
  return out;
}

}  // namespace hairrig
