// Where hair grows from on the scalp and which way (Luo et al. 2013 Sec. 7.1),
// on the head model (core/head_model.h) instead of the paper's painted mesh.
// Units mm, the head's frame (the points' frame).
//
// The parting line is the head spec's (core/head_spec.h): the arc of the
// plane through the scalp centre that holds face_dir, tilted by
// parting_offset_deg, from the front hairline (hairline_front_deg) over the
// crown to parting_back_deg past the vertical. On a roughly spherical scalp
// the shortest path from the parting to a scalp point p runs along the great
// circle (about the scalp centre) from the nearest parting point to p, so:
//   Gamma(p)  that great circle's arc, from the parting to p, each sample the
//             head's surface point seen from the scalp centre;
//   d_s(p)    the reference growing direction: the arc's tangent at p
//             (pointing away from the parting), in the head's tangent plane.
// Without a parting (ScalpSpec::parting false, or no scalp spec) the crown,
// the point straight above the scalp centre (against `down`), takes the
// parting's place: d_s points down the head away from the crown.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <random>
#include <vector>

#include "core/head_model.h"
#include "reconstruction/point_grid.h"

namespace hairrig {

struct ScalpRoot {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();           // r, on the head's surface
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();             // n(r), unit, out of the head
  Eigen::Vector3f growing_direction = Eigen::Vector3f::Zero();  // d_g (Eq. 12), unit
};

class ScalpGuide {
 public:
  // The scalp's samples are the head mesh's vertices on the scalp (for an
  // ellipsoid, its tessellation's, about 3 mm apart). `head` must outlive
  // the guide; `down` is unit.
  ScalpGuide(const HeadModel& head, const Eigen::Vector3f& down);
  ScalpGuide(const ScalpGuide&) = delete;
  ScalpGuide& operator=(const ScalpGuide&) = delete;

  // No scalp sample: nothing can be attached.
  bool empty() const { return samples_.empty(); }
  const std::vector<Eigen::Vector3f>& samples() const { return samples_; }

  // The scalp sample nearest q, and whether one lies within `distance_mm` of q.
  Eigen::Vector3f NearestSample(const Eigen::Vector3f& q) const;
  bool AnySampleWithin(const Eigen::Vector3f& q, double distance_mm) const;

  // The head's surface seen from the scalp centre along `direction` (falls
  // back to the centre plus `direction` times `fallback_radius_mm` when the
  // ray misses).
  Eigen::Vector3f SurfaceAlong(const Eigen::Vector3f& direction, double fallback_radius_mm) const;
  // p moved onto the head's surface along its outward direction.
  Eigen::Vector3f OntoSurface(const Eigen::Vector3f& p) const;

  // d_s(p) for p on (or near) the scalp: unit, tangent to the head.
  Eigen::Vector3f ReferenceDirection(const Eigen::Vector3f& p) const;
  // Gamma(p): from the parting (first) to p (last), samples about step_mm
  // apart on the head's surface.
  std::vector<Eigen::Vector3f> PathFromParting(const Eigen::Vector3f& p, double step_mm) const;
  // Eq. 12: d_s(r), or <q - r> where q lies higher above r's tangent plane
  // than d_s leads.
  Eigen::Vector3f GrowingDirection(const Eigen::Vector3f& r, const Eigen::Vector3f& q) const;

  // Root point assignment for the attaching point q: p the scalp sample
  // nearest q, p_M on Gamma(p) by Eq. 11, p_k drawn uniformly from
  // Gamma(p)'s p_1..p_M, r drawn on the scalp within `jitter_mm` of p_k
  // (falling back to the next path points on the scalp, then to p), d_g by
  // Eq. 12. Requires !empty().
  ScalpRoot AssignRoot(const Eigen::Vector3f& q, double step_mm, double jitter_mm,
                       std::mt19937_64& rng) const;

 private:
  // The nearest point of the parting (or the crown) seen from the centre, unit.
  Eigen::Vector3f PartingDirection(const Eigen::Vector3f& from_centre) const;
  Eigen::Vector3f Outward(const Eigen::Vector3f& p) const;

  const HeadModel& head_;
  Eigen::Vector3f centre_, up_, face_, parting_normal_, parting_up_;
  bool has_parting_ = false;
  double parting_begin_rad_ = 0, parting_end_rad_ = 0;  // the arc, from face_ towards parting_up_
  std::vector<Eigen::Vector3f> samples_;
  std::unique_ptr<PointGrid> grid_;
};

}  // namespace hairrig
