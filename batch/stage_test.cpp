// The stage contract on the fit stage of a small capture folder (strands
// only): the result file, skipping when the inputs are unchanged, reruns when
// an input or an option changes, hashes that do not depend on the folder's
// place, the fault hook, missing inputs; the capture stages' input files
// (only those inside the capture folder); and the stage options file.
#include "batch/stage.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "batch/batch.h"
#include "batch/process.h"
#include "batch/stage_record.h"
#include "core/strand_io.h"
#include "core/version.h"
#include "tests/support/status_testing.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

StrandSet Curls(int count) {
  StrandSet set;
  for (int s = 0; s < count; ++s) {
    std::vector<Eigen::Vector3f> p;
    for (int k = 0; k < 60; ++k) {
      const float a = 0.25f * static_cast<float>(k);
      p.emplace_back(20.0f * static_cast<float>(s % 4) + 5 * std::cos(a),
                     20.0f * static_cast<float>(s / 4) + 5 * std::sin(a),
                     -0.6f * static_cast<float>(k));
    }
    set.AddStrand(p);
  }
  return set;
}

// A folder holding what the fit stage reads.
std::string StrandsCapture(const std::string& name, int strands = 8) {
  const std::string dir = ::testing::TempDir() + "/stage_test/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir + "/reconstruction/strands");
  EXPECT_TRUE(WriteStrands(dir + "/reconstruction/strands/strands.ply", Curls(strands)).ok());
  return dir;
}

StageOptions FitOptionsFor(const std::string& dir, int guides = 2) {
  StageOptions o;
  o.stage = Stage::kFit;
  o.capture_dir = dir;
  o.settings.fit.guides = guides;
  o.settings.fit.threads = 1;
  o.run_id = "r1-test";
  return o;
}

// Sets HAIRRIG_STAGE_FAULT for one scope.
class FaultVariable {
 public:
  explicit FaultVariable(const std::string& value) {
    ::setenv(kStageFaultVariable, value.c_str(), 1);
  }
  ~FaultVariable() { ::unsetenv(kStageFaultVariable); }
};

TEST(Stage, FitWritesItsOutputAndResult) {
  const std::string dir = StrandsCapture("fit_once");
  const Result<StageResult> r = RunStage(FitOptionsFor(dir));
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_FALSE(r->skipped);
  EXPECT_TRUE(fs::exists(dir + "/fit/model.json"));
  EXPECT_EQ(r->result_file, dir + "/fit/result.json");
  const Result<StageRecord> record = ReadStageRecord(dir, Stage::kFit);
  ASSERT_TRUE(record.ok()) << record.status().ToString();
  EXPECT_EQ(record->status, "ok");
  EXPECT_EQ(record->run_id, "r1-test");
  EXPECT_EQ(record->input_hash, r->input_hash);
  EXPECT_EQ(record->input_hash.size(), 64u);
  EXPECT_FALSE(record->hairrig_version.empty());
  const Result<std::string> build = HairrigBuildId();
  ASSERT_TRUE(build.ok()) << build.status().ToString();
  EXPECT_EQ(record->hairrig_build, *build);
  EXPECT_TRUE(record->inputs.contains("reconstruction/strands/strands.ply"));
  EXPECT_EQ(record->summary["guides"], 2);
  EXPECT_FALSE(record->start_utc.empty());
  EXPECT_FALSE(record->end_utc.empty());
}

TEST(Stage, UnchangedInputsSkipAndChangesRerun) {
  const std::string dir = StrandsCapture("fit_skip");
  const Result<StageResult> first = RunStage(FitOptionsFor(dir));
  ASSERT_TRUE(first.ok()) << first.status().ToString();

  StageOptions again = FitOptionsFor(dir);
  again.run_id = "r2-test";
  again.settings.fit.threads = 2;  // threads do not enter the hash
  const Result<StageResult> second = RunStage(again);
  ASSERT_TRUE(second.ok()) << second.status().ToString();
  EXPECT_TRUE(second->skipped);
  EXPECT_EQ(second->input_hash, first->input_hash);
  const Result<StageRecord> skipped = ReadStageRecord(dir, Stage::kFit);
  ASSERT_TRUE(skipped.ok());
  EXPECT_TRUE(skipped->skipped);
  EXPECT_EQ(skipped->run_id, "r2-test");
  EXPECT_FALSE(skipped->checked_utc.empty());

  const Result<StageResult> other_option = RunStage(FitOptionsFor(dir, 3));
  ASSERT_TRUE(other_option.ok()) << other_option.status().ToString();
  EXPECT_FALSE(other_option->skipped);
  EXPECT_NE(other_option->input_hash, first->input_hash);

  ASSERT_TRUE(WriteStrands(dir + "/reconstruction/strands/strands.ply", Curls(9)).ok());
  const Result<StageResult> other_input = RunStage(FitOptionsFor(dir, 3));
  ASSERT_TRUE(other_input.ok()) << other_input.status().ToString();
  EXPECT_FALSE(other_input->skipped);
  EXPECT_NE(other_input->input_hash, other_option->input_hash);

  StageOptions forced = FitOptionsFor(dir, 3);
  forced.force = true;
  const Result<StageResult> rerun = RunStage(forced);
  ASSERT_TRUE(rerun.ok());
  EXPECT_FALSE(rerun->skipped);
}

