#include "simulation/guides.h"

#include <algorithm>
#include <cmath>
#include <queue>

namespace hairrig {

std::vector<Eigen::Vector3f> ResampleByArcLength(const Eigen::Vector3f* points, size_t count,
                                                 int samples) {
  std::vector<double> cumulative{0};
  for (size_t i = 1; i < count; ++i)
    cumulative.push_back(cumulative.back() + (points[i] - points[i - 1]).norm());
  std::vector<Eigen::Vector3f> out;
  const double total = cumulative.back();
  size_t seg = 0;
  for (int k = 0; k < samples; ++k) {
    const double s = samples == 1 ? 0 : total * k / (samples - 1);
    while (seg + 2 < count && cumulative[seg + 1] < s) ++seg;
    if (count == 1 || total <= 0) {
      out.push_back(points[0]);
      continue;
    }
    const double span = cumulative[seg + 1] - cumulative[seg];
    const float u =
        static_cast<float>(span > 0 ? std::clamp((s - cumulative[seg]) / span, 0.0, 1.0) : 0.0);
    out.push_back(points[seg] + u * (points[seg + 1] - points[seg]));
  }
  return out;
}

namespace {

using Features = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Cluster {
  std::vector<int> members;
  int guide = -1;
  double sum_squared = 0;  // of member-to-guide distances, per sample
  double Rms() const {
    return members.empty() ? 0 : std::sqrt(sum_squared / static_cast<double>(members.size()));
  }
};

double Distance2(const Features& f, int a, const Eigen::RowVectorXf& b, int samples) {
  return static_cast<double>((f.row(a) - b).squaredNorm()) / samples;
}

// The guide is the member nearest the mean (the first member where no
// distance compares); fills sum_squared.
void ChooseGuide(const Features& f, int samples, Cluster* c) {
  Eigen::RowVectorXf mean = Eigen::RowVectorXf::Zero(f.cols());
  for (int m : c->members) mean += f.row(m);
  mean /= static_cast<float>(c->members.size());
  c->guide = c->members.front();
  double best = Distance2(f, c->guide, mean, samples);
  for (int m : c->members) {
    const double d = Distance2(f, m, mean, samples);
    if (d < best || std::isnan(best)) {
      best = d;
      c->guide = m;
    }
  }
  c->sum_squared = 0;
  const Eigen::RowVectorXf guide = f.row(c->guide);
  for (int m : c->members) c->sum_squared += Distance2(f, m, guide, samples);
}

int Farthest(const Features& f, const std::vector<int>& members, const Eigen::RowVectorXf& from,
             int samples) {
  int best = members.front();
  double best_d = -1;
  for (int m : members) {
    const double d = Distance2(f, m, from, samples);
    if (d > best_d) {
      best_d = d;
      best = m;
    }
  }
  return best;
}

// 2-means seeded with two distant members.
std::pair<Cluster, Cluster> Split(const Features& f, const Cluster& c, const GuideOptions& o) {
  Eigen::RowVectorXf a = f.row(Farthest(f, c.members, f.row(c.guide), o.samples));
  Eigen::RowVectorXf b = f.row(Farthest(f, c.members, a, o.samples));
  std::pair<Cluster, Cluster> halves;
  for (int it = 0; it < o.kmeans_iterations; ++it) {
    halves = {};
    for (int m : c.members) {
      (Distance2(f, m, a, o.samples) <= Distance2(f, m, b, o.samples) ? halves.first
                                                                      : halves.second)
          .members.push_back(m);
    }
    if (halves.first.members.empty() || halves.second.members.empty()) break;
    Eigen::RowVectorXf na = Eigen::RowVectorXf::Zero(f.cols()), nb = na;
    for (int m : halves.first.members) na += f.row(m);
    for (int m : halves.second.members) nb += f.row(m);
    na /= static_cast<float>(halves.first.members.size());
    nb /= static_cast<float>(halves.second.members.size());
    if ((na - a).squaredNorm() + (nb - b).squaredNorm() == 0) break;
    a = na;
    b = nb;
  }
  if (halves.first.members.empty() || halves.second.members.empty()) {
    // Identical members: split the list in half.
    halves = {};
    for (size_t i = 0; i < c.members.size(); ++i)
      (i % 2 ? halves.second : halves.first).members.push_back(c.members[i]);
  }
  ChooseGuide(f, o.samples, &halves.first);
  ChooseGuide(f, o.samples, &halves.second);
  return halves;
}

}  // namespace

Status GuideOptions::Check() const {
  if (num_guides < 0) {
    return InvalidArgument("num_guides must be 0 (grow to target_rms_mm) or more, got " +
                           std::to_string(num_guides));
  }
  if (!(target_rms_mm > 0) || !std::isfinite(target_rms_mm))
    return InvalidArgument("target_rms_mm must be finite and positive");
  if (samples < 2)
    return InvalidArgument("samples must be at least 2, got " + std::to_string(samples));
  if (max_guides < 1)
    return InvalidArgument("max_guides must be at least 1, got " + std::to_string(max_guides));
  if (kmeans_iterations < 1) {
    return InvalidArgument("kmeans_iterations must be at least 1, got " +
                           std::to_string(kmeans_iterations));
  }
  return Status::Ok();
}

Result<GuideSelection> SelectGuides(const StrandSet& strands, const GuideOptions& o) {
  HR_RETURN_IF_ERROR(o.Check().WithContext("guide selection"));
  HR_RETURN_IF_ERROR(strands.Check());
  const int n = static_cast<int>(strands.num_strands());
  if (n == 0) return InvalidArgument("guide selection: the hair model has no strands");
  if (o.num_guides > n) {
    return InvalidArgument("guide selection: num_guides " + std::to_string(o.num_guides) +
                           " is more than the " + std::to_string(n) + " strands");
  }
  Features f(n, 3 * o.samples);
  const auto offsets = strands.Offsets();
  for (int s = 0; s < n; ++s) {
    const auto pts = ResampleByArcLength(&strands.points_mm[offsets[static_cast<size_t>(s)]],
                                         strands.point_counts[static_cast<size_t>(s)], o.samples);
    for (int k = 0; k < o.samples; ++k)
      f.block<1, 3>(s, 3 * k) = pts[static_cast<size_t>(k)].transpose();
  }
  std::vector<Cluster> clusters(1);
  for (int s = 0; s < n; ++s) clusters[0].members.push_back(s);
  ChooseGuide(f, o.samples, &clusters[0]);
  const int wanted = o.num_guides > 0 ? o.num_guides : std::min(o.max_guides, n);
  while (static_cast<int>(clusters.size()) < wanted) {
    // With a target: stop once the RMS distance of all strands to their guides meets it.
    if (o.num_guides == 0) {
      double total = 0;
      for (const auto& c : clusters) total += c.sum_squared;
      if (std::sqrt(total / n) <= o.target_rms_mm) break;
    }
    // The cluster that contributes most error is split next.
    auto worst = std::max_element(
        clusters.begin(), clusters.end(),
        [](const Cluster& x, const Cluster& y) { return x.sum_squared < y.sum_squared; });
    if (worst->members.size() < 2) break;
    auto [a, b] = Split(f, *worst, o);
    *worst = std::move(a);
    clusters.push_back(std::move(b));
  }
  GuideSelection out;
  out.cluster_of_strand.assign(static_cast<size_t>(n), -1);
  double total = 0;
  for (size_t g = 0; g < clusters.size(); ++g) {
    out.guide_strands.push_back(clusters[g].guide);
    for (int m : clusters[g].members)
      out.cluster_of_strand[static_cast<size_t>(m)] = static_cast<int>(g);
    total += clusters[g].sum_squared;
    out.max_cluster_rms_mm = std::max(out.max_cluster_rms_mm, clusters[g].Rms());
  }
  out.rms_error_mm = std::sqrt(total / n);
  return out;
}

}  // namespace hairrig
