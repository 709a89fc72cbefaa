// Crash points for the kill-and-resume tests: the dataset calls CrashPoint at
// the instants where a crash is most harmful (half a frame written, a frame
// renamed into place but not yet journalled, half a journal record written).
// With HAIRRIG_CRASH_AT="<name>:<n>" in the environment the process kills
// itself with SIGKILL at the n-th time it reaches point <name>; without it a
// crash point does nothing. Names: frame_half_written, frame_before_rename,
// frame_before_journal, journal_half_written, manifest_half_written.
#pragma once

namespace hairrig {

void CrashPoint(const char* name);

}  // namespace hairrig
