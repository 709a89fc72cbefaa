// Test helper: does a verdict (calibration or reconstruction) give a reason
// containing `text`? The verdict type needs a `reasons` vector of strings.
#pragma once

#include <string>

namespace hairrig_test {

template <typename Verdict>
bool HasReasonWith(const Verdict& verdict, const std::string& text) {
  for (const std::string& reason : verdict.reasons)
    if (reason.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace hairrig_test
