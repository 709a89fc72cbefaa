// The hairrig version (the top-level CMakeLists.txt's project VERSION), as
// recorded in stage results (batch/stage_record.h) and printed by
// `hairrig --version`, and the identity of the running build.
#pragma once

#include <string>

#include "core/status.h"

namespace hairrig {

// "MAJOR.MINOR.PATCH".
const char* HairrigVersion();

// The SHA-256 (hex) of the running executable's file (/proc/self/exe), read
// once per process: a rebuild after a code change, or a build by another
// compiler, has another one under the same version. IoError naming the file
// when it cannot be read.
Result<std::string> HairrigBuildSha256();

}  // namespace hairrig
