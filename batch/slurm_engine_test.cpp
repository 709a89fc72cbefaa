// The Slurm engine without a cluster: the parsers of sbatch, squeue and
// scontrol output, the job script (run by bash), sbatch's arguments, and
// Submit and View against stand-in commands (bash scripts) that record how
// they were called. tests/batch_slurm_test.cpp runs it on a real cluster.
#include "batch/slurm_engine.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "batch/batch_test_util.h"
#include "batch/process.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string WriteScript(const std::string& path, const std::string& body) {
  std::ofstream(path) << "#!/bin/bash\n" << body;
  fs::permissions(path, fs::perms::owner_all);
  return path;
}

std::string FreshDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/slurm_engine_test/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(SlurmOutput, SbatchJobIds) {
  EXPECT_EQ(*ParseSbatchJobId("1041\n"), "1041");
  EXPECT_EQ(*ParseSbatchJobId("1041;hairrigtest\n"), "1041");
  const Result<std::string> bad = ParseSbatchJobId("sbatch: error: invalid partition\n");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("invalid partition"), std::string::npos);
}

TEST(SlurmOutput, SqueueAndScontrolArrayStates) {
  const SlurmArrayStates queued = ParseSqueueArrayStates(
      "7|0|RUNNING|None\n7|1|PENDING|Dependency\n9|N/A|PENDING|Priority\ngarbage\n");
  ASSERT_EQ(queued.size(), 2u);
  EXPECT_EQ(queued.at({"7", 0}).state, "RUNNING");
  EXPECT_EQ(queued.at({"7", 1}).reason, "Dependency");

  const SlurmArrayStates shown = ParseScontrolArrayStates(
      "JobId=12 ArrayJobId=8 ArrayTaskId=1 ArrayTaskThrottle=2 JobName=hairrig-fit "
      "JobState=CANCELLED "
      "Reason=DependencyNeverSatisfied Dependency=aftercorr:7_*(failed)\n"
      "JobId=8 ArrayJobId=8 ArrayTaskId=2-5%2 JobState=PENDING Reason=Dependency\n");
  ASSERT_EQ(shown.size(), 1u);
  EXPECT_EQ(shown.at({"8", 1}).state, "CANCELLED");
  EXPECT_EQ(shown.at({"8", 1}).reason, "DependencyNeverSatisfied");

  EXPECT_EQ(PhaseOfSlurmState("PENDING"), JobPhase::kQueued);
  EXPECT_EQ(PhaseOfSlurmState("RUNNING"), JobPhase::kRunning);
  EXPECT_EQ(PhaseOfSlurmState("COMPLETING"), JobPhase::kRunning);
  for (const char* ended :
       {"COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "OUT_OF_MEMORY", "NODE_FAIL"}) {
    EXPECT_EQ(PhaseOfSlurmState(ended), JobPhase::kEnded) << ended;
  }
}

struct PlanFixture {
  SubmitPlan plan;
  Submission submission;
};

PlanFixture TwoCaptures(const std::string& batch_dir, const std::string& exe) {
  PlanFixture f;
  f.plan.batch_dir = batch_dir;
  f.plan.hairrig_exe = exe;
  f.plan.capture_dirs = {"/archive/cap 1", "/archive/it's $HOME `2`"};
  f.plan.settings.reconstruct.threads = 3;
  f.submission.run_id = "r1-test";
  f.submission.engine = EngineKind::kSlurm;
  f.submission.stages = {Stage::kCalibrate, Stage::kReconstruct, Stage::kFit};
  f.submission.captures = {0, 1};
  f.submission.max_parallel = 2;
  f.submission.partition = "short";
  f.submission.time_limit = {{"*", "10:00"}, {"reconstruct", "2:00:00"}};
  f.submission.mem = {{"reconstruct", "16G"}};
  return f;
}

// Bash runs the job script as Slurm would, with the stand-in for hairrig printing its arguments.
TEST(SlurmJobScript, EachElementRunsTheStageOnItsCaptureVerbatim) {
  const std::string dir = FreshDir("script");
  const std::string echo_args = WriteScript(dir + "/hairrig with space", "printf '<%s>' \"$@\"\n");
  const PlanFixture f = TwoCaptures(dir, echo_args);
  const std::string script = dir + "/fit.sbatch";
  std::ofstream(script) << SlurmJobScript(f.plan, f.submission, Stage::kFit);
  ::setenv("SLURM_ARRAY_TASK_ID", "1", 1);
  const Result<ProcessResult> run = RunProcess({"bash", script});
  ::unsetenv("SLURM_ARRAY_TASK_ID");
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  ASSERT_EQ(run->exit_code, 0) << run->err;
  EXPECT_EQ(run->out, "<stage><fit><--capture><" + f.plan.capture_dirs[1] + "><--options><" +
                          f.submission.OptionsFile(dir) + "><--run-id><r1-test>");
}

TEST(SlurmJobScript, SbatchArgumentsChainTheArraysElementByElement) {
  const PlanFixture f = TwoCaptures("/batch", "/bin/hairrig");
  const std::vector<std::string> first =
      SbatchArguments(f.plan, f.submission, Stage::kCalibrate, "/b/c.sbatch", "");
  const std::vector<std::string> expected_first{
      "--parsable",
      "--array=0-1%2",
      "--job-name=hairrig-calibrate",
      "--output=/batch/runs/r1-test/logs/calibrate_%a.log",
      "--chdir=/batch/runs/r1-test",
      "--cpus-per-task=2",
      "--partition=short",
      "--time=10:00",
      "/b/c.sbatch"};
  EXPECT_EQ(first, expected_first);
  const std::vector<std::string> second =
      SbatchArguments(f.plan, f.submission, Stage::kReconstruct, "/b/r.sbatch", "1041");
  auto has = [&](const std::string& arg) {
    return std::find(second.begin(), second.end(), arg) != second.end();
  };
  EXPECT_TRUE(has("--dependency=aftercorr:1041"));
  EXPECT_TRUE(has("--kill-on-invalid-dep=yes"));
  EXPECT_TRUE(has("--cpus-per-task=3"));
  EXPECT_TRUE(has("--time=2:00:00"));
  EXPECT_TRUE(has("--mem=16G"));
  EXPECT_EQ(second.back(), "/b/r.sbatch");
}

// Stand-ins for sbatch, squeue, scontrol and scancel that log their calls in `dir`.
SlurmCommands FakeSlurm(const std::string& dir) {
  SlurmCommands c;
  c.sbatch = WriteScript(dir + "/sbatch", "echo \"$*\" >> '" + dir +
                                              "/sbatch.calls'\n"
                                              "n=$(wc -l < '" +
                                              dir +
                                              "/sbatch.calls')\n"
                                              "if [ -f '" +
                                              dir +
                                              "/fail_at_'$n ]; then\n"
                                              "  echo 'sbatch: error: Batch job submission failed: "
                                              "Invalid partition name specified' >&2\n"
                                              "  exit 1\n"
                                              "fi\n"
                                              "echo \"$((100 + n));hairrigtest\"\n");
  c.scancel = WriteScript(dir + "/scancel", "echo \"$*\" >> '" + dir + "/scancel.calls'\n");
  c.squeue = WriteScript(dir + "/squeue",
                         "echo \"$*\" >> '" + dir +
                             "/squeue.calls'\n"
                             "echo '101|0|RUNNING|None'\necho '102|0|PENDING|Dependency'\n");
  c.scontrol = WriteScript(
      dir + "/scontrol",
      "echo \"$*\" >> '" + dir +
          "/scontrol.calls'\n"
          "if [ \"$4\" = 101 ]; then\n"
          "  echo 'JobId=105 ArrayJobId=101 ArrayTaskId=1 JobState=FAILED Reason=NonZeroExitCode'\n"
          "else\n"
          "  echo 'slurm_load_jobs error: Invalid job id specified' >&2; exit 1\n"
          "fi\n");
  return c;
}

TEST(SlurmEngine, SubmitsOneArrayPerStageChainedToThePrevious) {
  const std::string dir = FreshDir("submit");
  PlanFixture f = TwoCaptures(dir + "/batch", "/bin/hairrig");
  SlurmEngine engine(FakeSlurm(dir));
  int recorded = 0;
  ASSERT_TRUE(engine
                  .Submit(f.plan, &f.submission,
                          [&] {
                            ++recorded;
                            return Status::Ok();
                          })
                  .ok());
  EXPECT_EQ(recorded, 1);
  const std::map<std::string, std::string> ids{
      {"calibrate", "101"}, {"reconstruct", "102"}, {"fit", "103"}};
  EXPECT_EQ(f.submission.job_ids, ids);
  const std::string calls = ReadText(dir + "/sbatch.calls");
  EXPECT_NE(calls.find("--dependency=aftercorr:101 --kill-on-invalid-dep=yes"), std::string::npos)
      << calls;
  EXPECT_NE(calls.find("--dependency=aftercorr:102 --kill-on-invalid-dep=yes"), std::string::npos)
      << calls;
  EXPECT_EQ(calls.find("aftercorr:103"), std::string::npos) << calls;
  EXPECT_TRUE(fs::exists(f.submission.RunDir(f.plan.batch_dir) + "/reconstruct.sbatch"));
  EXPECT_TRUE(fs::is_directory(f.submission.RunDir(f.plan.batch_dir) + "/logs"));
}

TEST(SlurmEngine, AFailedSbatchCancelsTheArraysAlreadySubmitted) {
  const std::string dir = FreshDir("submit_fails");
  std::ofstream(dir + "/fail_at_3").put('\n');
  PlanFixture f = TwoCaptures(dir + "/batch", "/bin/hairrig");
  SlurmEngine engine(FakeSlurm(dir));
  int recorded = 0;
  const Status s = engine.Submit(f.plan, &f.submission, [&] {
    ++recorded;
    return Status::Ok();
  });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("Invalid partition name"), std::string::npos) << s.ToString();
  EXPECT_EQ(recorded, 0);
  EXPECT_EQ(ReadText(dir + "/scancel.calls"), "101 102\n");
}

