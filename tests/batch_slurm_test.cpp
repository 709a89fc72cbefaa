// `hairrig batch` end to end (docs/design.md section 10), as a lab runs it: three
// small simulated captures (tests/data/batch_rig.yaml at three sets of
// turntable angles) through every stage on a private single-node Slurm
// cluster on 127.0.0.1 that the test starts and stops
// (tests/support/private_slurm.sh holds the recipe), with the reconstruct
// stage of one capture made to fail by the fault hook (HAIRRIG_STAGE_FAULT,
// batch/stage.h): the others complete every stage, the failed one is
// reported failed with its error and its later stages blocked (Slurm cancels
// them: aftercorr), and `resubmit --failed` completes it once the fault is
// off. Then the same batch on the local engine gives the same outputs
// (ExpectSameOutputs).
//
// Skipped (exit 77) where the cluster cannot run: not root, or Slurm and
// munge not installed (scripts/install-deps installs them).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "batch/process.h"
#include "batch/stage.h"
#include "batch/stage_record.h"

namespace {

namespace fs = std::filesystem;
using hairrig::kAllStages;
using hairrig::ProcessResult;
using hairrig::RunProcess;
using hairrig::Stage;
using hairrig::StageName;

constexpr const char* kClusterScript = "tests/support/private_slurm.sh";
constexpr int kCaptures = 3;
constexpr const char* kFaultyCapture = "cap2";

// Cheap stages: one thread each (the calibration's solution and everything
// after it then repeat bit for bit), 200 strands, 20 guides, a fifth of a
// second of dynamics without previews.
constexpr const char* kStageOptions = R"({
  "calibrate": {"threads": 1},
  "reconstruct": {"strands": 200, "threads": 1},
  "fit": {"guides": 20, "threads": 1},
  "simulate": {"seconds": 0.2, "fps": 10, "preview_every": 0}
})";

ProcessResult RunCommand(const std::vector<std::string>& argv) {
  const hairrig::Result<ProcessResult> run = RunProcess(argv);
  EXPECT_TRUE(run.ok()) << run.status().ToString();
  return run.ok() ? *run : ProcessResult{};
}

// `hairrig ARGS --json`: its exit code and the JSON summary it prints last.
struct HairrigRun {
  int exit_code = -1;
  nlohmann::json summary;
  std::string err;
};

HairrigRun Hairrig(std::vector<std::string> args) {
  args.insert(args.begin(), {HAIRRIG_BIN, "--log-level", "warning"});
  args.push_back("--json");
  const ProcessResult run = RunCommand(args);
  HairrigRun r{run.exit_code, nlohmann::json(), run.err};
  const size_t end = run.out.find_last_not_of('\n');
  if (end != std::string::npos) {
    const size_t start = run.out.rfind('\n', end);
    r.summary = nlohmann::json::parse(run.out.substr(start == std::string::npos ? 0 : start + 1),
                                      nullptr, false);
  }
  return r;
}

// tests/data/batch_rig.yaml with its files resolved from the repository and
// the turntable at 8 angles 45 deg apart from `first_deg`.
std::string RigVariant(const std::string& dir, int first_deg) {
  std::ifstream in("tests/data/batch_rig.yaml");
  const fs::path data = fs::absolute("tests/data");
  std::string text, line;
  while (std::getline(in, line)) {
    for (const char* key : {"  scene: ", "  box: ", "head: "}) {
      if (line.rfind(key, 0) == 0) {
        line = key + (data / line.substr(std::string(key).size())).lexically_normal().string();
      }
    }
    if (line == "  stops: 8") {
      line = "  angles_deg: [";
      for (int k = 0; k < 8; ++k) line += (k ? ", " : "") + std::to_string(first_deg + 45 * k);
      line += "]";
    }
    text += line + "\n";
  }
  const std::string path = dir + "/rig_" + std::to_string(first_deg) + ".yaml";
  std::ofstream(path) << text;
  return path;
}

const nlohmann::json& CaptureRow(const nlohmann::json& report, const std::string& name) {
  for (const nlohmann::json& row : report["captures"]) {
    if (fs::path(row["capture"].get<std::string>()).filename() == name) return row;
  }
  static const nlohmann::json kNone = nlohmann::json::object();
  ADD_FAILURE() << "no capture " << name << " in " << report.dump();
  return kNone;
}

std::string StateOf(const nlohmann::json& report, const std::string& capture, Stage stage) {
  return CaptureRow(report, capture)["stages"][StageName(stage)].value("state", "");
}

