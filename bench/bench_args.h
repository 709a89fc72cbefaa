// Command-line helpers shared by the benches.
#pragma once

#include <cstdio>
#include <cstring>

namespace hairrig {

// `value` of option `flag` as yes or no into *out; false, with a message
// naming the flag on stderr, for anything else (*out untouched).
inline bool ParseYesNo(const char* flag, const char* value, bool* out) {
  if (std::strcmp(value, "yes") != 0 && std::strcmp(value, "no") != 0) {
    std::fprintf(stderr, "%s takes yes or no, not '%s'\n", flag, value);
    return false;
  }
  *out = std::strcmp(value, "yes") == 0;
  return true;
}

}  // namespace hairrig
