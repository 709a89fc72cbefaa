// The local engine: a pool of at most `max_parallel` captures processed at
// once on this machine (the default 2 suits a 2-core machine), each capture's
// stages in order as `hairrig stage` child processes; a stage succeeds when it
// exits 0 and its result.json of this submission says ok; after a stage fails
// the capture's later stages do not run (blocked). Submit runs the submission
// to its end in the calling process and records it twice: when it starts
// (the runner's host, pid and start time, so `status` and `wait` from another
// shell see it running) and when it ends.
#pragma once

#include "batch/engine.h"

namespace hairrig {

class LocalEngine : public BatchEngine {
 public:
  Status Submit(const SubmitPlan& plan, Submission* submission,
                const std::function<Status()>& record) override;
  // Queued while the runner runs (a stage that started shows as running by
  // its result.json); ended once it is gone.
  Result<JobViews> View(const Submission& submission) override;
};

}  // namespace hairrig
