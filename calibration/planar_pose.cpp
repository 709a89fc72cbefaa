#include "calibration/planar_pose.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace hairrig {

namespace {

using Matrix26d = Eigen::Matrix<double, 2, 6>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// An orthonormal frame on the quadrilateral's plane: origin at the corners'
// centroid, x along the first edge, z the normal.
struct PlaneFrame {
  Eigen::Vector3d origin;
  Eigen::Matrix3d axes;  // columns: x, y, normal (model frame)
  double scale = 0;      // the largest corner distance from the origin
};

bool MakePlaneFrame(const std::array<Eigen::Vector3d, 4>& corners, PlaneFrame* frame) {
  frame->origin = (corners[0] + corners[1] + corners[2] + corners[3]) / 4;
  frame->scale = 0;
  for (const Eigen::Vector3d& c : corners)
    frame->scale = std::max(frame->scale, (c - frame->origin).norm());
  if (!(frame->scale > 0)) return false;
  const Eigen::Vector3d normal = (corners[2] - corners[0]).cross(corners[3] - corners[1]);
  if (!(normal.norm() > 1e-9 * frame->scale * frame->scale)) return false;
  for (size_t skip = 0; skip < 4; ++skip) {  // no three corners on one line
    const Eigen::Vector3d& a = corners[(skip + 1) % 4];
    const Eigen::Vector3d& b = corners[(skip + 2) % 4];
    const Eigen::Vector3d& c = corners[(skip + 3) % 4];
    if (!((b - a).cross(c - a).norm() > 1e-6 * frame->scale * frame->scale)) return false;
  }
  const Eigen::Vector3d z = normal.normalized();
  for (const Eigen::Vector3d& c : corners) {
    if (std::abs(z.dot(c - frame->origin)) > 1e-6 * frame->scale) return false;
  }
  const Eigen::Vector3d edge = corners[1] - corners[0];
  const Eigen::Vector3d x = (edge - edge.dot(z) * z).normalized();
  frame->axes.col(0) = x;
  frame->axes.col(1) = z.cross(x);
  frame->axes.col(2) = z;
  return true;
}

// The homography (h33 = 1) taking plane points to normalised image points;
// false when the 4 correspondences are degenerate.
bool SolveHomography(const std::array<Eigen::Vector2d, 4>& plane,
                     const std::array<Eigen::Vector2d, 4>& image, Eigen::Matrix3d* h) {
  Eigen::Matrix<double, 8, 8> a;
  Eigen::Matrix<double, 8, 1> b;
  for (int i = 0; i < 4; ++i) {
    const double x = plane[static_cast<size_t>(i)].x(), y = plane[static_cast<size_t>(i)].y();
    const double u = image[static_cast<size_t>(i)].x(), v = image[static_cast<size_t>(i)].y();
    a.row(2 * i) << x, y, 1, 0, 0, 0, -u * x, -u * y;
    a.row(2 * i + 1) << 0, 0, 0, x, y, 1, -v * x, -v * y;
    b(2 * i) = u;
    b(2 * i + 1) = v;
  }
  const Eigen::FullPivLU<Eigen::Matrix<double, 8, 8>> lu(a);
  if (lu.rank() < 8) return false;
  const Eigen::Matrix<double, 8, 1> p = lu.solve(b);
  *h << p(0), p(1), p(2), p(3), p(4), p(5), p(6), p(7), 1;
  // A singular homography: three image corners on one line (seen edge-on).
  return h->allFinite() && std::abs(h->determinant()) > 1e-12 * std::pow(h->norm(), 3);
}

// Collins & Bartoli 2014, Sec. 4: with v the image of the plane's origin and
// J the perspective map's Jacobian there, J = s B Q[0:2, 0:2] for the
// rotation Q = Rv R (Rv takes the viewing direction of v onto the optical
// axis, B the 2x2 part of [I | -v] Rv^T, s the inverse depth). A = B^-1 J
// fixes Q's upper-left block up to s = its largest singular value; the
// block's two completions to a rotation, which differ in the sign of the
// third row, are the two poses. Returns 0 or 2 rotations (plane to camera).
std::vector<Eigen::Matrix3d> RotationsFromJacobian(const Eigen::Vector2d& v,
                                                   const Eigen::Matrix2d& jacobian) {
  const Eigen::Matrix3d rv =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(v.x(), v.y(), 1), Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  Eigen::Matrix<double, 2, 3> project;
  project << 1, 0, -v.x(), 0, 1, -v.y();
  const Eigen::Matrix2d b = (project * rv.transpose()).leftCols<2>();
  if (!(std::abs(b.determinant()) > 1e-12)) return {};
  const Eigen::Matrix2d a = b.inverse() * jacobian;
  const Eigen::Matrix2d ata =
      a.transpose() * a;  // largest eigenvalue without cancellation near equal ones
  const double half_gap = 0.5 * (ata(0, 0) - ata(1, 1));
  const double largest = std::sqrt(0.5 * (ata(0, 0) + ata(1, 1)) +
                                   std::sqrt(half_gap * half_gap + ata(0, 1) * ata(0, 1)));
  if (!(largest > 0)) return {};
  const Eigen::Matrix2d block = a / largest;
  const Eigen::Vector2d b1 = block.col(0), b2 = block.col(1);
  const double c1 = std::sqrt(std::max(0.0, 1 - b1.squaredNorm()));
  const double c2_size = std::sqrt(std::max(0.0, 1 - b2.squaredNorm()));
  const double c2 = b1.dot(b2) > 0 ? -c2_size : c2_size;  // columns orthogonal: b1.b2 + c1 c2 = 0
  std::vector<Eigen::Matrix3d> rotations;
  for (double sign : {1.0, -1.0}) {
    Eigen::Matrix3d q;
    q.col(0) << b1, sign * c1;
    q.col(1) << b2, sign * c2;
    q.col(2) = q.col(0).cross(q.col(1));
    rotations.push_back(rv.transpose() * q);
  }
  return rotations;
}

// The translation minimising the algebraic reprojection error of `plane`
// points (plane frame, z = 0) under `rotation`: [I | -u] (R p + T) = 0.
Eigen::Vector3d TranslationFor(const Eigen::Matrix3d& rotation,
                               const std::array<Eigen::Vector3d, 4>& plane,
                               const std::array<Eigen::Vector2d, 4>& image) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < 4; ++i) {
    Eigen::Matrix<double, 2, 3> n;
    n << 1, 0, -image[i].x(), 0, 1, -image[i].y();
    const Eigen::Matrix3d ntn = n.transpose() * n;
    normal += ntn;
    rhs -= ntn * (rotation * plane[i]);
  }
  return normal.ldlt().solve(rhs);
}

