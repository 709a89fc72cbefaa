#include "simulation/guide_interpolation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace hairrig {

namespace {

// Arc length (mm) from the root of every point of a curve.
template <typename Point>
std::vector<double> ArcLengths(const Point* points, size_t count) {
  std::vector<double> s(count, 0.0);
  for (size_t i = 1; i < count; ++i)
    s[i] = s[i - 1] + (points[i] - points[i - 1]).template cast<double>().norm();
  return s;
}

// The arc length on a guide matched with point i of a strand: the same arc
// length where the strand is no longer than the guide, the same share of the
// length where it is longer (so its tail bends with the whole guide).
double MatchedArcLength(const std::vector<double>& strand_lengths,
                        const std::vector<double>& guide_lengths, size_t i) {
  const double strand = strand_lengths.back(), guide = guide_lengths.back();
  return strand > guide ? strand_lengths[i] * (guide / strand) : strand_lengths[i];
}

// Where arc length s falls on a curve (clamped to its ends): between points
// index - 1 and index, `blend` of the way.
void Locate(const std::vector<double>& lengths, double s, int* index, double* blend) {
  const auto it = std::upper_bound(lengths.begin(), lengths.end(), s);
  if (it == lengths.begin()) {
    *index = 1;
    *blend = 0;
    return;
  }
  if (it == lengths.end()) {
    *index = static_cast<int>(lengths.size()) - 1;
    *blend = 1;
    return;
  }
  const size_t i = static_cast<size_t>(it - lengths.begin());
  const double span = lengths[i] - lengths[i - 1];
  *index = static_cast<int>(i);
  *blend = span > 0 ? (s - lengths[i - 1]) / span : 0.0;
}

Eigen::Vector3d Blend(const std::vector<Eigen::Vector3d>& curve, int index, double blend) {
  return (1 - blend) * curve[static_cast<size_t>(index) - 1] +
         blend * curve[static_cast<size_t>(index)];
}

// min |sum w_k (g_k - p)|^2 + beta sum d_k^2 w_k^2 s.t. sum w_k = 1 (KKT system).
Eigen::VectorXd ConstrainedWeights(const std::vector<Eigen::Vector3d>& candidates,
                                   const Eigen::Vector3d& p, double beta) {
  const int k = static_cast<int>(candidates.size());
  Eigen::MatrixXd b(3, k);
  for (int i = 0; i < k; ++i) b.col(i) = candidates[static_cast<size_t>(i)] - p;
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(k + 1, k + 1);
  kkt.topLeftCorner(k, k) = b.transpose() * b;
  const double scale = std::max(1e-12, kkt.topLeftCorner(k, k).diagonal().maxCoeff());
  for (int i = 0; i < k; ++i) kkt(i, i) += beta * b.col(i).squaredNorm() + 1e-9 * scale;
  kkt.block(0, k, k, 1).setOnes();
  kkt.block(k, 0, 1, k).setOnes();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k + 1);
  rhs[k] = 1;
  return kkt.colPivHouseholderQr().solve(rhs).head(k);
}

// Rebuilds each strand of `blended` from its root: every segment keeps its
// direction in `blended` and takes its length in `rest` (a segment the blend
// shrank to nothing keeps its rest direction).
void RestoreSegmentLengths(const StrandSet& rest, StrandSet* blended) {
  const std::vector<size_t> offsets = rest.Offsets();
  for (size_t s = 0; s + 1 < offsets.size(); ++s) {
    Eigen::Vector3f previous = blended->points_mm[offsets[s]];  // as blended
    bool rebuilt = false;  // whether a point before i moved off its blended place
    for (size_t i = offsets[s] + 1; i < offsets[s + 1]; ++i) {
      const Eigen::Vector3f rest_step = rest.points_mm[i] - rest.points_mm[i - 1];
      const Eigen::Vector3f step = blended->points_mm[i] - previous;
      previous = blended->points_mm[i];
      const float length = step.norm(), rest_length = rest_step.norm();
      if (!rebuilt && length == rest_length) continue;  // the rest shape stays exact
      rebuilt = true;
      blended->points_mm[i] =
          blended->points_mm[i - 1] + (length > 0 ? step * (rest_length / length) : rest_step);
    }
  }
}

}  // namespace

Status GuideInterpolationOptions::Check() const {
  if (guides_per_strand < 1 || guides_per_strand > 8) {
    return InvalidArgument("guides_per_strand must lie in 1..8, got " +
                           std::to_string(guides_per_strand));
  }
  if (!(regularisation >= 0) || !std::isfinite(regularisation))
    return InvalidArgument("regularisation must be finite and >= 0");
  return Status::Ok();
}