hairrig::StageRecord Record(const std::string& capture_dir, Stage stage) {
  const hairrig::Result<hairrig::StageRecord> record = hairrig::ReadStageRecord(capture_dir, stage);
  EXPECT_TRUE(record.ok()) << record.status().ToString();
  return record.ok() ? *record : hairrig::StageRecord{};
}

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Both engines gave the same outputs: every stage of a capture read inputs
// with the same SHA-256 (its frames and rig.yaml, and the outputs of the
// stages before it, calibration.json included), and the last stage wrote the
// same strand frames.
void ExpectSameOutputs(const std::string& a, const std::string& b) {
  for (Stage stage : kAllStages) {
    const hairrig::StageRecord ra = Record(a, stage), rb = Record(b, stage);
    EXPECT_EQ(ra.inputs, rb.inputs) << a << " " << StageName(stage);
    EXPECT_EQ(ra.input_hash, rb.input_hash) << a << " " << StageName(stage);
  }
  const std::string frames = "/simulation/head-shake/frames";
  size_t compared = 0;
  for (const fs::directory_entry& frame : fs::directory_iterator(a + frames)) {
    const std::string name = frame.path().filename();
    EXPECT_EQ(ReadBytes(frame.path()), ReadBytes(b + frames + "/" + name)) << a << " " << name;
    ++compared;
  }
  EXPECT_GT(compared, 0u) << a + frames;
}

class BatchSlurm : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char pattern[] = "/tmp/hairrig_batch_slurm_XXXXXX";
    if (::mkdtemp(pattern) == nullptr) {
      setup_error_ = "mkdtemp failed";
      return;
    }
    work_ = pattern;
    ::chmod(pattern, 0755);  // munged wants every folder above its socket searchable by all
    cluster_ = work_ + "/cluster";
    const ProcessResult start = RunCommand({"bash", kClusterScript, "start", cluster_});
    if (start.exit_code == 77) {
      skip_reason_ = start.err;
      return;
    }
    if (start.exit_code != 0) {
      setup_error_ = "private_slurm.sh start failed: " + start.err;
      return;
    }
    started_ = true;
    ::setenv("SLURM_CONF", (cluster_ + "/slurm.conf").c_str(), 1);
  }

  // Cancels every job and stops the daemons by their pids (private_slurm.sh stop).
  static void TearDownTestSuite() {
    if (started_) {
      const ProcessResult stop = RunCommand({"bash", kClusterScript, "stop", cluster_});
      EXPECT_EQ(stop.exit_code, 0) << stop.err;
    }
    std::error_code ec;
    if (!work_.empty()) fs::remove_all(work_, ec);
  }

  void SetUp() override {
    if (!skip_reason_.empty()) GTEST_SKIP() << skip_reason_;
    ASSERT_TRUE(setup_error_.empty()) << setup_error_;
  }

  static std::string work_, cluster_, skip_reason_, setup_error_;
  static bool started_;
};
std::string BatchSlurm::work_, BatchSlurm::cluster_, BatchSlurm::skip_reason_,
    BatchSlurm::setup_error_;
bool BatchSlurm::started_ = false;

