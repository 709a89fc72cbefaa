#include "reconstruction/curl_field.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <unordered_map>
#include <unordered_set>

#include "core/statistics.h"

namespace hairrig {

namespace {

// A cell's coordinates, each biased to [0, kSpan), packed into one key.
constexpr int64_t kBias = 1 << 20, kSpan = 1 << 21;

// A cell of a sparse grid of `cell_mm` cubes, as one key.
int64_t CellKey(const Eigen::Vector3i& c) {
  return ((c.x() + kBias) * kSpan + (c.y() + kBias)) * kSpan + (c.z() + kBias);
}

// A cell's coordinates from its key.
Eigen::Vector3i Unkey(int64_t key) {
  const int z = static_cast<int>(key % kSpan - kBias);
  key /= kSpan;
  const int y = static_cast<int>(key % kSpan - kBias);
  return {static_cast<int>(key / kSpan - kBias), y, z};
}

Eigen::Vector3i CellOf(const Eigen::Vector3f& p, double cell_mm) {
  return (p.cast<double>() / cell_mm).array().floor().cast<int>();
}

template <typename Visit>
void ForNeighbourCells(const Eigen::Vector3i& c, Visit visit) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) visit(CellKey(c + Eigen::Vector3i(dx, dy, dz)));
}

// The seen strands' axis: the sum of their directed tangents over the 27
// cells around a point's cell.
class AxisGrid {
 public:
  AxisGrid(const std::vector<StrandSegment>& segments, double cell_mm) : cell_mm_(cell_mm) {
    std::unordered_map<int64_t, Eigen::Vector3f> sums;
    for (const StrandSegment& s : segments)
      for (size_t k = 0; k + 1 < s.points_mm.size(); ++k)
        sums.try_emplace(CellKey(CellOf(s.points_mm[k], cell_mm)), Eigen::Vector3f::Zero())
            .first->second += s.points_mm[k + 1] - s.points_mm[k];
    for (const auto& cell : sums) {
      const int64_t key = cell.first;
      Eigen::Vector3f total = Eigen::Vector3f::Zero();
      const Eigen::Vector3i c = Unkey(key);
      ForNeighbourCells(c, [&](int64_t k) {
        const auto it = sums.find(k);
        if (it != sums.end()) total += it->second;
      });
      if (total.norm() > 1e-6f) axes_[key] = total.normalized();
    }
  }

  // Unit, or zero where the seen strands cancel out or are absent.
  Eigen::Vector3f At(const Eigen::Vector3f& p) const {
    const auto it = axes_.find(CellKey(CellOf(p, cell_mm_)));
    return it != axes_.end() ? it->second : Eigen::Vector3f::Zero();
  }

 private:
  double cell_mm_;
  std::unordered_map<int64_t, Eigen::Vector3f> axes_;
};

// What one segment says of the curl.
struct SegmentTurn {
  double length_mm = 0;
  double helix_angle = 0;  // mean, rad
  double rate = 0;         // signed turn of the tangent's part square to the axis, rad/mm
  double consistency = 0;  // |sum of signed turns| / sum of their sizes
};

// The polyline's curvature and torsion (1/mm), each the median over its
// steps, whatever axis it turns about: the angle between consecutive steps'
// tangents over their mean length, and the signed angle between consecutive
// binormals about the tangent between them over the step's length (positive
// for a right-handed helix). 0 where there are too few steps.
void Bending(const std::vector<Eigen::Vector3f>& p, double* curvature, double* torsion) {
  std::vector<Eigen::Vector3d> tangents;
  std::vector<double> lengths;
  for (size_t k = 0; k + 1 < p.size(); ++k) {
    const Eigen::Vector3d step = (p[k + 1] - p[k]).cast<double>();
    if (step.norm() < 1e-9) continue;
    tangents.push_back(step.normalized());
    lengths.push_back(step.norm());
  }
  std::vector<double> curvatures, torsions;
  Eigen::Vector3d previous_binormal = Eigen::Vector3d::Zero();
  for (size_t k = 0; k + 1 < tangents.size(); ++k) {
    const Eigen::Vector3d& a = tangents[k];
    const Eigen::Vector3d& b = tangents[k + 1];
    const Eigen::Vector3d cross = a.cross(b);
    curvatures.push_back(std::atan2(cross.norm(), a.dot(b)) /
                         (0.5 * (lengths[k] + lengths[k + 1])));
    // Too straight for its plane to say where it bends.
    if (cross.norm() < 1e-3) {
      previous_binormal.setZero();
      continue;
    }
    const Eigen::Vector3d binormal = cross.normalized();
    if (previous_binormal.squaredNorm() > 0)
      torsions.push_back(
          std::atan2(previous_binormal.cross(binormal).dot(a), previous_binormal.dot(binormal)) /
          lengths[k]);
    previous_binormal = binormal;
  }
  *curvature = Median(std::move(curvatures));
  *torsion = Median(std::move(torsions));
}