TEST(Stage, TheHashDoesNotDependOnWhereTheCaptureLies) {
  const Result<StageResult> a = RunStage(FitOptionsFor(StrandsCapture("here")));
  const Result<StageResult> b = RunStage(FitOptionsFor(StrandsCapture("elsewhere")));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->input_hash, b->input_hash);
}

TEST(Stage, TheFaultHookFailsOneStageOfOneCapture) {
  const std::string dir = StrandsCapture("cap_fault");
  {
    const FaultVariable fault("reconstruct:cap_fault,fit:cap_fault");
    const Result<StageResult> r = RunStage(FitOptionsFor(dir));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("injected fault"), std::string::npos)
        << r.status().ToString();
    EXPECT_NE(r.status().message().find("fit of " + dir), std::string::npos)
        << r.status().ToString();
    const Result<StageRecord> record = ReadStageRecord(dir, Stage::kFit);
    ASSERT_TRUE(record.ok()) << record.status().ToString();
    EXPECT_EQ(record->status, "failed");
    EXPECT_TRUE(record->injected_fault);
    EXPECT_NE(record->error.find(kStageFaultVariable), std::string::npos);
    EXPECT_FALSE(fs::exists(dir + "/fit/model.json"));
  }
  {
    const FaultVariable other_capture("fit:cap_other");
    EXPECT_TRUE(RunStage(FitOptionsFor(dir)).ok());
  }
  const Result<StageResult> after = RunStage(FitOptionsFor(dir));
  ASSERT_TRUE(after.ok());
  EXPECT_TRUE(after->skipped);
}

TEST(Stage, AMissingInputFailsNamingItAndTheStageThatWritesIt) {
  const std::string dir = ::testing::TempDir() + "/stage_test/empty";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Result<StageResult> r = RunStage(FitOptionsFor(dir));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("reconstruction/strands/strands.ply"), std::string::npos);
  EXPECT_NE(r.status().message().find("run the reconstruct stage first"), std::string::npos);
  const Result<StageRecord> record = ReadStageRecord(dir, Stage::kFit);
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->status, "failed");

  StageOptions calibrate;
  calibrate.capture_dir = dir;
  const Result<StageResult> c = RunStage(calibrate);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.status().message().find("rig.yaml is missing"), std::string::npos)
      << c.status().ToString();

  StageOptions nowhere = FitOptionsFor(dir + "/absent");
  EXPECT_EQ(RunStage(nowhere).status().code(), StatusCode::kNotFound);
}

// A capture stage's inputs are the files inside the capture folder: a frame
// that is a symlink leading outside is no input (not in the input hash, so a
// file elsewhere cannot change it), and a frames/ folder leading outside
// refuses the stage.
TEST(Stage, FramesLeadingOutsideTheCaptureAreNoInputs) {
  const std::string dir = ::testing::TempDir() + "/stage_test/frames_outside";
  const std::string outside = dir + "_elsewhere";
  fs::remove_all(dir);
  fs::remove_all(outside);
  fs::create_directories(dir + "/frames");
  fs::create_directories(outside);
  std::ofstream(dir + "/rig.yaml") << "name: frames outside\n";
  std::ofstream(dir + "/manifest.json") << "{}\n";
  std::ofstream(dir + "/frames/000_CAM.png") << "the frame of view 0";
  std::ofstream(outside + "/other.png") << "a file of another folder";
  fs::create_symlink(outside + "/other.png", dir + "/frames/001_CAM.png");
  const auto files = StageInputFiles(Stage::kCalibrate, dir, StageSettings{});
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  EXPECT_EQ(files->count("frames/000_CAM.png"), 1u);
  EXPECT_EQ(files->count("frames/001_CAM.png"), 0u);

  fs::rename(dir + "/frames", outside + "/frames");
  fs::create_directory_symlink(outside + "/frames", dir + "/frames");
  const auto refused = StageInputFiles(Stage::kCalibrate, dir, StageSettings{});
  EXPECT_EQ(refused.status().code(), StatusCode::kFailedPrecondition)
      << refused.status().ToString();
  EXPECT_NE(refused.status().message().find(dir + "/frames"), std::string::npos)
      << refused.status().ToString();
  EXPECT_NE(refused.status().message().find("outside"), std::string::npos)
      << refused.status().ToString();
}

TEST(Stage, CaptureNameIsTheFolderName) {
  EXPECT_EQ(CaptureName("/archive/cap1"), "cap1");
  EXPECT_EQ(CaptureName("/archive/cap1/"), "cap1");
  EXPECT_EQ(CaptureName("/archive/./cap1/."), "cap1");
}