TEST(SlurmEngine, ViewsComeFromSqueueThenScontrol) {
  const std::string dir = FreshDir("view");
  PlanFixture f = TwoCaptures(dir + "/batch", "/bin/hairrig");
  f.submission.stages = {Stage::kCalibrate, Stage::kReconstruct};
  f.submission.job_ids = {{"calibrate", "101"}, {"reconstruct", "102"}};
  SlurmEngine engine(FakeSlurm(dir));
  const Result<JobViews> views = engine.View(f.submission);
  ASSERT_TRUE(views.ok()) << views.status().ToString();
  EXPECT_EQ(views->Get(Stage::kCalibrate, 0).phase, JobPhase::kRunning);
  EXPECT_EQ(views->Get(Stage::kReconstruct, 0).phase, JobPhase::kQueued);
  EXPECT_NE(views->Get(Stage::kReconstruct, 0).detail.find("Dependency"), std::string::npos);
  const JobView failed = views->Get(Stage::kCalibrate, 1);
  EXPECT_EQ(failed.phase, JobPhase::kEnded);
  EXPECT_NE(failed.detail.find("FAILED (NonZeroExitCode)"), std::string::npos) << failed.detail;
  EXPECT_EQ(views->Get(Stage::kReconstruct, 1).phase, JobPhase::kEnded);
  EXPECT_NE(ReadText(dir + "/squeue.calls").find("--format=%F|%K|%T|%r"), std::string::npos);
}

TEST(SlurmEngine, MissingCommandsAreNamed) {
  SlurmCommands missing;
  missing.squeue = "/nonexistent/squeue";
  SlurmEngine engine(missing);
  Submission s;
  s.job_ids = {{"fit", "1"}};
  s.captures = {0};
  const Result<JobViews> views = engine.View(s);
  ASSERT_FALSE(views.ok());
  EXPECT_NE(views.status().message().find("/nonexistent/squeue"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