// sin of the least angle to the axis at which a step's turn is measured.
constexpr double kMinAcross = 0.5;

SegmentTurn TurnAlong(const StrandSegment& segment, const AxisGrid& axes) {
  SegmentTurn out;
  const std::vector<Eigen::Vector3f>& p = segment.points_mm;
  double cos_sum = 0, turn_sum = 0, turn_size = 0, turn_length = 0;
  int steps = 0;
  Eigen::Vector3d previous_across = Eigen::Vector3d::Zero();
  for (size_t k = 0; k + 1 < p.size(); ++k) {
    const Eigen::Vector3d step = (p[k + 1] - p[k]).cast<double>();
    const double length = step.norm();
    const Eigen::Vector3d a = axes.At(p[k]).cast<double>();
    if (length < 1e-9 || a.squaredNorm() < 0.5) {
      previous_across.setZero();
      continue;
    }
    const Eigen::Vector3d t = step / length;
    out.length_mm += length;
    cos_sum += std::clamp(t.dot(a), -1.0, 1.0);
    ++steps;
    Eigen::Vector3d across = t - t.dot(a) * a;
    // Too close to the axis for its side to say which way it turns: on a
    // ringlet, the stretches the views see along its outline.
    if (across.norm() < kMinAcross) {
      previous_across.setZero();
      continue;
    }
    across.normalize();
    if (previous_across.squaredNorm() > 0) {
      const double turn =
          std::atan2(previous_across.cross(across).dot(a), previous_across.dot(across));
      turn_sum += turn;
      turn_size += std::abs(turn);
      turn_length += length;
    }
    previous_across = across;
  }
  if (steps == 0) return out;
  // A segment that runs against its neighbours' mean direction winds about
  // the same axis the other way along it: the angle is to the axis' line,
  // and the turns, measured about the neighbours' way, change sign (a
  // helix's handedness does not depend on the way it is run along).
  const double sense = cos_sum >= 0 ? 1.0 : -1.0;
  out.helix_angle = std::acos(std::clamp(std::abs(cos_sum) / steps, 0.0, 1.0));
  out.rate = turn_length > 0 ? sense * turn_sum / turn_length : 0;
  out.consistency = turn_size > 0 ? std::abs(turn_sum) / turn_size : 0;
  return out;
}

// The value below which half the weight lies.
double WeightedMedian(std::vector<std::pair<double, double>> value_weight) {
  if (value_weight.empty()) return 0;
  std::sort(value_weight.begin(), value_weight.end());
  double total = 0;
  for (const auto& vw : value_weight) total += vw.second;
  double run = 0;
  for (const auto& [value, weight] : value_weight) {
    run += weight;
    if (run >= total / 2) return value;
  }
  return value_weight.back().first;
}

}  // namespace

const char* CurlRegionName(CurlRegion region) {
  return region == CurlRegion::kWholeHair ? "whole-hair" : "near-arcs";
}

bool ParseCurlRegion(const std::string& name, CurlRegion* region) {
  for (const CurlRegion r : {CurlRegion::kNearArcs, CurlRegion::kWholeHair}) {
    if (name == CurlRegionName(r)) {
      *region = r;
      return true;
    }
  }
  return false;
}

const char* CurlRadiusFromName(CurlRadiusFrom from) {
  switch (from) {
    case CurlRadiusFrom::kCurvature:
      return "curvature";
    case CurlRadiusFrom::kTurnRate:
      return "turn-rate";
    case CurlRadiusFrom::kCurvatureAndTorsion:
      return "curvature-and-torsion";
    case CurlRadiusFrom::kHelixFit:
      return "helix-fit";
    case CurlRadiusFrom::kHelixFitLessBias:
      return "helix-fit-less-bias";
  }
  return "curvature";
}