TEST(StageSettings, DefaultsRoundTripAndRelativeFilesResolve) {
  const StageSettings defaults;
  const Result<StageSettings> back = StageSettingsFromJson(defaults.ToJson(), "defaults", "/base");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->ToJson(), defaults.ToJson());
  EXPECT_EQ(defaults.fit.guides, 300);  // scripts/demo's
  EXPECT_EQ(defaults.simulate.scenario, "head-shake");

  const nlohmann::json j = {
      {"calibrate", {{"intrinsics", {"cam.json"}}, {"threads", 1}}},
      {"reconstruct", {{"strands", 200}, {"hull_voxel_mm", 4.0}, {"head", "fit"}}},
      {"simulate", {{"head", "heads/h.yaml"}, {"seconds", 0.2}}}};
  const Result<StageSettings> s = StageSettingsFromJson(j, "opts.json", "/base");
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->calibrate.intrinsics, std::vector<std::string>{"/base/cam.json"});
  EXPECT_EQ(s->reconstruct.strands, 200);
  EXPECT_EQ(s->reconstruct.head, "fit") << "a fitted head is no file to resolve";
  EXPECT_EQ(s->simulate.head, "/base/heads/h.yaml");
  EXPECT_EQ(s->Threads(Stage::kCalibrate), 1);
  EXPECT_EQ(s->Threads(Stage::kSimulate), 1);
}

TEST(StageSettings, MistakesNameTheFileAndField) {
  auto message = [](const nlohmann::json& j) {
    return StageSettingsFromJson(j, "opts.json", "").status().ToString();
  };
  EXPECT_NE(message({{"fitt", nlohmann::json::object()}}).find("fitt"), std::string::npos);
  EXPECT_NE(message({{"fit", {{"guidez", 3}}}}).find("guidez"), std::string::npos);
  EXPECT_NE(message({{"fit", {{"guides", 0}}}}).find("fit.guides"), std::string::npos);
  EXPECT_NE(message({{"calibrate", {{"mode", "wobbly"}}}}).find("wobbly"), std::string::npos);
  EXPECT_NE(message({{"simulate", {{"scenario", "storm"}}}}).find("storm"), std::string::npos);
  EXPECT_NE(message({{"reconstruct", 3}}).find("reconstruct"), std::string::npos);
  EXPECT_NE(message(nlohmann::json::array()).find("opts.json"), std::string::npos);
  EXPECT_EQ(LoadStageSettings("/nonexistent/opts.json").status().code(), StatusCode::kNotFound);
}

TEST(StageNames, ListsComeBackInPipelineOrder) {
  const Result<std::vector<Stage>> stages =
      ParseStageList({"simulate,calibrate", "fit", "calibrate"});
  ASSERT_TRUE(stages.ok());
  EXPECT_EQ(*stages, (std::vector<Stage>{Stage::kCalibrate, Stage::kFit, Stage::kSimulate}));
  EXPECT_EQ(ParseStageList({})->size(), 4u);
  EXPECT_FALSE(ParseStageList({"fit,sing"}).ok());
  EXPECT_STREQ(StageFolder(Stage::kReconstruct), "reconstruction");
}

// The batch's options refuse a bad value with InvalidArgument naming the
// field, before any folder is made or any stage record written.
TEST(BatchOptions, CheckNamesTheBadField) {
  EXPECT_TRUE(ProcessOptions{}.Check().ok());
  {
    SubmitOptions o;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "batch_dir"));
    o.batch_dir = "batch";
    o.hairrig_exe = "/usr/bin/hairrig";
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.max_parallel = -1;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "--max-parallel"));
    o.max_parallel.reset();
    o.hairrig_exe.clear();
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "hairrig binary"));
  }
  {
    StageOptions o;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "capture_dir"));
    o = FitOptionsFor("capture");
    EXPECT_TRUE(o.Check().ok()) << o.Check().ToString();
    o.settings.fit.threads = 0;
    EXPECT_TRUE(IsInvalidNaming(o.Check(), "fit.threads"));
  }

  const std::string dir = ::testing::TempDir() + "/stage_test/options_batch";
  fs::remove_all(dir);
  SubmitOptions submit;
  submit.batch_dir = dir + "/batch";
  submit.max_parallel = -3;
  submit.hairrig_exe = "/usr/bin/hairrig";
  const Result<SubmitSummary> submitted = SubmitBatch(submit);
  ASSERT_FALSE(submitted.ok());
  EXPECT_NE(submitted.status().message().find("--max-parallel"), std::string::npos);
  EXPECT_FALSE(fs::exists(submit.batch_dir)) << "no batch folder is made for bad options";

  const std::string capture = StrandsCapture("options");
  StageOptions stage = FitOptionsFor(capture);
  stage.settings.fit.threads = 2000;
  const Result<StageResult> r = RunStage(stage);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("fit.threads"), std::string::npos);
  EXPECT_FALSE(ReadStageRecord(capture, Stage::kFit).ok()) << "no result.json for bad options";
}

}  // namespace
}  // namespace hairrig
