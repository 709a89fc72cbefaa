// Child processes for the batch engines: the local engine runs `hairrig stage`
// children, the Slurm engine runs sbatch, squeue, scontrol and scancel. Every
// program is started from an argument vector (posix_spawn), never through a
// shell, so no path or name is ever interpreted by one; job scripts that a
// shell does read quote every value with ShellQuote.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

struct ProcessOptions {
  // Non-empty: the child's stdout and stderr are appended to this file
  // (created if absent) instead of being captured.
  std::string output_file;
  // Non-empty: the child starts in this folder.
  std::string working_dir;
  // Captured bytes kept per stream; the rest is read and dropped.
  size_t max_capture_bytes = size_t{4} << 20;

  // Every value is valid (empty strings are the defaults above; 0 keeps no byte).
  Status Check() const { return Status::Ok(); }
};

struct ProcessResult {
  // The exit status, or 128 + the signal number when a signal ended it.
  int exit_code = -1;
  std::string out;  // captured stdout (empty with output_file)
  std::string err;  // captured stderr (empty with output_file)
  // The last line of stderr (of stdout when stderr is empty), else "exit code N": for messages.
  std::string Describe() const;
};

// Runs argv[0] (looked up in PATH when it has no '/') with argv and waits for
// it to end. Errors: InvalidArgument for an empty argv; NotFound naming the
// program when it cannot be found or executed; IoError naming the output file
// or the failed system call. A program that runs and fails is not an error:
// its exit code is in the result.
Result<ProcessResult> RunProcess(const std::vector<std::string>& argv,
                                 const ProcessOptions& options = {});

// `text` as one word for a POSIX shell: single-quoted, with each ' written '\''.
std::string ShellQuote(const std::string& text);

// The absolute path of the running executable (/proc/self/exe); IoError when
// it cannot be read.
Result<std::string> SelfExecutable();

// The start time of process `pid` in clock ticks since boot (field 22 of
// /proc/<pid>/stat), or 0 when there is no such process. With the pid it
// names one process even after the pid is reused.
uint64_t ProcessStartTicks(pid_t pid);
// True when process `pid` runs (a zombie does not) and started at `start_ticks`.
bool ProcessRuns(pid_t pid, uint64_t start_ticks);

}  // namespace hairrig
