// zeta of Luo et al. 2013 Eq. 5: a point's distance to the closest point on
// the scalp (mm, the head's frame: the turntable frame), measured to a dense
// fixed sample of the scalp (4,000 points drawn with a fixed seed, so
// deterministic; a few mm apart on an adult head, so up to a few mm over the
// exact distance near the scalp, relatively less further out).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/head_model.h"

namespace hairrig {

class ScalpDistance {
 public:
  // `head` may be null: then available() is false and every distance is 0.
  explicit ScalpDistance(const HeadModel* head);

  bool available() const { return !samples_.empty(); }
  double operator()(const Eigen::Vector3f& p) const;

 private:
  std::vector<Eigen::Vector3f> samples_;
};

}  // namespace hairrig
