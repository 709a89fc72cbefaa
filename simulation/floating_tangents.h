// Adaptive floating-tangents fitting (Bao & Qi 2017, Sec. V, Algorithms 1 and
// 2): a strand becomes a G1 piecewise-helical curve, N elements of three
// parameters each (curvature, torsion, length), the input of the super-helix
// dynamics. Millimetres.
//
// Steps: a Bezier spline through the strand (simulation/strand_spline.h); the
// element count N (Sec. V-A, Algorithm 2) or a fixed N (the paper's Table 2
// baseline); N + 1 break points at equal arc length with their tangents; the
// break points relaxed so that each pair is co-helical (Sec. V-B, Eqs. 3-5, a
// linear least-squares solve) while the tangents are kept exactly; one helix
// per pair (Sec. V-C, Eq. 8).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "simulation/helix.h"

namespace hairrig {

class StrandSpline;

struct FloatingTangentsOptions {
  bool adaptive = true;        // Algorithm 2; false: `fixed_elements` for every strand
  int fixed_elements = 15;     // the paper's fixed-N comparison (Table 2)
  int min_elements = 3;        // N_min, Table 3
  int max_elements = 25;       // N_max, Table 3
  double min_length_mm = 50;   // L_min = 5 cm, Table 3
  double max_length_mm = 800;  // L_max = 80 cm, Table 3
  // Ours: the root's own residual is in the least squares, so the fitted strand
  // starts at the scalp. false: Eq. 5 as printed (sum from i = 1).
  bool anchor_root = true;
  // Ours, with anchor_root: an element the strand crosses with little turning
  // whose relaxed pair only a coil could join (no short rotation; typical of
  // nearly straight, slightly S-shaped or noisy stretches) gets one more
  // condition that makes it a planar arc. Faster (no coil search) and free of
  // the noise's tiny coils, but the extra condition moves the break points:
  // off by default (measured side by side in bench/fit_bench.cpp).
  bool planar_arcs = false;
  // Ours: an element over which the strand turns so little that an arc would
  // stray less than this (mm) from its chord is straight; its end tangent
  // becomes its start tangent, and a run of such elements shares one tangent
  // while the run's arc would still stray less than this. Nearly parallel
  // tangents otherwise admit no short rotation once rounding noise (float
  // input, ~1e-5 mm) tilts the chord: only a coil would join them. 0: off.
  double straight_sagitta_mm = 0.001;
  // Ours: N starts at Algorithm 2's or at the strand's total turning / 90 deg
  // if more (Algorithm 2's inner-product test at the spline's own resolution:
  // its 20 samples miss curls shorter than L / 20), and grows (to the N an
  // error law e ~ N^-k predicts, by at least a quarter, up to N_max) while
  // the mean fit error exceeds this (mm); if it stops at N_max with a
  // relaxation that moves a break point by more than a quarter element (a
  // resonance of elements of about half a curl), one element fewer when that
  // relaxes less. 0: Algorithm 2 alone, as in the paper.
  double target_mean_error_mm = 0.05;
  // The fit error is measured against the helical curve as a polyline whose
  // chords stray from the curve by at most this (mm): each element gets
  // length * sqrt(curvature / (8 sagitta)) chords, at least 2.
  double error_sagitta_mm = 0.005;

  // InvalidArgument naming the field for a value out of range or not finite.
  Status Check() const;
};

struct PiecewiseHelix {
  std::vector<HelixElement> elements;
  double length_mm() const;
  // Points every `step_mm` along the curve (both ends included).
  std::vector<Eigen::Vector3d> Sample(double step_mm) const;
};

struct StrandFitSummary {
  int elements = 0;
  double strand_length_mm = 0;
  double mean_error_mm = 0;  // input points to the helical curve
  double max_error_mm = 0;
  double max_g1_defect_deg = 0;  // angle between tangents at joints
  double max_cohelical_residual =
      0;  // |<p*_{i+1} - p*_i, t_{i+1} - t_i>| / |p*_{i+1} - p*_i|, Eq. 4
  // The largest move of a break point by the relaxation (Sec. V-B), in
  // elements (1 = one element's length).
  double max_relaxation_elements = 0;
};

// Algorithm 2 (with L_min / L_max of Sec. V-A), clamped to [N_min, N_max].
int AdaptiveElementCount(const StrandSpline& spline, const FloatingTangentsOptions& options);

// Fits one strand. InvalidArgument for bad options, fewer than 2 distinct
// points, NaNs; Internal if no helix joins a relaxed pair (named by index).
// The summary's figures are measured only when `summary` is given (the fit
// error, the distance from every point to the helical curve, is the costliest
// step); without it, the fit error only where the element count's growth
// needs it.
Result<PiecewiseHelix> FitFloatingTangents(const std::vector<Eigen::Vector3d>& points_mm,
                                           const FloatingTangentsOptions& options,
                                           StrandFitSummary* summary = nullptr);

// Distances from each point to the polyline through `curve`: mean and max.
void DistanceToCurve(const std::vector<Eigen::Vector3d>& points,
                     const std::vector<Eigen::Vector3d>& curve, double* mean_mm, double* max_mm);

}  // namespace hairrig
