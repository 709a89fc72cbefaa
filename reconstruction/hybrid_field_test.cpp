#include "reconstruction/hybrid_field.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace hairrig {
namespace {

// Voxel (x, y, z)'s index, as SolveLaplace lays the grid out (x fastest).
size_t VoxelIndex(const Eigen::Vector3i& size, int x, int y, int z) {
  return static_cast<size_t>(x + size.x() * (y + size.y() * z));
}

// Fixed voxels on the faces x = 0 and x = nx - 1 hold a value linear in x
// (per channel: a different slope); the other faces are mirrors, so the
// harmonic interpolant is that linear function everywhere; enough sweeps
// reach it. Returns channel 0's values.
std::vector<float> ExpectLinearInX(const Eigen::Vector3i& size, int channels, int sweeps) {
  const auto index = [&](int x, int y, int z) { return VoxelIndex(size, x, y, z); };
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

// Every face fixed to a linear function, which the 6-neighbour stencil
// holds exactly: on a grid large enough for the coarse levels, every voxel
// ends at it, whichever axis it varies along.
TEST(SolveLaplace, LinearFunctionThroughTheCoarseLevels) {
  const Eigen::Vector3i size(20, 12, 10);
  const auto index = [&](int x, int y, int z) { return VoxelIndex(size, x, y, z); };
  const auto truth = [](int x, int y, int z) { return static_cast<float>(x + 2 * y - 3 * z); };
  std::vector<uint8_t> fixed(static_cast<size_t>(size.prod()), 0);
  std::vector<float> values(fixed.size(), 0.f);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const bool face = x == 0 || y == 0 || z == 0 || x + 1 == size.x() || y + 1 == size.y() ||
                          z + 1 == size.z();
        if (!face) continue;
        fixed[index(x, y, z)] = 1;
        values[index(x, y, z)] = truth(x, y, z);
      }
  SolveLaplace(size, 1, fixed, &values, 200);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x)
        EXPECT_NEAR(values[index(x, y, z)], truth(x, y, z), 1e-3)
            << "voxel " << x << "," << y << "," << z;
}

// Plain Gauss-Seidel SOR (omega 1.7, the neighbours that exist summed in
// the order -x, +x, -y, +y, -z, +z), one channel, for a grid without coarse
// levels: SolveLaplace must match it to the bit.
std::vector<float> ReferenceSor(const Eigen::Vector3i& size, const std::vector<uint8_t>& fixed,
                                std::vector<float> v, int sweeps) {
  const int64_t sy = size.x(), sz = static_cast<int64_t>(size.x()) * size.y();
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (int z = 0; z < size.z(); ++z)
      for (int y = 0; y < size.y(); ++y)
        for (int x = 0; x < size.x(); ++x) {
          const int64_t i = x + sy * y + sz * z;
          if (fixed[static_cast<size_t>(i)]) continue;
          const std::array<std::pair<bool, int64_t>, 6> nb = {{{x > 0, i - 1},
                                                               {x + 1 < size.x(), i + 1},
                                                               {y > 0, i - sy},
                                                               {y + 1 < size.y(), i + sy},
                                                               {z > 0, i - sz},
                                                               {z + 1 < size.z(), i + sz}}};
          float sum = 0;
          int n = 0;
          for (const auto& [exists, j] : nb)
            if (exists) sum += v[static_cast<size_t>(j)], ++n;
          float& value = v[static_cast<size_t>(i)];
          value += 1.7f * (sum / static_cast<float>(n) - value);
        }
  return v;
}

TEST(SolveLaplace, SmallGridIsPlainSorToTheBit) {
  const Eigen::Vector3i size(7, 6, 5);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(-5.f, 5.f);
  std::vector<uint8_t> fixed(static_cast<size_t>(size.prod()));
  std::vector<float> values(fixed.size());
  for (size_t i = 0; i < fixed.size(); ++i) {
    fixed[i] = rng() % 4 == 0 ? 1 : 0;
    values[i] = value(rng);
  }
  const std::vector<float> expected = ReferenceSor(size, fixed, values, 9);
  SolveLaplace(size, 1, fixed, &values, 9);
  EXPECT_EQ(values, expected);
}

TEST(SolveLaplace, TinyGrids) {
  ExpectLinearInX(Eigen::Vector3i(5, 3, 2), 3, 300);
  ExpectLinearInX(Eigen::Vector3i(3, 1, 1), 1, 300);
}

}  // namespace
}  // namespace hairrig
