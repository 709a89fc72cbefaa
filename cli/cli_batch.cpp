// `hairrig batch <submit|status|wait|report|resubmit> --batch DIR`: the
// pipeline's stages over an archive of captures, on this machine or on a
// Slurm cluster (batch/batch.h).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>
#include <memory>

#include "batch/batch.h"
#include "batch/process.h"
#include "cli/cli.h"

namespace hairrig {
namespace {

struct SubmitArgs {
  std::string batch_dir;
  std::string captures;
  std::string engine = "local";
  std::vector<std::string> stages;
  std::string stage_options;
  std::string partition;
  int max_parallel = 2;
  std::vector<std::string> time_limit, mem;
  bool failed = false;
};

struct WaitArgs {
  std::string batch_dir;
  double timeout_s = 0;
  double poll_s = 2;
};

// The submit options given on the command line; the rest come from the batch's latest submission.
Result<SubmitOptions> ToSubmitOptions(const SubmitArgs& a, bool engine_given,
                                      bool max_parallel_given, bool partition_given) {
  SubmitOptions o;
  o.batch_dir = a.batch_dir;
  o.captures = a.captures;
  if (engine_given) {
    HR_ASSIGN_OR_RETURN(o.engine, ParseEngine(a.engine));
  }
  if (!a.stages.empty()) {
    HR_ASSIGN_OR_RETURN(o.stages, ParseStageList(a.stages));
  }
  o.stage_options = a.stage_options;
  if (max_parallel_given) o.max_parallel = a.max_parallel;
  if (partition_given) o.partition = a.partition;
  o.time_limit = a.time_limit;
  o.mem = a.mem;
  HR_ASSIGN_OR_RETURN(o.hairrig_exe, SelfExecutable());
  return o;
}

int FailureExitCode(const nlohmann::json& report) {
  const nlohmann::json& counts = report["counts"];
  return counts["failed"].get<int>() + counts["blocked"].get<int>() > 0 ? 3 : 0;
}

void PrintSubmit(const nlohmann::json& j) {
  if (j["run_id"].get<std::string>().empty()) {
    std::printf("batch %s: nothing to resubmit\n", j["batch"].get<std::string>().c_str());
    return;
  }
  std::printf("batch %s: submission %s, %zu captures, engine %s\n",
              j["batch"].get<std::string>().c_str(), j["run_id"].get<std::string>().c_str(),
              j["captures"].size(), j["engine"].get<std::string>().c_str());
  for (const auto& [stage, id] : j["job_ids"].items()) {
    std::printf("  %s: Slurm job array %s\n", stage.c_str(), id.get<std::string>().c_str());
  }
  std::printf("%s\n", j["report"]["brief"].get<std::string>().c_str());
}

void PrintStatus(const nlohmann::json& report) {
  std::printf("batch %s\n", report["batch"].get<std::string>().c_str());
  for (const auto& stage : report["stages"]) {
    std::map<std::string, int> counts;
    for (const auto& capture : report["captures"])
      ++counts[capture["stages"][stage.get<std::string>()]["state"]];
    std::string line;
    for (const auto& [state, n] : counts)
      line += (line.empty() ? "" : ", ") + std::to_string(n) + " " + state;
    std::printf("  %-12s %s\n", stage.get<std::string>().c_str(), line.c_str());
  }
  std::printf("%s\n", report["brief"].get<std::string>().c_str());
}

void AddBatchFolderOption(CLI::App* cmd, std::string* batch_dir) {
  cmd->add_option("--batch", *batch_dir,
                  "the batch folder (its state: captures, stages, engine, job ids)")
      ->required();
}

void AddSubmitOptions(CLI::App* cmd, SubmitArgs* a) {
  cmd->add_option("--engine", a->engine, "local (a process pool on this machine) or slurm")
      ->check(CLI::IsMember({"local", "slurm"}));
  cmd->add_option("--stages", a->stages,
                  "stages to run, in pipeline order (default: all; e.g. fit,simulate)");
  cmd->add_option("--stage-options", a->stage_options,
                  "stage options, a JSON file (batch/stages.h)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--partition", a->partition, "Slurm partition");
  cmd->add_option("--max-parallel", a->max_parallel,
                  "captures processed at once (Slurm: per stage's array; 0: no limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--time", a->time_limit, "Slurm time limit per job: T, or STAGE=T (repeat)");
  cmd->add_option(
      "--mem", a->mem,
      "Slurm memory per job: M, or STAGE=M (repeat), e.g. --mem 4G --mem reconstruct=16G");
}

void AddSubmit(CLI::App& batch, CommonOptions& common, Dispatch& dispatch, bool resubmit) {
  auto args = std::make_shared<SubmitArgs>();
  CLI::App* cmd = resubmit
                      ? batch.add_subcommand(
                            "resubmit", "submit again every capture with a failed or blocked stage")
                      : batch.add_subcommand(
                            "submit",
                            "run the stages over the captures (local: to the end; slurm: queues "
                            "one job array per stage)");
  AddBatchFolderOption(cmd, &args->batch_dir);
  if (resubmit) {
    cmd->add_flag("--failed", args->failed,
                  "the captures with a failed or blocked stage (required)")
        ->required();
  } else {
    cmd->add_option("--captures", args->captures,
                    "a file listing capture folders (one a line) or a folder of captures; needed "
                    "to start a batch")
        ->check(CLI::ExistingPath);
  }
  AddSubmitOptions(cmd, args.get());
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([args, cmd, resubmit, &dispatch] {
    const bool engine_given = cmd->count("--engine") > 0;
    const bool max_parallel_given = cmd->count("--max-parallel") > 0;
    const bool partition_given = cmd->count("--partition") > 0;
    dispatch.action = [args, resubmit, engine_given, max_parallel_given,
                       partition_given]() -> Result<nlohmann::json> {
      HR_ASSIGN_OR_RETURN(
          const SubmitOptions options,
          ToSubmitOptions(*args, engine_given, max_parallel_given, partition_given));
      HR_ASSIGN_OR_RETURN(const SubmitSummary summary,
                          resubmit ? ResubmitFailed(options) : SubmitBatch(options));
      return summary.ToJson();
    };
    dispatch.print_human = PrintSubmit;
    dispatch.exit_code = [](const nlohmann::json& j) { return FailureExitCode(j["report"]); };
  });
}

void AddReportCommands(CLI::App& batch, CommonOptions& common, Dispatch& dispatch) {
  auto dir = std::make_shared<std::string>();
  CLI::App* status = batch.add_subcommand(
      "status", "counts per stage: done, skipped, failed, blocked, pending, running");
  CLI::App* report = batch.add_subcommand("report",
                                          "per capture and stage: done, skipped, failed (with the "
                                          "error and log), blocked, pending, running");
  for (CLI::App* cmd : {status, report}) {
    AddBatchFolderOption(cmd, dir.get());
    cmd->add_flag("--json", common.json, "print the report as one JSON object");
  }
  status->callback([dir, &dispatch] {
    dispatch.action = [dir]() -> Result<nlohmann::json> {
      HR_ASSIGN_OR_RETURN(const BatchReport r, ReportBatch(*dir));
      return r.ToJson();
    };
    dispatch.print_human = PrintStatus;
  });
  report->callback([dir, &dispatch] {
    dispatch.action = [dir]() -> Result<nlohmann::json> {
      HR_ASSIGN_OR_RETURN(const BatchReport r, ReportBatch(*dir));
      nlohmann::json j = r.ToJson();
      j["table"] = r.Table();
      return j;
    };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("%s", j["table"].get<std::string>().c_str());
    };
  });

