// The steady clock every module dates events with (frames' trigger and
// arrival times, capture and calibration delays), in nanoseconds.
#pragma once

#include <chrono>
#include <cstdint>

namespace hairrig {

inline int64_t SteadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Seconds from a SteadyNowNs() reading to now.
inline double SecondsSince(int64_t start_ns) {
  return static_cast<double>(SteadyNowNs() - start_ns) * 1e-9;
}

}  // namespace hairrig
