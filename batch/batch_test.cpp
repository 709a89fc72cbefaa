// `hairrig batch` on the local engine with a stand-in for the hairrig binary
// (a bash script that records the stages it is asked for and writes their
// result files), so the batch's own logic is tested in seconds: finding the
// captures, the batch folder's state, stages in order with later ones
// blocked after a failure, the report, resubmitting the failed captures.
// tests/batch_slurm_test.cpp runs the real stages, locally and on Slurm.
#include "batch/batch.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "batch/batch_test_util.h"
#include "batch/stage_record.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// Normalised, as FindCaptures gives the captures under it.
std::string FreshDir(const std::string& name) {
  const std::string dir =
      (fs::path(::testing::TempDir()) / "batch_test" / name).lexically_normal().string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void MakeCaptureFolder(const std::string& dir) {
  fs::create_directories(dir);
  std::ofstream(dir + "/journal.jsonl") << "{}\n";
  std::ofstream(dir + "/capture.json") << "{}\n";
}

// Stands in for `hairrig stage NAME --capture DIR --options F --run-id ID`:
// appends NAME to DIR/order.txt; fails (result failed) when DIR/fail_NAME
// exists; exits 0 without a result when DIR/silent_NAME exists.
std::string FakeHairrig(const std::string& dir) {
  const std::string path = dir + "/fake_hairrig";
  std::ofstream(path) << R"(#!/bin/bash
stage=$2 capture=$4 run=$8
case $stage in
  calibrate) folder=calibration ;;
  reconstruct) folder=reconstruction ;;
  simulate) folder=simulation ;;
  *) folder=$stage ;;
esac
echo "$stage" >> "$capture/order.txt"
[ -f "$capture/silent_$stage" ] && exit 0
status=ok error=""
if [ -f "$capture/fail_$stage" ]; then status=failed error="made to fail"; fi
mkdir -p "$capture/$folder"
printf '{"format": "hairrig-stage-result", "version": 1, "stage": "%s", "status": "%s", ' \
  "$stage" "$status" > "$capture/$folder/result.json"
printf '"run_id": "%s", "error": "%s", "input_hash": "h-%s"}\n' \
  "$run" "$error" "$stage" >> "$capture/$folder/result.json"
[ "$status" = ok ]
)";
  fs::permissions(path, fs::perms::owner_all);
  return path;
}

struct Archive {
  std::string root;
  std::vector<std::string> captures;  // sorted, as FindCaptures gives them
  std::string exe;
};

Archive ThreeCaptures(const std::string& name) {
  Archive a;
  a.root = FreshDir(name);
  for (const char* capture : {"a/cap0", "b/cap1", "b/cap2"}) {
    a.captures.push_back(a.root + "/archive/" + capture);
    MakeCaptureFolder(a.captures.back());
  }
  a.exe = FakeHairrig(a.root);
  return a;
}

SubmitOptions LocalSubmit(const Archive& a) {
  SubmitOptions o;
  o.batch_dir = a.root + "/batch";
  o.captures = a.root + "/archive";
  o.engine = EngineKind::kLocal;
  o.max_parallel = 2;
  o.hairrig_exe = a.exe;
  return o;
}

const StageCell& Cell(const BatchReport& r, size_t capture, Stage stage) {
  const size_t k = std::find(r.stages.begin(), r.stages.end(), stage) - r.stages.begin();
  return r.captures.at(capture).stages.at(k);
}

