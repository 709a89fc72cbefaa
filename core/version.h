// The hairrig version (the top-level CMakeLists.txt's project VERSION), as
// recorded in stage results (batch/stage_record.h) and printed by
// `hairrig --version`, and the identity of the running build.
#pragma once

#include <string>

#include "core/status.h"

namespace hairrig {

// "MAJOR.MINOR.PATCH".
const char* HairrigVersion();

// The running executable's build: its GNU build ID (hex; the linker's hash of
// the linked program, read from the loaded program's notes, no file read),
// else the SHA-256 of its file (/proc/self/exe) for a toolchain that writes
// no build ID. A rebuild after a code change, or a build by another
// compiler, has another one under the same version; copies of one build have
// the same. IoError naming the file when the fallback cannot read it.
Result<std::string> HairrigBuildId();

}  // namespace hairrig
