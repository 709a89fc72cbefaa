// For tests: an analytic subject for the head fit, an ellipsoid head whose
// scalp wears a 12 mm shell of hair, on a neck, seen by sixteen cameras on
// two rings (200 x 260 px), labelled exactly as hair_segmentation.h labels.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/head_model.h"
#include "reconstruction/hair_segmentation.h"
#include "reconstruction/head_fit.h"
#include "tests/support/plane_scene_testing.h"

namespace hairrig::head_scene {

inline constexpr int kWidth = 200, kHeight = 260;
inline constexpr double kHairMm = 12;
inline constexpr double kNeckRadiusMm = 45;

inline HeadSpec TrueHead(const Eigen::Vector3d& face_dir) {
  HeadSpec head;
  head.center_turntable_mm = Eigen::Vector3d(6, -4, 300);
  head.radii_mm = Eigen::Vector3d(76, 94, 106);
  if (std::abs(face_dir.x()) > std::abs(face_dir.y()))
    std::swap(head.radii_mm.x(), head.radii_mm.y());
  ScalpSpec& s = head.scalp;
  s.defined = true;
  s.center_turntable_mm = head.center_turntable_mm;
  s.face_dir = face_dir;
  s.hairline_front_deg = 30;
  s.hairline_temple_deg = 20;
  s.hairline_ear_deg = 5;
  s.hairline_nape_deg = -25;
  s.parting = false;
  return head;
}

// The subject: the head, the hair shell over its scalp and the neck below.
class Subject {
 public:
  explicit Subject(const HeadSpec& head) : head_(HeadModel::Build(head).value()) {
    HeadSpec shell = head;
    shell.radii_mm += Eigen::Vector3d::Constant(kHairMm);
    shell_ = HeadModel::Build(shell).value();
  }

  SegmentLabel Label(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
    const double far = 1e5;
    HeadHit hit;
    const double t_head = head_->Intersect(origin, dir, 0, far, &hit) ? hit.t : far;
    const double t_neck = NeckHit(origin, dir);
    double t = 0;
    // The shell's surface points over the scalp are hair; it is crossed at most twice.
    for (int crossing = 0; crossing < 2 && shell_->Intersect(origin, dir, t, far, &hit);
         ++crossing) {
      t = hit.t + 1e-6;
      if (hit.t > std::min(t_head, t_neck)) break;
      if (OverScalp(origin + hit.t * dir)) return kSegHair;
    }
    return std::min(t_head, t_neck) < far ? kSegHead : kSegBackdrop;
  }

 private:
  bool OverScalp(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d c = head_->head().center_turntable_mm;
    const Eigen::Vector3d r = head_->head().radii_mm;
    const Eigen::Vector3d q = p - c;
    return head_->OnScalp(c + q / q.cwiseQuotient(r).norm());
  }

  // The neck: a vertical cylinder under the head, from 170 to 60 mm below its centre.
  double NeckHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
    const Eigen::Vector3d c = head_->head().center_turntable_mm;
    const Eigen::Vector2d o(origin.x() - c.x(), origin.y() - c.y()), d(dir.x(), dir.y());
    const double a = d.squaredNorm(), b = 2 * o.dot(d),
                 k = o.squaredNorm() - kNeckRadiusMm * kNeckRadiusMm;
    const double disc = b * b - 4 * a * k;
    if (a < 1e-12 || disc < 0) return 1e5;
    const double t = (-b - std::sqrt(disc)) / (2 * a);
    const double z = origin.z() + t * dir.z() - c.z();
    return t > 0 && z > -170 && z < -60 ? t : 1e5;
  }

  std::unique_ptr<HeadModel> head_, shell_;
};

inline HeadFitView View(const Subject& subject, double azimuth_deg, double height_mm) {
  HeadFitView v;
  v.camera = plane_scene::CentredCamera(kWidth, kHeight, 330);
  const double a = DegToRad(azimuth_deg);
  const Eigen::Vector3d target(6, -4, 260);
  const Eigen::Vector3d eye =
      target + Eigen::Vector3d(650 * std::sin(a), -650 * std::cos(a), height_mm);
  v.cam_from_object = LookAt(eye, target);
  v.label = cv::Mat1b(kHeight, kWidth, uint8_t{kSegBackdrop});
  const Rigid3d object_from_cam = v.cam_from_object.Inverse();
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const Eigen::Vector2d n = UndistortPixel(v.camera, Eigen::Vector2d(x, y)).value();
      const Eigen::Vector3d dir =
          (object_from_cam.rotation * Eigen::Vector3d(n.x(), n.y(), 1)).normalized();
      v.label(y, x) = subject.Label(object_from_cam.translation, dir);
    }
  }
  return v;
}

inline std::vector<HeadFitView> Views(const HeadSpec& head) {
  const Subject subject(head);
  std::vector<HeadFitView> views;
  for (int k = 0; k < 16; ++k) views.push_back(View(subject, 22.5 * k, k % 2 == 0 ? 120 : -60));
  return views;
}

}  // namespace hairrig::head_scene