TEST(FindCaptures, FoldersAreSearchedAndListsRead) {
  const Archive a = ThreeCaptures("find");
  MakeCaptureFolder(a.captures[0] + "/nested");  // inside a capture: not searched
  fs::create_directories(a.root + "/archive/empty");
  const Result<std::vector<std::string>> found = FindCaptures(a.root + "/archive");
  ASSERT_TRUE(found.ok()) << found.status().ToString();
  EXPECT_EQ(*found, a.captures);

  std::ofstream(a.root + "/list.txt") << "# the archive\narchive/b/cap2\n\n"
                                      << a.captures[0] << "/\n";
  const Result<std::vector<std::string>> listed = FindCaptures(a.root + "/list.txt");
  ASSERT_TRUE(listed.ok()) << listed.status().ToString();
  EXPECT_EQ(*listed, (std::vector<std::string>{a.captures[2], a.captures[0]}));

  std::ofstream(a.root + "/twice.txt") << "archive/b/cap2\narchive/b/../b/cap2\n";
  EXPECT_NE(FindCaptures(a.root + "/twice.txt").status().message().find("listed twice"),
            std::string::npos);
  std::ofstream(a.root + "/wrong.txt") << "archive/empty\n";
  const Status wrong = FindCaptures(a.root + "/wrong.txt").status();
  EXPECT_NE(wrong.message().find("wrong.txt:1"), std::string::npos) << wrong.ToString();
  EXPECT_NE(wrong.message().find("not a capture folder"), std::string::npos) << wrong.ToString();
  EXPECT_EQ(FindCaptures(a.root + "/archive/empty").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(FindCaptures(a.root + "/none").status().code(), StatusCode::kNotFound);
}

TEST(BatchState, RoundTrips) {
  const std::string dir = FreshDir("state");
  BatchState state;
  state.created_utc = "2026-11-24T10:00:00.000Z";
  state.captures = {"/a/cap0", "/a/cap1"};
  Submission s;
  s.run_id = "r1-x";
  s.engine = EngineKind::kSlurm;
  s.stages = {Stage::kReconstruct, Stage::kFit};
  s.captures = {1};
  s.max_parallel = 4;
  s.partition = "short";
  s.time_limit = {{"*", "1:00:00"}};
  s.mem = {{"reconstruct", "16G"}};
  s.job_ids = {{"reconstruct", "7"}, {"fit", "8"}};
  state.submissions.push_back(s);
  ASSERT_TRUE(WriteBatchState(dir, state).ok());
  const Result<BatchState> back = ReadBatchState(dir);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->submissions.size(), 1u);
  const Submission& b = back->submissions[0];
  EXPECT_EQ(back->captures, state.captures);
  EXPECT_EQ(b.engine, EngineKind::kSlurm);
  EXPECT_EQ(b.stages, s.stages);
  EXPECT_EQ(b.captures, s.captures);
  EXPECT_EQ(b.job_ids, s.job_ids);
  EXPECT_EQ(Submission::ForStage(b.time_limit, Stage::kFit), "1:00:00");
  EXPECT_EQ(Submission::ForStage(b.mem, Stage::kReconstruct), "16G");
  EXPECT_EQ(Submission::ForStage(b.mem, Stage::kFit), "");
  EXPECT_EQ(back->LatestFor(1, Stage::kFit), &back->submissions[0]);
  EXPECT_EQ(back->LatestFor(0, Stage::kFit), nullptr);
  EXPECT_EQ(ReadBatchState(dir + "/nothing").status().code(), StatusCode::kNotFound);
}

TEST(LocalBatch, StagesRunInOrderAndAFailureBlocksTheLaterOnes) {
  const Archive a = ThreeCaptures("local");
  std::ofstream(a.captures[1] + "/fail_reconstruct").put('\n');
  std::ofstream(a.captures[2] + "/silent_fit").put('\n');
  const Result<SubmitSummary> submitted = SubmitBatch(LocalSubmit(a));
  ASSERT_TRUE(submitted.ok()) << submitted.status().ToString();
  const BatchReport& r = submitted->report;
  EXPECT_TRUE(r.Finished());
  EXPECT_FALSE(r.AllSucceeded());
  EXPECT_EQ(ReadText(a.captures[0] + "/order.txt"), "calibrate\nreconstruct\nfit\nsimulate\n");
  EXPECT_EQ(ReadText(a.captures[1] + "/order.txt"), "calibrate\nreconstruct\n");
  EXPECT_EQ(ReadText(a.captures[2] + "/order.txt"), "calibrate\nreconstruct\nfit\n");
  for (Stage stage : kAllStages) EXPECT_EQ(Cell(r, 0, stage).state, "done") << StageName(stage);
  EXPECT_EQ(Cell(r, 0, Stage::kFit).input_hash, "h-fit");
  EXPECT_EQ(Cell(r, 1, Stage::kCalibrate).state, "done");
  EXPECT_EQ(Cell(r, 1, Stage::kReconstruct).state, "failed");
  EXPECT_EQ(Cell(r, 1, Stage::kReconstruct).error, "made to fail");
  EXPECT_EQ(Cell(r, 1, Stage::kFit).state, "blocked");
  EXPECT_EQ(Cell(r, 1, Stage::kSimulate).state, "blocked");
  EXPECT_NE(Cell(r, 1, Stage::kFit).error.find("reconstruct"), std::string::npos);
  EXPECT_EQ(Cell(r, 2, Stage::kFit).state, "failed");
  EXPECT_NE(Cell(r, 2, Stage::kFit).error.find("without writing its result"), std::string::npos);
  EXPECT_EQ(Cell(r, 2, Stage::kSimulate).state, "blocked");
  EXPECT_EQ(r.Count("done"), 4 + 1 + 2);
  EXPECT_EQ(r.Count("failed"), 2);
  EXPECT_EQ(r.Count("blocked"), 3);
  EXPECT_TRUE(fs::exists(Cell(r, 1, Stage::kReconstruct).log));
  const std::string table = r.Table();
  EXPECT_NE(table.find("b/cap1 reconstruct: made to fail"), std::string::npos) << table;
  EXPECT_EQ(r.ToJson()["counts"]["blocked"], 3);

  // The failed captures again, faults removed: only they run, every stage.
  fs::remove(a.captures[1] + "/fail_reconstruct");
  fs::remove(a.captures[2] + "/silent_fit");
  SubmitOptions again = LocalSubmit(a);
  again.captures.clear();
  const Result<SubmitSummary> resubmitted = ResubmitFailed(again);
  ASSERT_TRUE(resubmitted.ok()) << resubmitted.status().ToString();
  EXPECT_EQ(resubmitted->captures, (std::vector<std::string>{a.captures[1], a.captures[2]}));
  EXPECT_TRUE(resubmitted->report.AllSucceeded()) << resubmitted->report.Table();
  EXPECT_EQ(ReadText(a.captures[0] + "/order.txt"), "calibrate\nreconstruct\nfit\nsimulate\n");
  EXPECT_NE(Cell(resubmitted->report, 1, Stage::kFit).run_id,
            Cell(resubmitted->report, 0, Stage::kFit).run_id);

  const Result<SubmitSummary> nothing = ResubmitFailed(again);
  ASSERT_TRUE(nothing.ok());
  EXPECT_TRUE(nothing->run_id.empty());
}

