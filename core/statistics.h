// Small statistics shared by every module that summarises measurements.
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace hairrig {

// The element at floor(q * size) once sorted (the last for q >= 1, the first
// for q <= 0 or NaN): no interpolation, so Quantile(v, 0.5) is Median(v).
// 0 for no values.
template <typename T>
double Quantile(std::vector<T> values, double q) {
  if (values.empty()) return 0;
  const double position = q > 0 ? q * static_cast<double>(values.size()) : 0.0;
  const size_t k =
      std::min(values.size() - 1,
               static_cast<size_t>(std::min(position, static_cast<double>(values.size()))));
  const auto kth = values.begin() + static_cast<std::ptrdiff_t>(k);
  std::nth_element(values.begin(), kth, values.end());
  return static_cast<double>(*kth);
}

// The upper median (the element at size / 2 once sorted); 0 for no values.
template <typename T>
double Median(std::vector<T> values) {
  return Quantile(std::move(values), 0.5);
}

}  // namespace hairrig