bool FromFittedHelices(CurlRadiusFrom from) {
  return from == CurlRadiusFrom::kHelixFit || from == CurlRadiusFrom::kHelixFitLessBias;
}

bool ParseCurlRadiusFrom(const std::string& name, CurlRadiusFrom* from) {
  for (const CurlRadiusFrom candidate : kCurlRadiusFroms) {
    if (name == CurlRadiusFromName(candidate)) {
      *from = candidate;
      return true;
    }
  }
  return false;
}

Status CurlFieldOptions::Check() const {
  if (!(axis_cell_mm > 0)) return InvalidArgument("curl axis_cell_mm must be positive");
  if (!(min_arc_angle_deg > 0 && min_arc_angle_deg < 90))
    return InvalidArgument("curl min_arc_angle_deg must lie in (0, 90)");
  if (!(min_arc_length_mm > 0)) return InvalidArgument("curl min_arc_length_mm must be positive");
  if (!(min_turn_consistency >= 0 && min_turn_consistency <= 1))
    return InvalidArgument("curl min_turn_consistency must lie in [0, 1]");
  if (min_arcs < 1) return InvalidArgument("curl min_arcs must be at least 1");
  if (!(min_arc_share >= 0 && min_arc_share <= 1))
    return InvalidArgument("curl min_arc_share must lie in [0, 1]");
  if (!(min_handedness_agreement >= 0.5 && min_handedness_agreement <= 1))
    return InvalidArgument("curl min_handedness_agreement must lie in [0.5, 1]");
  if (!(region_mm > 0)) return InvalidArgument("curl region_mm must be positive");
  if (!(whole_hair_min_arc_share >= 0 && whole_hair_min_arc_share <= 1))
    return InvalidArgument("curl whole_hair_min_arc_share must be in [0, 1]");
  if (!(min_depth_mm >= 0 && std::isfinite(min_depth_mm)))
    return InvalidArgument("curl min_depth_mm must be finite and not negative");
  if (!(bend_span_mm > 0 && bend_span_mm <= 20))
    return InvalidArgument("curl bend_span_mm must lie in (0, 20]");
  if (!(bend_axis_relax_mm > 0)) return InvalidArgument("curl bend_axis_relax_mm must be positive");
  if (!(min_bend_deg >= 0 && min_bend_deg < 90))
    return InvalidArgument("curl min_bend_deg must lie in [0, 90)");
  if (!(max_helix_angle_deg > min_arc_angle_deg && max_helix_angle_deg < 90))
    return InvalidArgument("curl max_helix_angle_deg must lie in (min_arc_angle_deg, 90)");
  if (!(min_radius_mm > 0 && max_radius_mm >= min_radius_mm))
    return InvalidArgument("curl radii: 0 < min_radius_mm <= max_radius_mm");
  return Status::Ok();
}

HelixShape CurlEstimate::RawShape() const {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const double alpha = helix_angle_deg * M_PI / 180;
  if (radius_from == CurlRadiusFrom::kCurvatureAndTorsion) {
    const double k2t2 = curvature_per_mm * curvature_per_mm + torsion_per_mm * torsion_per_mm;
    if (!(curvature_per_mm > 0)) return {kNone, kNone};
    return {curvature_per_mm / k2t2, 2 * M_PI * torsion_per_mm / k2t2};
  }
  if (FromFittedHelices(radius_from))
    return fitted.radius_mm > 0 ? fitted : HelixShape{kNone, kNone};
  double radius = kNone;
  if (radius_from == CurlRadiusFrom::kTurnRate && rate_per_mm > 0)
    radius = std::sin(alpha) / rate_per_mm;
  if (radius_from == CurlRadiusFrom::kCurvature && curvature_per_mm > 0)
    radius = std::sin(alpha) * std::sin(alpha) / curvature_per_mm;
  return {radius, 2 * M_PI * radius / std::tan(alpha)};
}

