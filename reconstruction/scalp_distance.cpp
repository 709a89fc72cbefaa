#include "reconstruction/scalp_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace hairrig {

ScalpDistance::ScalpDistance(const HeadModel* head) {
  if (head == nullptr) return;
  std::mt19937_64 rng(17);
  samples_.resize(4000);
  for (Eigen::Vector3f& s : samples_) {
    Eigen::Vector3d normal;
    s = head->SampleScalp(rng, &normal).cast<float>();
  }
}

double ScalpDistance::operator()(const Eigen::Vector3f& p) const {
  float best = std::numeric_limits<float>::max();
  for (const Eigen::Vector3f& s : samples_) best = std::min(best, (s - p).squaredNorm());
  return samples_.empty() ? 0.0 : std::sqrt(best);
}

}  // namespace hairrig
