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

}  // namespace hairrig