TEST(LocalBatch, AStageThatNeverFinishedIsFailedOnceItsRunnerIsGone) {
  const Archive a = ThreeCaptures("never_finished");
  const Result<SubmitSummary> submitted = SubmitBatch(LocalSubmit(a));
  ASSERT_TRUE(submitted.ok()) << submitted.status().ToString();
  StageRecord running;
  running.stage = "simulate";
  running.status = "running";
  running.run_id = submitted->run_id;
  ASSERT_TRUE(WriteStageRecord(a.captures[0], Stage::kSimulate, running).ok());
  const Result<BatchReport> r = ReportBatch(a.root + "/batch");
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(Cell(*r, 0, Stage::kSimulate).state, "failed");
  EXPECT_NE(Cell(*r, 0, Stage::kSimulate).error.find("never finished"), std::string::npos);
  EXPECT_TRUE(WaitForBatch(a.root + "/batch", 5, 0.1).ok());
}

TEST(LocalBatch, OptionsAndStagesCarryOverAndOtherCapturesAreRefused) {
  const Archive a = ThreeCaptures("carry_over");
  std::ofstream(a.root + "/opts.json") << R"({"fit": {"guides": 7}})";
  SubmitOptions first = LocalSubmit(a);
  first.stages = {Stage::kFit, Stage::kSimulate};
  first.stage_options = a.root + "/opts.json";
  ASSERT_TRUE(SubmitBatch(first).ok());
  SubmitOptions second;
  second.batch_dir = first.batch_dir;
  second.hairrig_exe = a.exe;
  const Result<SubmitSummary> again = SubmitBatch(second);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->stages, first.stages);
  EXPECT_EQ(again->engine, EngineKind::kLocal);
  const Result<BatchState> state = ReadBatchState(first.batch_dir);
  ASSERT_TRUE(state.ok());
  const std::string options = ReadText(state->submissions.back().OptionsFile(first.batch_dir));
  EXPECT_NE(options.find("\"guides\": 7"), std::string::npos) << options;
  EXPECT_EQ(again->report.stages, first.stages);

  SubmitOptions other = second;
  other.captures = a.captures[0];
  EXPECT_EQ(SubmitBatch(other).status().code(), StatusCode::kInvalidArgument);
  SubmitOptions fresh = second;
  fresh.batch_dir = a.root + "/fresh";
  EXPECT_NE(SubmitBatch(fresh).status().message().find("--captures"), std::string::npos);
  SubmitOptions bad_time = second;
  bad_time.time_limit = {"fitt=1:00"};
  EXPECT_NE(SubmitBatch(bad_time).status().message().find("fitt"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