TEST_F(BatchSlurm, AFailedStageBlocksItsCaptureUntilResubmittedAndLocalRunsMatch) {
  // Three captures, and a copy of them for each engine.
  const std::string archive = work_ + "/slurm", local_archive = work_ + "/local";
  for (int c = 1; c <= kCaptures; ++c) {
    const std::string name = "cap" + std::to_string(c);
    const HairrigRun capture = Hairrig(
        {"capture", "--config", RigVariant(work_, 15 * (c - 1)), "--out", work_ + "/raw/" + name});
    ASSERT_EQ(capture.exit_code, 0) << capture.err;
  }
  fs::copy(work_ + "/raw", archive, fs::copy_options::recursive);
  fs::copy(work_ + "/raw", local_archive, fs::copy_options::recursive);
  const std::string options = work_ + "/stage_options.json";
  std::ofstream(options) << kStageOptions;
  const std::string batch = work_ + "/slurm_batch";

  ::setenv(hairrig::kStageFaultVariable, (std::string("reconstruct:") + kFaultyCapture).c_str(), 1);
  const HairrigRun submitted =
      Hairrig({"batch", "submit", "--batch", batch, "--captures", archive, "--engine", "slurm",
               "--max-parallel", "2", "--stage-options", options, "--time", "10:00"});
  ::unsetenv(hairrig::kStageFaultVariable);  // the jobs have the environment of their sbatch
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  ASSERT_EQ(submitted.summary["job_ids"].size(), 4u) << submitted.summary.dump();
  const HairrigRun status = Hairrig({"batch", "status", "--batch", batch});
  ASSERT_EQ(status.exit_code, 0) << status.err;

  HairrigRun waited =
      Hairrig({"batch", "wait", "--batch", batch, "--timeout", "600", "--poll", "1"});
  EXPECT_EQ(waited.exit_code, 3) << waited.err;  // a failure
  const nlohmann::json& first = waited.summary;
  ASSERT_TRUE(first.value("finished", false)) << first.dump(1);
  for (const char* done : {"cap1", "cap3"}) {
    for (Stage stage : kAllStages)
      EXPECT_EQ(StateOf(first, done, stage), "done") << done << " " << StageName(stage);
    EXPECT_TRUE(fs::exists(archive + "/" + done + "/simulation/head-shake/summary.json")) << done;
    // The reconstruction judged itself (reconstruction/reconstruction_verdict.h).
    EXPECT_TRUE(fs::exists(archive + "/" + done + "/reconstruction/verdict.json")) << done;
  }
  EXPECT_EQ(StateOf(first, kFaultyCapture, Stage::kCalibrate), "done");
  EXPECT_EQ(StateOf(first, kFaultyCapture, Stage::kReconstruct), "failed");
  const std::string error =
      CaptureRow(first, kFaultyCapture)["stages"]["reconstruct"].value("error", "");
  EXPECT_NE(error.find("injected fault"), std::string::npos) << error;
  EXPECT_EQ(StateOf(first, kFaultyCapture, Stage::kFit), "blocked");
  EXPECT_EQ(StateOf(first, kFaultyCapture, Stage::kSimulate), "blocked");
  EXPECT_FALSE(fs::exists(archive + "/" + kFaultyCapture + "/fit"));

  // Slurm itself cancels the blocked elements: aftercorr can never be satisfied.
  const std::string fit_array = submitted.summary["job_ids"]["fit"];
  std::string shown;
  for (int tries = 0; tries < 60 && shown.find("DependencyNeverSatisfied") == std::string::npos;
       ++tries) {
    if (tries > 0) std::this_thread::sleep_for(std::chrono::milliseconds(500));
    shown = RunCommand({"scontrol", "show", "job", "--oneliner", fit_array}).out;
  }
  EXPECT_NE(shown.find("ArrayTaskId=1 "), std::string::npos) << shown;
  EXPECT_NE(shown.find("JobState=CANCELLED Reason=DependencyNeverSatisfied"), std::string::npos)
      << shown;

  // The human report names the failure and its log.
  const ProcessResult table = RunCommand({HAIRRIG_BIN, "batch", "report", "--batch", batch});
  EXPECT_NE(table.out.find("cap2 reconstruct: injected fault"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("blocked"), std::string::npos) << table.out;

  const HairrigRun resubmitted = Hairrig({"batch", "resubmit", "--batch", batch, "--failed"});
  ASSERT_EQ(resubmitted.exit_code, 0) << resubmitted.err;
  ASSERT_EQ(resubmitted.summary["captures"].size(), 1u) << resubmitted.summary.dump();
  waited = Hairrig({"batch", "wait", "--batch", batch, "--timeout", "600", "--poll", "1"});
  EXPECT_EQ(waited.exit_code, 0) << waited.err << waited.summary.dump(1);
  const nlohmann::json& second = waited.summary;
  EXPECT_TRUE(second.value("all_succeeded", false)) << second.dump(1);
  EXPECT_EQ(StateOf(second, kFaultyCapture, Stage::kCalibrate),
            "skipped");  // unchanged since the first run
  for (Stage stage : {Stage::kReconstruct, Stage::kFit, Stage::kSimulate}) {
    EXPECT_EQ(StateOf(second, kFaultyCapture, stage), "done") << StageName(stage);
  }

  // The local engine on the other copy: the same outputs at every stage.
  const HairrigRun local =
      Hairrig({"batch", "submit", "--batch", work_ + "/local_batch", "--captures", local_archive,
               "--max-parallel", "2", "--stage-options", options});
  ASSERT_EQ(local.exit_code, 0) << local.err;
  EXPECT_TRUE(local.summary["report"].value("all_succeeded", false)) << local.summary.dump(1);
  for (int c = 1; c <= kCaptures; ++c) {
    const std::string name = "cap" + std::to_string(c);
    ExpectSameOutputs(archive + "/" + name, local_archive + "/" + name);
  }
  EXPECT_NE(Record(local_archive + "/cap1", Stage::kCalibrate).input_hash,
            Record(local_archive + "/cap2", Stage::kCalibrate).input_hash);

  // One stage by hand: unchanged, so skipped.
  const HairrigRun again =
      Hairrig({"stage", "fit", "--capture", local_archive + "/cap1", "--options", options});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(again.summary.value("skipped", false)) << again.summary.dump();
}

}  // namespace
