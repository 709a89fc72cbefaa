#include "batch/engine.h"

#include "batch/local_engine.h"
#include "batch/slurm_engine.h"

namespace hairrig {

std::vector<std::string> StageJobArguments(const SubmitPlan& plan, const Submission& submission,
                                           Stage stage, const std::string& capture_dir) {
  return {"stage",     StageName(stage), "--capture",
          capture_dir, "--options",      submission.OptionsFile(plan.batch_dir),
          "--run-id",  submission.run_id};
}

std::unique_ptr<BatchEngine> MakeBatchEngine(EngineKind kind) {
  if (kind == EngineKind::kSlurm) return std::make_unique<SlurmEngine>();
  return std::make_unique<LocalEngine>();
}

}  // namespace hairrig
