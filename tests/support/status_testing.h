// Test helpers for Status results: an options struct's Check() or a loader
// that refuses a bad value must say kInvalidArgument and name what is wrong.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "core/status.h"

namespace hairrig {

// Succeeds when `status` is kInvalidArgument and its message contains `field`
// (the option's name, as a user would search for it). Use as
// EXPECT_TRUE(IsInvalidNaming(options.Check(), "field")) so that a failure
// reports the caller's line.
inline ::testing::AssertionResult IsInvalidNaming(const Status& status, const std::string& field) {
  if (status.code() != StatusCode::kInvalidArgument) {
    return ::testing::AssertionFailure()
           << "expected kInvalidArgument naming '" << field << "', got: " << status.ToString();
  }
  if (status.message().find(field) == std::string::npos) {
    return ::testing::AssertionFailure()
           << "the error does not name '" << field << "': " << status.ToString();
  }
  return ::testing::AssertionSuccess();
}

}  // namespace hairrig
