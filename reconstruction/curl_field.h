// Where the hair curls and how: a curl (helix radius, pitch, handedness)
// estimated from the seen strands, and the region in which strand growth
// winds on that helix (the whole hair, or near the seen arcs; CurlRegion;
// helix_guide.h, strand_growth.h).
//
// Inside ringlets no view sees the strands, and Bao & Qi's Laplace field
// (Sec. IV-A, Eq. 1) there runs along the curls' axis: a strand grown along
// it is straight, every true tangent its helix angle off. The seen strands
// show the curl only in part (the views see the front arcs of each ringlet;
// most seen stretches follow the ringlets' outline, along the axis), so the
// estimate takes the arcs that clearly wind:
//   - the axis at a point is the mean direction of the directed seen strands
//     within a box about 3 axis_cell_mm wide (the sum over the 27 cells
//     around the point's cell): over several ringlets it averages their turns
//     away and leaves their common axis;
//   - along a segment, each step's tangent t has the helix angle
//     acos(t . a) to the axis a, and its part square to the axis turns about
//     a at the rate sin(alpha) / r per mm, signed by the handedness (a
//     helix of radius r, helix_guide.h);
//   - an arc is a segment of at least min_arc_length_mm whose helix angle
//     (acos of the mean |t . a|) is at least min_arc_angle_deg and whose turns go mostly one way
//     (the sum of the signed turns at least min_turn_consistency of the sum
//     of their sizes);
//   - the curl's shape from each arc's own helix fitted to its points, less
//     the fit's bias on that arc's noise (helix_fit.h, FitHelixLessItsBias;
//     arcs it refuses are left out; kHelixFit keeps the plain fit, about a
//     tenth wider on a capture's arcs): the radius and the pitch each their
//     own median over the fitted arcs, weighted by length; the
//     radius raised to min_radius_mm if less, the pitch scaled with it. With
//     fewer than min_arcs arcs fitted (a loose curl's arcs turn under a
//     quarter turn) the shape comes from the arcs' curvature kappa and
//     torsion tau instead (each arc's median over its steps; a helix's are
//     kappa = r / (r^2 + c^2), tau = c / (r^2 + c^2), c = P / (2 pi)), whose
//     torsion grows with the points' noise. The handedness is the
//     length-weighted majority's of the turns. About the axis estimated from
//     its neighbours a seen arc turns at about half the rate its curvature
//     implies (on curly_blond, with the true strands' axis as well); the
//     fit finds each arc's own axis. CurlRadiusFrom keeps curvature and
//     torsion, sin^2(alpha) / kappa and the turn rate measurable beside the
//     fit (docs/accuracy.md, "The curl's shape from the arcs' own helices");
//   - a head's ringlets need not all wind one way: a strand that starts
//     winding at a point winds the way the arcs in the 27 axis cells around
//     it turn (the majority by length, each arc counted in every cell it
//     touches), the whole head's majority's way where no arc is near; it
//     keeps that way while it winds on.
// The hair counts as curly when at least min_arcs arcs hold at least
// min_arc_share of the seen length, at least min_handedness_agreement of
// their length turns the way of the other arcs in their axis cells (by
// length, each counted in every cell it touches; a
// ringlet winds one way along its length; the arcs of waves and of stray
// bends turn either way about as often, even side by side), the radius is
// at most max_radius_mm (wider is a wave, not a curl) and alpha at most
// max_helix_angle_deg (a flatter coil has next to no pitch). Not in Bao & Qi,
// whose growth follows the field alone.
//
// Units: mm and radians unless a name says deg; the segments' frame.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/status.h"
#include "reconstruction/helix_fit.h"
#include "reconstruction/helix_guide.h"
#include "reconstruction/strand_segments.h"

