// The hairrig version (the top-level CMakeLists.txt's project VERSION), as
// recorded in stage results (batch/stage_record.h) and printed by
// `hairrig --version`.
#pragma once

namespace hairrig {

// "MAJOR.MINOR.PATCH".
const char* HairrigVersion();

}  // namespace hairrig