Result<GuideInterpolation> GuideInterpolation::Build(
    const StrandSet& full_rest, const std::vector<std::vector<Eigen::Vector3d>>& guides_rest,
    const GuideInterpolationOptions& options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("guide interpolation"));
  if (guides_rest.empty()) return InvalidArgument("guide interpolation: no guide");
  HR_RETURN_IF_ERROR(full_rest.Check());
  GuideInterpolation out;
  out.rest_ = full_rest;
  out.guides_rest_ = guides_rest;
  std::vector<std::vector<double>> guide_lengths;
  for (size_t g = 0; g < guides_rest.size(); ++g) {
    const auto& curve = guides_rest[g];
    if (curve.size() < 2)
      return InvalidArgument("guide interpolation: guide " + std::to_string(g) + " has < 2 points");
    for (const auto& p : curve) {
      if (!p.allFinite())
        return InvalidArgument("guide interpolation: guide " + std::to_string(g) +
                               " is not finite");
    }
    guide_lengths.push_back(ArcLengths(curve.data(), curve.size()));
  }
  const int k = std::min<int>(options.guides_per_strand, static_cast<int>(guides_rest.size()));
  out.per_particle_ = k;
  out.keep_lengths_ = options.keep_lengths;
  const std::vector<size_t> offsets = full_rest.Offsets();
  out.particles_.resize(full_rest.num_points());
  std::vector<int> order(guides_rest.size());
  double squared_error = 0;
  for (size_t s = 0; s < full_rest.num_strands(); ++s) {
    const Eigen::Vector3d root = full_rest.points_mm[offsets[s]].cast<double>();
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + k, order.end(), [&](int a, int b) {
      return (guides_rest[static_cast<size_t>(a)][0] - root).squaredNorm() <
             (guides_rest[static_cast<size_t>(b)][0] - root).squaredNorm();
    });
    const std::vector<double> lengths =
        ArcLengths(&full_rest.points_mm[offsets[s]], offsets[s + 1] - offsets[s]);
    for (size_t i = offsets[s]; i < offsets[s + 1]; ++i) {
      Particle& particle = out.particles_[i];
      std::vector<Eigen::Vector3d> candidates;
      for (int j = 0; j < k; ++j) {
        const size_t g = static_cast<size_t>(order[static_cast<size_t>(j)]);
        particle.guides[j] = static_cast<int>(g);
        Locate(guide_lengths[g], MatchedArcLength(lengths, guide_lengths[g], i - offsets[s]),
               &particle.segment[j], &particle.blend[j]);
        candidates.push_back(Blend(guides_rest[g], particle.segment[j], particle.blend[j]));
      }
      const Eigen::Vector3d p = full_rest.points_mm[i].cast<double>();
      const Eigen::VectorXd w = ConstrainedWeights(candidates, p, options.regularisation);
      Eigen::Vector3d fit = Eigen::Vector3d::Zero();
      for (int j = 0; j < k; ++j) {
        particle.weights[j] = w[j];
        fit += w[j] * candidates[static_cast<size_t>(j)];
      }
      squared_error += (fit - p).squaredNorm();
    }
  }
  out.rest_fit_rms_mm_ =
      std::sqrt(squared_error / static_cast<double>(std::max<size_t>(1, full_rest.num_points())));
  return out;
}

Result<StrandSet> GuideInterpolation::Apply(
    const std::vector<std::vector<Eigen::Vector3d>>& guides_now) const {
  if (guides_now.size() != guides_rest_.size()) {
    return InvalidArgument("guide interpolation: " + std::to_string(guides_now.size()) +
                           " guides given, " + std::to_string(guides_rest_.size()) + " at rest");
  }
  for (size_t g = 0; g < guides_now.size(); ++g) {
    if (guides_now[g].size() != guides_rest_[g].size()) {
      return InvalidArgument("guide interpolation: guide " + std::to_string(g) +
                             " changed its point count");
    }
  }
  StrandSet out = rest_;
  for (size_t i = 0; i < particles_.size(); ++i) {
    const Particle& particle = particles_[i];
    Eigen::Vector3d displacement = Eigen::Vector3d::Zero();
    for (int j = 0; j < per_particle_; ++j) {
      const size_t g = static_cast<size_t>(particle.guides[j]);
      displacement +=
          particle.weights[j] * (Blend(guides_now[g], particle.segment[j], particle.blend[j]) -
                                 Blend(guides_rest_[g], particle.segment[j], particle.blend[j]));
    }
    out.points_mm[i] += displacement.cast<float>();
  }
  if (keep_lengths_) RestoreSegmentLengths(rest_, &out);
  return out;
}

}  // namespace hairrig
