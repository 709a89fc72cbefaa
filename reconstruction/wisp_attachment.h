// Wisps attached to the head (Luo et al. 2013 Sec. 7.1, 7.2): interior
// strands from roots on the scalp regularised by the interior field (Eq. 13),
// exterior wisps extended down to the scalp by them, and interior wisps grown
// from them. The steps of BuildWisps (wisps.h) that need the head; their
// rules are written there. Units mm, the points' frame.
#pragma once

#include <Eigen/Core>
#include <random>
#include <vector>

#include "core/head_model.h"
#include "reconstruction/interior_field.h"
#include "reconstruction/scalp_guide.h"
#include "reconstruction/wisps.h"

namespace hairrig {

class WispAttacher {
 public:
  // All must outlive the attacher. `bounding_diagonal_mm` is B of Eq. 13.
  WispAttacher(const HeadModel& head, const ScalpGuide& guide, const InteriorField& field,
               const WispOptions& options, double bounding_diagonal_mm);

  // Sec. 7.1's interior strand from the root to q (first vertex r, last q):
  // the root and the two vertices after it along d_g and q are kept; the
  // others lie head_clearance_mm or more outside the head. `continuation`
  // (optional: the wisp's vertex after q) takes part in the smoothing as a
  // kept vertex, so that the strand runs into the wisp without a kink. Just
  // {r, q} when q is within three steps of r.
  std::vector<Eigen::Vector3f> InteriorStrand(const ScalpRoot& root, const Eigen::Vector3f& q,
                                              const Eigen::Vector3f* continuation = nullptr) const;

  // Sec. 7.1: the interior strand to the centre's R_0 prepended to every
  // isocurve (offset); sets `attached` and `interior_vertices`. False (the
  // wisp unchanged) for an empty wisp or a non-finite R_0.
  bool Attach(Wisp* wisp, std::mt19937_64& rng) const;

  // Sec. 7.2: an interior wisp towards the point `target` (full ranges).
  // False when the truncated interior strand keeps fewer than 4 vertices.
  bool MakeInteriorWisp(const Eigen::Vector3f& target, std::mt19937_64& rng, Wisp* wisp) const;

 private:
  // Vertex k of an isocurve offset from an interior strand: the root onto
  // the head's surface, the two next out of the head, the rest clear of it.
  Eigen::Vector3f PlaceOffsetVertex(int k, const Eigen::Vector3f& v) const;
  Eigen::Vector3f KeepOutside(const Eigen::Vector3f& v, double margin_mm) const;

  const HeadModel& head_;
  const ScalpGuide& guide_;
  const InteriorField& field_;
  const WispOptions& options_;
  double field_weight_;  // alpha_int B
};

// Wisp::normals for each wisp: across x along at the centre isocurve, signed
// away from the head (the head's outward direction at the vertex); where the
// wisp has one isocurve or the cross product vanishes, the outward direction
// made perpendicular to the isocurve.
void SetWispNormals(const HeadModel& head, std::vector<Wisp>* wisps);

}  // namespace hairrig
