#include "core/version.h"

#ifndef HAIRRIG_VERSION
#error "HAIRRIG_VERSION is set by core/CMakeLists.txt from the project's VERSION"
#endif

namespace hairrig {

const char* HairrigVersion() { return HAIRRIG_VERSION; }

}  // namespace hairrig
