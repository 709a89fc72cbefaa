// Raising a test process' limit on open files, for the connection-flood tests.
#pragma once

#include <sys/resource.h>

namespace hairrig_test {

// Raises this process' soft limit on open files to `wanted` (up to the hard
// limit); false when the hard limit is lower or the call fails.
inline bool AllowOpenFiles(rlim_t wanted) {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0) return false;
  if (limit.rlim_cur >= wanted) return true;
  if (limit.rlim_max != RLIM_INFINITY && limit.rlim_max < wanted) return false;
  limit.rlim_cur = wanted;
  return setrlimit(RLIMIT_NOFILE, &limit) == 0;
}

}  // namespace hairrig_test