nlohmann::json CurlEstimate::ToJson() const {
  return {{"curly", curl.curly()},
          {"radius_mm", curl.radius_mm},
          {"pitch_mm", curl.pitch_mm},
          {"handedness", curl.handedness},
          {"arcs", arcs},
          {"arc_share", arc_share},
          {"helix_angle_deg", helix_angle_deg},
          {"rate_per_mm", rate_per_mm},
          {"curvature_per_mm", curvature_per_mm},
          {"torsion_per_mm", torsion_per_mm},
          {"fitted_radius_mm", fitted.radius_mm},
          {"fitted_pitch_mm", fitted.pitch_mm},
          {"fitted_arcs", fitted_arcs},
          {"radius_from", CurlRadiusFromName(radius_from)},
          {"region", curl.curly() ? CurlRegionName(region) : "none"},
          {"handedness_agreement", HandednessAgreement()},
          {"right_handed_share", right_handed_share},
          {"local_handedness_agreement", local_handedness_agreement}};
}

// The cells (region_mm) within one cell of a seen arc's, and the way the
// arcs about each axis cell turn.
struct CurlField::Region {
  bool whole_hair = false;  // CurlRegion::kWholeHair: `cells` is not asked
  double cell_mm = 20;
  std::unordered_set<int64_t> cells;
  double axis_cell_mm = 10;
  // Per axis cell: the right-handed less the left-handed arcs' length (mm)
  // over the 27 cells around it.
  std::unordered_map<int64_t, double> turn_mm;
  Curl mirrored;  // the estimate's curl, the other way round
};

