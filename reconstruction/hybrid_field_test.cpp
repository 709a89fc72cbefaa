#include "reconstruction/hybrid_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hairrig {
namespace {

// Fixed voxels on the faces x = 0 and x = nx - 1 hold a value linear in x
// (per channel: a different slope); the other faces are mirrors, so the
// harmonic interpolant is that linear function everywhere; enough sweeps
// reach it. Returns channel 0's values.
std::vector<float> ExpectLinearInX(const Eigen::Vector3i& size, int channels, int sweeps) {
  const auto index = [&](int x, int y, int z) {
    return static_cast<size_t>(x + size.x() * (y + size.y() * z));
  };
  const size_t voxels = static_cast<size_t>(size.x()) * size.y() * size.z();
  std::vector<uint8_t> fixed(voxels, 0);
  std::vector<float> values(voxels * static_cast<size_t>(channels), 0.f);
  const auto truth = [&](int x, int c) { return static_cast<float>((c + 1) * x - 2 * c); };
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x : {0, size.x() - 1}) {
        fixed[index(x, y, z)] = 1;
        for (int c = 0; c < channels; ++c)
          values[index(x, y, z) * static_cast<size_t>(channels) + static_cast<size_t>(c)] =
              truth(x, c);
      }
  SolveLaplace(size, channels, fixed, &values, sweeps);
  std::vector<float> first(voxels);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x)
        for (int c = 0; c < channels; ++c) {
          const float v =
              values[index(x, y, z) * static_cast<size_t>(channels) + static_cast<size_t>(c)];
          if (c == 0) first[index(x, y, z)] = v;
          EXPECT_NEAR(v, truth(x, c), 1e-3 * (c + 1) * size.x())
              << "voxel " << x << "," << y << "," << z << " channel " << c << " of " << channels;
        }
  return first;
}

TEST(SolveLaplace, LinearBetweenFixedFacesForEveryChannelCount) {
  // The channels are solved independently, by the same arithmetic whatever
  // their count: channel 0 comes out the same to the bit.
  const Eigen::Vector3i size(20, 9, 7);
  const std::vector<float> one = ExpectLinearInX(size, 1, 300);
  EXPECT_EQ(ExpectLinearInX(size, 2, 300), one);
  EXPECT_EQ(ExpectLinearInX(size, 3, 300), one);
}

TEST(SolveLaplace, SmallGridsWithoutCoarseLevel) {
  ExpectLinearInX(Eigen::Vector3i(5, 3, 2), 3, 300);
  ExpectLinearInX(Eigen::Vector3i(3, 1, 1), 1, 300);
}

}  // namespace
}  // namespace hairrig
