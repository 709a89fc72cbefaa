#include "core/version.h"

#include "core/sha256.h"

#ifndef HAIRRIG_VERSION
#error "HAIRRIG_VERSION is set by core/CMakeLists.txt from the project's VERSION"
#endif

namespace hairrig {

const char* HairrigVersion() { return HAIRRIG_VERSION; }

Result<std::string> HairrigBuildSha256() {
  static const Result<std::string> build = Sha256OfFile("/proc/self/exe");
  return build;
}

}  // namespace hairrig
