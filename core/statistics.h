// Small statistics shared by every module that summarises measurements.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace hairrig {

// The upper median (the element at size / 2 once sorted); 0 for no values.
template <typename T>
double Median(std::vector<T> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return static_cast<double>(*middle);
}

}  // namespace hairrig