namespace hairrig {

// What the curl's radius and pitch are taken from (see the file's comment;
// alpha is the arcs' helix angle to the estimated axis).
enum class CurlRadiusFrom {
  kCurvatureAndTorsion,  // r = kappa / (kappa^2 + tau^2), P = 2 pi tau / (kappa^2 + tau^2)
  kCurvature,            // r = sin^2(alpha) / kappa, P = 2 pi r / tan(alpha)
  kTurnRate,             // r = sin(alpha) / rate, P = 2 pi r / tan(alpha)
  kHelixFit,             // each arc's own helix fitted to its points (FitHelix)
  kHelixFitLessBias,     // the same less each fit's bias on its arc (FitHelixLessItsBias)
};
inline constexpr CurlRadiusFrom kCurlRadiusFroms[] = {
    CurlRadiusFrom::kHelixFit, CurlRadiusFrom::kHelixFitLessBias,
    CurlRadiusFrom::kCurvatureAndTorsion, CurlRadiusFrom::kCurvature, CurlRadiusFrom::kTurnRate};
// True for the shapes from each arc's fitted helix (kHelixFit, kHelixFitLessBias).
bool FromFittedHelices(CurlRadiusFrom from);
const char* CurlRadiusFromName(CurlRadiusFrom from);  // "helix-fit", "curvature-and-torsion", ...
// False for an unknown name.
bool ParseCurlRadiusFrom(const std::string& name, CurlRadiusFrom* from);

// Where strands wind once the hair is found to curl.
enum class CurlRegion {
  // Near the seen arcs: in the cells of CurlFieldOptions::region_mm next to
  // (or holding) a cell with a seen arc.
  kNearArcs,
  // Wherever a strand grows. The views see most ringlets along their outline
  // and few of their arcs (a few per cent of the seen strands' length on a
  // capture's points, under a third on the true visible surface), so a
  // ringlet no arc lies on is as likely as one that shows its curl. On a
  // head whose hair curls in part, the straight part winds too.
  kWholeHair,
};
const char* CurlRegionName(CurlRegion region);  // "near-arcs", "whole-hair"
// False for an unknown name.
bool ParseCurlRegion(const std::string& name, CurlRegion* region);

struct CurlFieldOptions {
  bool enabled = true;  // false: no curl (growth as without it)
  CurlRadiusFrom radius_from = CurlRadiusFrom::kHelixFitLessBias;
  double axis_cell_mm = 10;
  double min_arc_angle_deg = 35;
  double min_arc_length_mm = 15;
  double min_turn_consistency = 0.5;
  int min_arcs = 30;
  double min_arc_share = 0.01;
  // Of the arcs' length, the share that must turn the way of the other arcs
  // in its axis cells (CurlEstimate::local_handedness_agreement).
  double min_handedness_agreement = 0.75;
  // Where strands wind once the hair is found to curl. kWholeHair falls
  // back to kNearArcs when the arcs hold less than whole_hair_min_arc_share
  // (CurlEstimate::region says which was used).
  CurlRegion region = CurlRegion::kWholeHair;
  // The share of the seen length (a fraction in [0, 1]; Check() refuses
  // others) the arcs must hold for kWholeHair to wind the whole hair. Hair
  // the curly test passes by a small margin (the bends of waves or stray
  // strands) then winds near its arcs only, not throughout. A value at or
  // under min_arc_share has no effect. The curls' arcs hold 1.8-4 % under
  // the variations of docs/accuracy.md, bangs_real's 0.9 % (not curly): the
  // `curl.arc_share` of each robustness run's strands/summary.json.
  double whole_hair_min_arc_share = 0.015;
  // Where strands wind near the arcs, they wind in the cells of this size
  // next to (or holding) a cell with a seen arc: from region_mm to about
  // 3.5 region_mm from it.
  double region_mm = 20;
  // Strands wind only this far or further from the seen strands' ribbons
  // (the hybrid field's d_s): nearer, they follow the seen surface's field.
  double min_depth_mm = 0;
  // A strand that leaves a seen strand it followed for more than
  // bend_span_mm, which turned by min_bend_deg or more over that stretch,
  // starts its helix on that bend (HelixGuide::StartOnBend): the seen arc's
  // own ringlet, on the side it bends to. Else, and with start_on_bend
  // false, the helix's axis is the field's direction (HelixGuide::Start).
  bool start_on_bend = true;
  double bend_span_mm = 4;
  double min_bend_deg = 8;
  // A helix started on a bend keeps its axis and turns it towards the
  // field's direction over about this length (mm): at the seen surface the
  // field runs along the seen strand, not along its ringlet's axis.
  double bend_axis_relax_mm = 10;
  double max_helix_angle_deg = 80;
  // A smaller estimated radius is raised to min_radius_mm; a larger one than
  // max_radius_mm is no curl.
  double min_radius_mm = 2, max_radius_mm = 20;
  // InvalidArgument naming the field for a value out of range.
  Status Check() const;
};

struct CurlEstimate {
  Curl curl;  // not curly(): the hair does not curl (or too few arcs say so)
  int64_t arcs = 0;
  double arc_share = 0;  // of the directed segments' length
  double helix_angle_deg = 0, rate_per_mm = 0;
  double curvature_per_mm = 0, torsion_per_mm = 0;  // the arcs' medians, 1/mm (|torsion|)
  // The medians of the arcs' own fitted helices (mm; weighted by length, the
  // radius and the pitch each its own median), whatever radius_from is; 0
  // where no arc could be fitted. By FitHelixLessItsBias when radius_from is
  // kHelixFitLessBias, else by FitHelix. The arcs the fit refuses (under a
  // quarter turn, or no cone to their chords) are left out.
  HelixShape fitted;
  int64_t fitted_arcs = 0;
  CurlRadiusFrom radius_from = CurlRadiusFrom::kHelixFitLessBias;
  // Where strands wind, as decided from the arcs (not as asked); meaningful
  // only when curl.curly().
  CurlRegion region = CurlRegion::kWholeHair;
  // The helix the arcs give by radius_from, before min_radius_mm and the
  // curly test; infinite when they do not bend (or, from fitted helices, no
  // arc was fitted).
  HelixShape RawShape() const;
  double right_handed_share = 0;  // of the arcs' length
  // The share of the arcs' length that turns the way the other arcs in its
  // axis cells turn (the curly test); 0 without two arcs in one cell.
  double local_handedness_agreement = 0;
  // The majority's share of the arcs' length, in [0.5, 1]; 0 without arcs.
  double HandednessAgreement() const {
    return arcs > 0 ? std::max(right_handed_share, 1 - right_handed_share) : 0;
  }
  nlohmann::json ToJson() const;
};

class CurlField {
 public:
  // From the directed segments (root to tip, strand_direction.h).
  static CurlField Estimate(const std::vector<StrandSegment>& segments,
                            const CurlFieldOptions& options);
  // CurlField() has no curl anywhere.
  // One curl everywhere (a curl known beforehand, or the truth's in a bench).
  static CurlField Everywhere(const Curl& curl);

  const CurlEstimate& estimate() const { return estimate_; }
  // The curl strands at p wind on: the way the seen arcs in the axis cells
  // about p turn, the estimate's (the arcs' majority) where none is near;
  // nullptr where the hair is not seen to curl or p lies outside the region.
  const Curl* At(const Eigen::Vector3f& p) const;

 private:
  struct Region;
  CurlEstimate estimate_;
  std::shared_ptr<const Region> region_;  // null: everywhere (when curly)
};

}  // namespace hairrig