  auto wait_args = std::make_shared<WaitArgs>();
  CLI::App* wait = batch.add_subcommand(
      "wait", "wait until no stage is pending or running, then print the report");
  AddBatchFolderOption(wait, &wait_args->batch_dir);
  wait->add_option("--timeout", wait_args->timeout_s, "give up after this many seconds (0: never)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  wait->add_option("--poll", wait_args->poll_s, "seconds between looks at the jobs")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  wait->add_flag("--json", common.json, "print the report as one JSON object");
  wait->callback([wait_args, &dispatch] {
    dispatch.action = [wait_args]() -> Result<nlohmann::json> {
      HR_ASSIGN_OR_RETURN(
          const BatchReport r,
          WaitForBatch(wait_args->batch_dir, wait_args->timeout_s, wait_args->poll_s));
      nlohmann::json j = r.ToJson();
      j["table"] = r.Table();
      return j;
    };
    dispatch.print_human = [](const nlohmann::json& j) {
      std::printf("%s", j["table"].get<std::string>().c_str());
    };
    dispatch.exit_code = FailureExitCode;
  });
}

}  // namespace

void AddBatchCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  CLI::App* batch = app.add_subcommand(
      "batch", "the pipeline's stages over an archive of captures, locally or on a Slurm cluster");
  batch->require_subcommand(1);
  AddSubmit(*batch, common, dispatch, false);
  AddReportCommands(*batch, common, dispatch);
  AddSubmit(*batch, common, dispatch, true);
}

}  // namespace hairrig