namespace {

// A seen arc: its length, the way it turns (+1 right-handed) and the axis
// cells its points lie in.
struct Arc {
  double length_mm = 0;
  int sense = 1;
  std::vector<int64_t> cells;
};

std::vector<int64_t> AxisCells(const StrandSegment& s, double cell_mm) {
  std::vector<int64_t> cells;
  for (const Eigen::Vector3f& p : s.points_mm) cells.push_back(CellKey(CellOf(p, cell_mm)));
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

// Per axis cell, the signed length of the arcs with a point in it.
std::unordered_map<int64_t, double> SignedLengthPerCell(const std::vector<Arc>& arcs) {
  std::unordered_map<int64_t, double> per_cell;
  for (const Arc& a : arcs)
    for (int64_t c : a.cells) per_cell[c] += a.sense * a.length_mm;
  return per_cell;
}

// The share of the arcs' length that turns the way the other arcs in its
// cells turn (arcs alone in their cells left out); 0 when every arc is alone.
double LocalAgreement(const std::vector<Arc>& arcs,
                      const std::unordered_map<int64_t, double>& per_cell) {
  double agreeing = 0, counted = 0;
  for (const Arc& a : arcs) {
    double others = 0;
    for (int64_t c : a.cells) others += per_cell.at(c) - a.sense * a.length_mm;
    if (std::abs(others) < 1e-9) continue;
    counted += a.length_mm;
    if (others * a.sense > 0) agreeing += a.length_mm;
  }
  return counted > 0 ? agreeing / counted : 0;
}

}  // namespace

CurlField CurlField::Everywhere(const Curl& curl) {
  CurlField field;
  field.estimate_.curl = curl;
  return field;
}

CurlField CurlField::Estimate(const std::vector<StrandSegment>& segments,
                              const CurlFieldOptions& o) {
  CurlField field;
  if (!o.enabled || segments.empty()) return field;
  const AxisGrid axes(segments, o.axis_cell_mm);
  std::vector<std::pair<double, double>> angles, rates, curvatures, torsions, fit_radii,
      fit_pitches;
  std::vector<Arc> arcs;
  double seen_mm = 0, arc_mm = 0, right_mm = 0;
  auto region = std::make_shared<Region>();
  region->cell_mm = o.region_mm;
  region->axis_cell_mm = o.axis_cell_mm;
  const double min_angle = o.min_arc_angle_deg * M_PI / 180;
  for (const StrandSegment& s : segments) {
    const SegmentTurn turn = TurnAlong(s, axes);
    seen_mm += turn.length_mm;
    if (turn.length_mm < o.min_arc_length_mm || turn.helix_angle < min_angle ||
        turn.consistency < o.min_turn_consistency || turn.rate == 0)
      continue;
    arc_mm += turn.length_mm;
    if (turn.rate > 0) right_mm += turn.length_mm;
    angles.emplace_back(turn.helix_angle, turn.length_mm);
    rates.emplace_back(std::abs(turn.rate), turn.length_mm);
    double curvature = 0, torsion = 0;
    Bending(s.points_mm, &curvature, &torsion);
    curvatures.emplace_back(curvature, turn.length_mm);
    torsions.emplace_back(std::abs(torsion), turn.length_mm);
    HelixShape fitted;
    const bool fits = o.radius_from == CurlRadiusFrom::kHelixFitLessBias
                          ? FitHelixLessItsBias(s.points_mm, &fitted)
                          : FitHelix(s.points_mm, &fitted);
    if (fits) {
      fit_radii.emplace_back(fitted.radius_mm, turn.length_mm);
      fit_pitches.emplace_back(fitted.pitch_mm, turn.length_mm);
    }
    arcs.push_back({turn.length_mm, turn.rate > 0 ? 1 : -1, AxisCells(s, o.axis_cell_mm)});
    for (const Eigen::Vector3f& p : s.points_mm)
      ForNeighbourCells(CellOf(p, o.region_mm), [&](int64_t k) { region->cells.insert(k); });
  }
  CurlEstimate& e = field.estimate_;
  e.arcs = static_cast<int64_t>(arcs.size());
  e.arc_share = seen_mm > 0 ? arc_mm / seen_mm : 0;
  if (e.arcs == 0) return field;
  const double alpha = WeightedMedian(angles), rate = WeightedMedian(rates);
  e.helix_angle_deg = alpha * 180 / M_PI;
  e.rate_per_mm = rate;
  e.curvature_per_mm = WeightedMedian(curvatures);
  e.torsion_per_mm = WeightedMedian(torsions);
  e.fitted = {WeightedMedian(fit_radii), WeightedMedian(fit_pitches)};
  e.fitted_arcs = static_cast<int64_t>(fit_radii.size());
  // Too few arcs for fitted helices (loose curls' arcs turn under a quarter
  // turn): their curvature and torsion.
  e.radius_from = FromFittedHelices(o.radius_from) && e.fitted_arcs < o.min_arcs
                      ? CurlRadiusFrom::kCurvatureAndTorsion
                      : o.radius_from;
  e.right_handed_share = right_mm / arc_mm;
  const std::unordered_map<int64_t, double> per_cell = SignedLengthPerCell(arcs);
  e.local_handedness_agreement = LocalAgreement(arcs, per_cell);
  const HelixShape shape = e.RawShape();
  const double radius = std::max(shape.radius_mm, o.min_radius_mm);
  // A radius raised to the least keeps the fitted helices' helix angle (the
  // pitch scaled with it), else takes the arcs' angle to their neighbours'
  // axis.
  double pitch = shape.pitch_mm;
  if (radius > shape.radius_mm)
    pitch = FromFittedHelices(e.radius_from) ? shape.pitch_mm * radius / shape.radius_mm
                                             : 2 * M_PI * radius / std::tan(alpha);
  if (e.arcs < o.min_arcs || e.arc_share < o.min_arc_share ||
      e.local_handedness_agreement < o.min_handedness_agreement || !(radius <= o.max_radius_mm) ||
      !(pitch > 0 && std::isfinite(pitch)) || e.helix_angle_deg > o.max_helix_angle_deg)
    return field;
  e.region = o.region == CurlRegion::kWholeHair && e.arc_share >= o.whole_hair_min_arc_share
                 ? CurlRegion::kWholeHair
                 : CurlRegion::kNearArcs;
  region->whole_hair = e.region == CurlRegion::kWholeHair;
  e.curl.handedness = right_mm * 2 >= arc_mm ? 1 : -1;
  e.curl.radius_mm = radius;
  e.curl.pitch_mm = pitch;
  for (const auto& [key, signed_mm] : per_cell)
    ForNeighbourCells(Unkey(key), [&](int64_t k) { region->turn_mm[k] += signed_mm; });
  region->mirrored = e.curl;
  region->mirrored.handedness = -e.curl.handedness;
  field.region_ = std::move(region);
  return field;
}

const Curl* CurlField::At(const Eigen::Vector3f& p) const {
  if (!estimate_.curl.curly()) return nullptr;
  if (!region_) return &estimate_.curl;
  if (!region_->whole_hair && region_->cells.count(CellKey(CellOf(p, region_->cell_mm))) == 0)
    return nullptr;
  const auto turn = region_->turn_mm.find(CellKey(CellOf(p, region_->axis_cell_mm)));
  const bool mirrored =
      turn != region_->turn_mm.end() && turn->second * estimate_.curl.handedness < 0;
  return mirrored ? &region_->mirrored : &estimate_.curl;
}

}  // namespace hairrig