double SquaredReprojectionError(const Rigid3d& pose, const Eigen::Vector3d* points,
                                const Eigen::Vector2d* image, size_t count) {
  double sum = 0;
  for (size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d y = pose * points[i];
    if (!(y.z() > 0)) return INFINITY;
    sum += (y.head<2>() / y.z() - image[i]).squaredNorm();
  }
  return sum;
}

}  // namespace

std::vector<Rigid3d> PlanarSquarePoses(const std::array<Eigen::Vector3d, 4>& corners_model,
                                       const std::array<Eigen::Vector2d, 4>& normalised) {
  PlaneFrame frame;
  if (!MakePlaneFrame(corners_model, &frame)) return {};
  std::array<Eigen::Vector3d, 4> plane;
  std::array<Eigen::Vector2d, 4>
      scaled;  // plane coordinates / scale, for the homography's conditioning
  for (size_t i = 0; i < 4; ++i) {
    plane[i] = frame.axes.transpose() * (corners_model[i] - frame.origin);
    plane[i].z() = 0;
    scaled[i] = plane[i].head<2>() / frame.scale;
    if (!normalised[i].allFinite()) return {};
  }
  Eigen::Matrix3d h;
  if (!SolveHomography(scaled, normalised, &h)) return {};
  const Eigen::Vector2d v(h(0, 2), h(1, 2));  // the image of the plane's origin
  Eigen::Matrix2d jacobian;                   // d(image) / d(plane) at the origin, per mm
  jacobian << h(0, 0) - h(2, 0) * h(0, 2), h(0, 1) - h(2, 1) * h(0, 2), h(1, 0) - h(2, 0) * h(1, 2),
      h(1, 1) - h(2, 1) * h(1, 2);
  jacobian /= frame.scale;

  const Rigid3d plane_from_model(Eigen::Matrix3d(frame.axes.transpose()),
                                 -(frame.axes.transpose() * frame.origin));
  std::vector<std::pair<double, Rigid3d>> scored;
  for (const Eigen::Matrix3d& rotation : RotationsFromJacobian(v, jacobian)) {
    const Eigen::Vector3d translation = TranslationFor(rotation, plane, normalised);
    if (!(translation.z() > 0) || !translation.allFinite()) continue;
    const Rigid3d cam_from_model = Rigid3d(rotation, translation) * plane_from_model;
    scored.emplace_back(
        SquaredReprojectionError(cam_from_model, corners_model.data(), normalised.data(), 4),
        cam_from_model);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Rigid3d> poses;
  for (const auto& [error, pose] : scored) poses.push_back(pose);
  return poses;
}

PoseRefinement RefinePose(const std::vector<Eigen::Vector3d>& points_model,
                          const std::vector<Eigen::Vector2d>& normalised, const Rigid3d& start) {
  const size_t count = std::min(points_model.size(), normalised.size());
  PoseRefinement out{start, 0, 0};
  double cost = SquaredReprojectionError(start, points_model.data(), normalised.data(), count);
  double damping = 1e-6;
  bool converged = false;
  for (int iteration = 0; iteration < 100 && !converged && std::isfinite(cost) && cost > 0;
       ++iteration) {
    out.iterations = iteration + 1;
    Matrix6d normal = Matrix6d::Zero();
    Vector6d gradient = Vector6d::Zero();
    const Eigen::Matrix3d rotation = out.cam_from_model.RotationMatrix();
    for (size_t i = 0; i < count; ++i) {
      const Eigen::Vector3d rotated = rotation * points_model[i];
      const Eigen::Vector3d y = rotated + out.cam_from_model.translation;
      const Eigen::Vector2d projected = y.head<2>() / y.z();
      Eigen::Matrix<double, 2, 3> d_projection;
      d_projection << 1, 0, -projected.x(), 0, 1, -projected.y();
      d_projection /= y.z();
      Matrix26d jacobian;  // left rotation increment w: dY/dw = -[R p]x; dY/dT = I
      Eigen::Matrix3d minus_cross;
      minus_cross << 0, rotated.z(), -rotated.y(), -rotated.z(), 0, rotated.x(), rotated.y(),
          -rotated.x(), 0;
      jacobian << d_projection * minus_cross, d_projection;
      normal += jacobian.transpose() * jacobian;
      gradient += jacobian.transpose() * (projected - normalised[i]);
    }
    bool accepted = false;
    while (!accepted && damping < 1e12) {
      Matrix6d damped = normal;
      damped.diagonal() += damping * normal.diagonal();
      const Vector6d step = damped.ldlt().solve(-gradient);
      const Eigen::Vector3d w = step.head<3>();
      const double angle = w.norm();
      const Rigid3d turn = Rigid3d::FromAngleAxis(w, Eigen::Vector3d::Zero());
      const Rigid3d candidate(turn.rotation * out.cam_from_model.rotation,
                              out.cam_from_model.translation + step.tail<3>());
      const double candidate_cost =
          SquaredReprojectionError(candidate, points_model.data(), normalised.data(), count);
      if (candidate_cost < cost) {
        accepted = true;
        const double change =
            angle + step.tail<3>().norm() / std::max(1.0, out.cam_from_model.translation.norm());
        out.cam_from_model = candidate;
        cost = candidate_cost;
        damping = std::max(damping / 10, 1e-12);
        converged = change < 1e-14;
      } else {
        damping *= 10;
      }
    }
    if (!accepted) break;
  }
  out.rms = count > 0 ? std::sqrt(cost / static_cast<double>(count)) : 0;
  return out;
}

}  // namespace hairrig
