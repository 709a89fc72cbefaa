#include "rig/capture.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/file_util.h"
#include "core/truth_maps.h"
#include "rig/capture_plan.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/quota_storage.h"
#include "sim_hw/renderer.h"
#include "sim_rig/sim_rig.h"
#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using namespace hairrig::testing;

// The rigs these tests build are simulated ones (sim_rig/sim_rig.h).
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

class CountingSink : public FrameSink {
 public:
  void OnFrameStored(const StoredFrame& frame) override {
    ++frames;
    if (frame.image.cols == 300 && frame.image.rows == 400 && fs::exists(frame.path)) ++good;
  }
  void OnCaptureFinished() override { finished = true; }
  std::atomic<int> frames{0}, good{0};
  std::atomic<bool> finished{false};
};

CaptureSummary Capture(const std::string& config, const std::string& out, FrameSink* sink = nullptr,
                       std::function<void(const CaptureProgress&)> on_progress = nullptr) {
  CaptureOptions o;
  o.config_path = config;
  o.out_dir = out;
  o.sink = sink;
  o.on_progress = std::move(on_progress);
  auto summary = RunCapture(o);
  EXPECT_TRUE(summary.ok()) << summary.status().ToString();
  return summary.ok() ? *summary : CaptureSummary{};
}

nlohmann::json Manifest(const std::string& dir) {
  std::ifstream in(dir + "/manifest.json");
  return nlohmann::json::parse(in);
}

// What every capture, complete or stopped, must satisfy: each journalled frame
// verifies, the manifest agrees with the journal, no temporaries are left.
void ExpectConsistent(const CaptureSummary& s) {
  const auto journal = ReadJournal(s.dir);
  const auto verified = VerifiedFramesOnDisk(s.dir);
  EXPECT_EQ(static_cast<int>(verified.size()), CountEvents(journal, "frame_stored"))
      << "a journalled frame fails to verify";
  EXPECT_EQ(static_cast<int>(verified.size()), s.views_completed);
  const auto manifest = Manifest(s.dir);
  EXPECT_EQ(manifest["views_completed"], s.views_completed);
  EXPECT_EQ(manifest["status"], s.status);
  EXPECT_EQ(manifest["frames"].size(), verified.size());
  for (const auto& e : fs::directory_iterator(s.dir + "/frames")) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
  EXPECT_EQ(journal.back()["event"], "session_end");
}

// Every planned view of a simulated capture is in ground_truth.json; every
// view with a stored frame has its ground-truth maps (a view rendered but not
// stored may have them too), and they are the maps of the view's camera at
// the turntable angle ground_truth.json gives it, rendered here again from the
// recorded scene.
void ExpectGroundTruthOfEveryStoredView(const std::string& capture_dir, int views) {
  std::ifstream in(capture_dir + "/ground_truth/ground_truth.json");
  const nlohmann::json truth = nlohmann::json::parse(in);
  ASSERT_EQ(truth["views"].size(), static_cast<size_t>(views));
  auto scene = LoadScene(truth["scene"].get<std::string>());
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  // The true head, its mesh copied beside the JSON file.
  auto read = ReadCaptureTruth(capture_dir);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_TRUE(read->head.has_value());
  EXPECT_EQ(read->head->radii_mm, scene->head.radii_mm);
  EXPECT_EQ(read->head->scalp.defined, scene->head.scalp.defined);
  EXPECT_EQ(read->head->mesh_file.empty(), scene->head.mesh_file.empty());
  if (!scene->head.mesh_file.empty()) {
    EXPECT_TRUE(fs::exists(read->head->mesh_file)) << read->head->mesh_file;
  }
  auto renderer = Renderer::Create(*scene);
  ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
  for (const auto& v : truth["views"]) {
    const int view = v["view"].get<int>();
    const double angle = v["turntable_deg"].get<double>();
    EXPECT_NEAR(std::remainder(angle - 360.0 * v["stop"].get<int>() / 19, 360.0), 0.0, 1e-3)
        << "view " << view;
    char label[32];
    std::snprintf(label, sizeof label, "%03d_label.png", view);
    if (VerifiedFramesOnDisk(capture_dir).count(view) == 0 &&
        !fs::exists(capture_dir + "/ground_truth/views/" + label))
      continue;
    auto recorded = ReadVerifiedViewTruthMaps(*read, view);
    ASSERT_TRUE(recorded.ok()) << recorded.status().ToString();
    if (view % 9 != 0) continue;  // a few views rendered again
    RenderOptions o;
    o.noise = false;
    o.ground_truth = true;
    auto again =
        (*renderer)->Render(scene->FindCamera(v["camera_serial"].get<std::string>()), angle, o);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(cv::countNonZero(recorded->label != again->truth.label), 0) << "view " << view;
    EXPECT_EQ(cv::countNonZero(recorded->strand_id != again->truth.strand_id), 0)
        << "view " << view;
    cv::Mat alpha_error;
    cv::absdiff(recorded->hair_alpha, again->truth.hair_alpha, alpha_error);
    double worst = 0;
    cv::minMaxLoc(alpha_error, nullptr, &worst);
    EXPECT_LE(worst, 1.0 / 65535) << "view " << view;  // the 16-bit quantisation
  }
}

TEST(Capture, DefaultPlanGivesThirtyEightVerifiedViews) {
  const std::string dir = FreshDir("capture_complete");
  CountingSink sink;
  // When half the views are stored: the ETA and the wall time it gave. (Two
  // cameras' frames stored at once may report 18 and then 20.)
  double eta_at_half = -1;
  std::chrono::steady_clock::time_point half;
  const CaptureSummary s =
      Capture(WriteSmallRig(dir), dir + "/c", &sink, [&](const CaptureProgress& p) {
        if (p.step.rfind("stored", 0) == 0 && p.views_done >= 19 && eta_at_half < 0) {
          eta_at_half = p.eta_s;
          half = std::chrono::steady_clock::now();
        }
      });
  // The renders (storage) lag the sweep here: the ETA follows them. A ratio
  // within one run, with room for a shared machine's noise.
  ASSERT_GE(eta_at_half, 0);
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - half).count();
  EXPECT_GT(eta_at_half, took_s / 3) << "ETA " << eta_at_half << " s, took " << took_s << " s";
  EXPECT_LT(eta_at_half, took_s * 3) << "ETA " << eta_at_half << " s, took " << took_s << " s";
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.views_planned, 38);
  EXPECT_EQ(s.views_completed, 38);
  EXPECT_EQ(s.frames, 38);
  EXPECT_EQ(s.faults, 0);
  ExpectConsistent(s);
  EXPECT_EQ(sink.frames.load(), 38);
  EXPECT_EQ(sink.good.load(), 38);
  EXPECT_TRUE(sink.finished.load());
  const auto journal = ReadJournal(s.dir);
  EXPECT_EQ(CountEvents(journal, "view_planned"), 38);
  EXPECT_EQ(CountEvents(journal, "position_reached"), 19);
  for (const auto& [view, r] : VerifiedFramesOnDisk(s.dir)) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/%03d_%s.png", view,
                  r["serial"].get<std::string>().c_str());
    EXPECT_EQ(r["file"], name);
    EXPECT_EQ(r["serial"], view % 2 == 0 ? "SIM-CAM-UPPER" : "SIM-CAM-LOWER");
    EXPECT_NEAR(r["angle_measured_deg"].get<double>(), 360.0 * (view / 2) / 19, 1e-3);
    const cv::Mat image = cv::imread(s.dir + "/" + r["file"].get<std::string>());
    EXPECT_EQ(image.cols, 300);
    EXPECT_EQ(image.rows, 400);
  }
  EXPECT_TRUE(fs::exists(s.dir + "/rig.yaml"));
  EXPECT_GT(s.lower_bound_s, 0);
  ExpectGroundTruthOfEveryStoredView(s.dir, 38);
}

// The physical lower bound, recomputed here from the scene's timings: 18 moves
// of 360/19 deg (trapezoid at 30 deg/s, 60 deg/s^2: 0.5 s ramps, so
// d/v + v/a), each with 0.5 s settle; 19 exposures of 0.02 s; the last stop's
// readout 0.05 s and download 0.25 s; all times time_scale. The efficiency is
// printed, not asserted (a shared machine's timing is noise).
// The ground truth is checked against its checksums before the evaluation
// reads it: a map of another view, a folder or a file leading outside the
// capture, and a ground truth without its checksums are refused by name.
TEST(Capture, GroundTruthChangedAfterTheCaptureIsRefused) {
  const std::string dir = FreshDir("capture_truth_changed");
  CountingSink sink;
  const CaptureSummary s = Capture(WriteSmallRig(dir), dir + "/c", &sink);
  ASSERT_EQ(s.status, "complete") << s.message;
  const std::string truth_dir = s.dir + "/ground_truth";
  auto truth = ReadCaptureTruth(s.dir);
  ASSERT_TRUE(truth.ok()) << truth.status().ToString();
  ASSERT_TRUE(ReadVerifiedViewTruthMaps(*truth, 5).ok());
  ASSERT_TRUE(VerifyTruthFile(*truth, truth->strands_file).ok());

  fs::copy_file(truth_dir + "/views/007_label.png", truth_dir + "/views/005_label.png",
                fs::copy_options::overwrite_existing);
  auto swapped = ReadVerifiedViewTruthMaps(*truth, 5);
  ASSERT_EQ(swapped.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(swapped.status().message().find("005_label.png: its SHA-256 does not match"),
            std::string::npos)
      << swapped.status().message();

  const std::string outside = dir + "/outside";
  fs::create_directories(outside);
  fs::copy_file(truth_dir + "/views/006_depth.png", outside + "/006_depth.png");
  fs::remove(truth_dir + "/views/006_depth.png");
  fs::create_symlink(outside + "/006_depth.png", truth_dir + "/views/006_depth.png");
  EXPECT_FALSE(ReadVerifiedViewTruthMaps(*truth, 6).ok()) << "a map leading outside the capture";

  fs::rename(truth_dir, outside + "/ground_truth");
  fs::create_directory_symlink(outside + "/ground_truth", truth_dir);
  const auto moved = ReadCaptureTruth(s.dir);
  ASSERT_FALSE(moved.ok());
  EXPECT_NE(moved.status().message().find("ground_truth"), std::string::npos);

  fs::remove(truth_dir);
  fs::rename(outside + "/ground_truth", truth_dir);
  fs::remove(truth_dir + "/checksums.json");
  const auto unfinished = ReadCaptureTruth(s.dir);
  ASSERT_EQ(unfinished.status().code(), StatusCode::kNotFound);
  EXPECT_NE(unfinished.status().message().find("--resume"), std::string::npos);
}

TEST(Capture, LowerBoundAndEfficiencyAtRealisticTimings) {
  const std::string dir = FreshDir("capture_efficiency");
  const double scale = 0.2;
  std::vector<CaptureProgress> progress;  // on_progress calls are serialised
  const CaptureSummary s =
      Capture(WriteSmallRig(dir, {{"sim", "sim:\n  scene: small_scene.yaml\n  time_scale: " +
                                              std::to_string(scale) + "\n"}}),
              dir + "/c", nullptr, [&](const CaptureProgress& p) { progress.push_back(p); });
  ASSERT_EQ(s.status, "complete") << s.message;
  const double move_s = (360.0 / 19) / 30 + 30.0 / 60;
  const double expected = scale * (18 * (move_s + 0.5) + 19 * 0.02 + 0.05 + 0.25);
  EXPECT_NEAR(s.lower_bound_s, expected, 1e-9);
  // The ETA starts at the plan's bound (moves, settles, exposures), stays
  // above 0 while a stop is being shot and is 0 once every stop is shot.
  ASSERT_GE(progress.size(), 19u);
  EXPECT_NEAR(progress.front().eta_s, scale * (18 * (move_s + 0.5) + 19 * 0.02), 1e-9);
  for (const CaptureProgress& p :
       progress) {  // the sequencer's own steps, before their stop is done
    if (p.step == "exposing" || p.step.rfind("moving", 0) == 0) {
      EXPECT_GT(p.eta_s, 0) << p.step << " at stop " << p.stop;
    }
  }
  EXPECT_EQ(progress.back().eta_s, 0) << progress.back().step;
  EXPECT_GT(s.wall_s,
            0.9 * s.lower_bound_s);  // the sweep cannot beat physics (10 % for clock granularity)
  std::printf("small rig at time_scale %.1f: sweep %.3f s, lower bound %.3f s, efficiency %.3f\n",
              scale, s.wall_s, s.lower_bound_s, s.efficiency);
}

TEST(Capture, RefusesAnExistingFolderWithoutResume) {
  const std::string dir = FreshDir("capture_exists");
  fs::create_directories(dir + "/c");
  CaptureOptions o;
  o.config_path = WriteSmallRig(dir);
  o.out_dir = dir + "/c";
  auto s = RunCapture(o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("--resume"), std::string::npos) << s.status().ToString();
}

// A capture with `text` as its `section` is refused naming `field`, and creates nothing.
void ExpectSectionRefused(const std::string& dir, const std::string& section,
                          const std::string& text, const std::string& field) {
  CaptureOptions o;
  o.config_path = WriteSmallRig(dir, {{section, text}});
  o.out_dir = dir + "/c";
  auto s = RunCapture(o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find(field), std::string::npos) << s.status().ToString();
  EXPECT_FALSE(fs::exists(o.out_dir));
}

void ExpectPlanRefused(const std::string& dir, const std::string& plan, const std::string& field) {
  ExpectSectionRefused(dir, "plan", plan, field);
}

TEST(Capture, BrokenConfigCreatesNothing) {
  ExpectPlanRefused(FreshDir("capture_bad_config"), "plan: {stops: 0}\n", "plan.stops");
}

// The calibration section is checked before shooting (an unknown key used to
// pass a capture and fail only its calibration).
TEST(Capture, AnUnknownKeyInTheCalibrationSectionCreatesNothing) {
  ExpectSectionRefused(FreshDir("capture_bad_calibration"), "calibration",
                       "calibration: {box: calib-box.yaml, box_height_mm: 600, box_yw_deg: 3}\n",
                       "box_yw_deg");
}

// Plan mistakes that used to pass silently (a typo switching a panel off, a
// view shot twice) or only fail at their stop (an angle of 1e12 deg) are
// refused when the config is read, before the capture folder exists.
TEST(Capture, PlanMistakesAreRefusedBeforeAnythingIsShot) {
  const std::string dir = FreshDir("capture_plan_mistakes");
  ExpectPlanRefused(dir, "plan: {lights: {top: 1, botom: 1}}\n",
                    "no light named 'botom' in the devices section (lights: top, bottom)");
  ExpectPlanRefused(
      dir, "plan:\n  views:\n    - {angle_deg: 0, camera: upper, lights: {top: 1, botom: 0}}\n",
      "plan.views[0].lights.botom");
  ExpectPlanRefused(dir, "plan: {angles_deg: [0, 1e12]}\n",
                    "plan.angles_deg': element 1: expected a number in [-3600, 3600]");
  ExpectPlanRefused(dir, "plan: {angles_deg: [0, 90, 0]}\n", "planned twice");
  ExpectPlanRefused(dir, "plan: {stops: 2, cameras: [upper, lower, upper]}\n", "planned twice");
  ExpectPlanRefused(
      dir,
      "plan:\n  views:\n    - {angle_deg: 90, camera: upper}\n    - {angle_deg: 90, camera: "
      "lower}\n"
      "    - {angle_deg: 90, camera: upper}\n",
      "plan.views[2]': camera 'upper' at 90 deg under the same lights is planned twice");
  ExpectPlanRefused(dir, "plan: {cameras: [uper]}\n",
                    "no camera named 'uper' in the devices section (cameras: upper, lower)");
  ExpectPlanRefused(dir, "plan:\n  stops: 2\n  stops: 3\n", "duplicate key 'stops' (first at line");
  ExpectPlanRefused(dir, "plan: {stops: 2}\n---\nplan: {stops: 3}\n", "a second YAML document");
}

TEST(Capture, TriggerPulseWidthIsAPlanField) {
  const std::string dir = FreshDir("capture_pulse");
  ExpectPlanRefused(dir, "plan: {trigger_pulse_us: 0}\n", "plan.trigger_pulse_us");
  const CaptureSummary ok = Capture(
      WriteSmallRig(dir, {{"plan", "plan: {stops: 2, trigger_pulse_us: 20000}\n"}}), dir + "/c2");
  EXPECT_EQ(ok.status, "complete");
}

TEST(Capture, ExplicitViewsPlan) {
  const std::string dir = FreshDir("capture_views");
  const std::string plan =
      "plan:\n  views:\n"
      "    - {angle_deg: 90, camera: upper, lights: {top: 1, bottom: 0}}\n"
      "    - {angle_deg: 90, camera: lower, lights: {top: 1, bottom: 0}}\n"
      "    - {angle_deg: 180, camera: lower}\n";
  const CaptureSummary s = Capture(WriteSmallRig(dir, {{"plan", plan}}), dir + "/c");
  EXPECT_EQ(s.status, "complete");
  EXPECT_EQ(s.views_planned, 3);
  EXPECT_EQ(CountEvents(ReadJournal(s.dir), "position_reached"), 2);
  ExpectConsistent(s);
}

// The snapshot's plan edited between sessions: resume refuses to mix two
// plans in one capture (it used to shoot the new views into the old capture).
TEST(Capture, ResumeRefusesAChangedPlan) {
  const std::string dir = FreshDir("capture_plan_changed");
  const CaptureSummary s =
      Capture(WriteSmallRig(dir, {{"plan", "plan: {stops: 2}\n"}}), dir + "/c");
  ASSERT_EQ(s.status, "complete");
  std::string snapshot;
  {
    std::ifstream in(s.dir + "/rig.yaml");
    snapshot.assign(std::istreambuf_iterator<char>(in), {});
  }
  const size_t at = snapshot.find("stops: 2");
  ASSERT_NE(at, std::string::npos);
  snapshot.replace(at, 8, "stops: 3");
  std::ofstream(s.dir + "/rig.yaml", std::ios::trunc) << snapshot;
  const size_t records = ReadJournal(s.dir).size();
  CaptureOptions o;
  o.out_dir = s.dir;
  o.resume = true;
  const auto resumed = RunCapture(o);
  ASSERT_FALSE(resumed.ok());
  EXPECT_EQ(resumed.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(resumed.status().message().find("the plan of a capture cannot change"),
            std::string::npos)
      << resumed.status().ToString();
  EXPECT_NE(resumed.status().message().find("another --out"), std::string::npos);
  EXPECT_EQ(ReadJournal(s.dir).size(), records) << "nothing journalled for a refused session";
}

std::map<std::string, std::string> SimWithFaults(const std::string& faults) {
  return {
      {"sim", "sim:\n  scene: small_scene.yaml\n  time_scale: 0.01\n  faults:\n" + faults + "\n"}};
}

std::map<std::string, std::string> WithRetries(std::map<std::string, std::string> sections,
                                               const std::string& retries) {
  sections["retries"] = retries;
  return sections;
}

TEST(CaptureFaults, DroppedFrameIsReshot) {
  const std::string dir = FreshDir("fault_drop");
  const CaptureSummary s = Capture(
      WriteSmallRig(dir, SimWithFaults("    - {kind: drop_frame, device: SIM-CAM-UPPER, at: 3}")),
      dir + "/c");
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.views_completed, 38);
  EXPECT_GE(s.faults, 1);
  const auto journal = ReadJournal(s.dir);
  EXPECT_EQ(CountEvents(journal, "reshoot_pass"), 1);
  ExpectConsistent(s);
}

TEST(CaptureFaults, CameraThatDropsOffIsReopened) {
  const std::string dir = FreshDir("fault_gone");
  const CaptureSummary s = Capture(
      WriteSmallRig(
          dir, SimWithFaults("    - {kind: camera_gone, device: SIM-CAM-LOWER, at: 5, count: 2}")),
      dir + "/c");
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.views_completed, 38);
  EXPECT_EQ(CountEvents(ReadJournal(s.dir), "device_reopened"), 1);
  ExpectConsistent(s);
}

TEST(CaptureFaults, CameraThatStaysGoneLeavesTheCaptureIncomplete) {
  const std::string dir = FreshDir("fault_gone_for_good");
  const CaptureSummary s = Capture(
      WriteSmallRig(
          dir,
          SimWithFaults("    - {kind: camera_gone, device: SIM-CAM-LOWER, at: 5, count: 1000}")),
      dir + "/c");
  EXPECT_EQ(s.status, "incomplete");
  // Every upper view; of the lower views at most the 4 triggered before it went
  // (frames still in flight when a camera drops off are lost with it).
  const auto verified = VerifiedFramesOnDisk(s.dir);
  for (int view = 0; view < 38; view += 2)
    EXPECT_TRUE(verified.count(view)) << "upper view " << view;
  EXPECT_LE(s.views_completed, 19 + 4);
  for (int view : s.missing_views) EXPECT_EQ(view % 2, 1) << "only lower views may be missing";
  EXPECT_NE(s.message.find("--resume"), std::string::npos) << s.message;
  ExpectConsistent(s);
  ExpectGroundTruthOfEveryStoredView(s.dir, 38);
}

// The frame timeout of the late-download tests: above a frame's render time
// on a busy machine (a sanitizer build renders about ten times slower). A
// frame meant to arrive after its view timed out is late by more than that:
// kLateFrameDelay device seconds at the small rig's time_scale 0.01.
#if defined(__SANITIZE_ADDRESS__)
constexpr const char* kLateFrameTimeout = "frame_timeout_s: 20";
constexpr const char* kLateFrameDelay = "delay_s: 3000";
#else
constexpr const char* kLateFrameTimeout = "frame_timeout_s: 2";
constexpr const char* kLateFrameDelay = "delay_s: 300";
#endif

TEST(CaptureFaults, LateDownloadTimesOutAndIsReshot) {
  const std::string dir = FreshDir("fault_late");
  const CaptureSummary s = Capture(
      WriteSmallRig(
          dir,
          WithRetries(
              SimWithFaults(
                  "    - {kind: download_timeout, device: SIM-CAM-UPPER, at: 2, delay_s: 300}"),
              "retries:\n  camera: {attempts: 3, backoff_s: 0.01}\n  " +
                  std::string(kLateFrameTimeout) + "\n")),
      dir + "/c");
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.views_completed, 38);
  EXPECT_GE(s.faults, 1);
  ExpectConsistent(s);
}

// Mean absolute difference, in grey levels, between a stored frame and a
// noise-free render of its camera at `turntable_deg`.
double DifferenceFromRender(const Renderer& renderer, const Scene& scene, const cv::Mat& frame,
                            const std::string& serial, double turntable_deg, double exposure_s) {
  RenderOptions o;
  o.noise = false;
  o.exposure_s = exposure_s;
  auto rendered = renderer.Render(scene.FindCamera(serial), turntable_deg, o);
  EXPECT_TRUE(rendered.ok()) << rendered.status().ToString();
  if (!rendered.ok()) return 0;
  cv::Mat a, b;
  cv::cvtColor(frame, a, cv::COLOR_BGR2GRAY);
  cv::cvtColor(rendered->image, b, cv::COLOR_BGR2GRAY);
  return cv::mean(cv::abs(a - b))[0] + cv::mean(cv::abs(b - a))[0];
}

// Every stored frame of the camera shows its own stop: it is close to a render
// of its view, and closer to it than to a render one stop on.
void ExpectEveryFrameShowsItsStop(const std::string& capture_dir, const std::string& serial) {
  std::ifstream in(capture_dir + "/ground_truth/ground_truth.json");
  const nlohmann::json truth = nlohmann::json::parse(in);
  auto scene = LoadScene(truth["scene"].get<std::string>());
  ASSERT_TRUE(scene.ok()) << scene.status().ToString();
  auto renderer = Renderer::Create(*scene);
  ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
  std::map<int, double> angle_of_view;
  for (const auto& v : truth["views"])
    angle_of_view[v["view"].get<int>()] = v["turntable_deg"].get<double>();
  int checked = 0;
  for (const auto& [view, record] : VerifiedFramesOnDisk(capture_dir)) {
    if (record["serial"] != serial) continue;
    const cv::Mat frame =
        cv::imread(capture_dir + "/" + record["file"].get<std::string>(), cv::IMREAD_COLOR);
    ASSERT_FALSE(frame.empty()) << record.dump();
    const double exposure_s = record.value("exposure_s", 0.0);
    const double own =
        DifferenceFromRender(**renderer, *scene, frame, serial, angle_of_view.at(view), exposure_s);
    const double next = DifferenceFromRender(**renderer, *scene, frame, serial,
                                             angle_of_view.at(view) + 360.0 / 19, exposure_s);
    // Sensor noise and JPEG leave about 2.3 grey levels; one stop on, about 17.
    EXPECT_LT(own, 5.0) << "view " << view;
    EXPECT_LT(own, 0.5 * next) << "view " << view << " looks like the next stop's (" << own
                               << " vs " << next << " grey levels from the renders)";
    ++checked;
  }
  EXPECT_EQ(checked, 19) << serial;
}

// The real camera backends (gphoto2 and Aravis, on their simulated devices)
// with a line trigger: a shot that comes out after its view timed out, while
// the camera's next view is awaited, is recognised by its own trigger time
// and never stored as that next view.
TEST(CaptureFaults, FrameArrivingAfterItsViewTimedOutIsNotStoredForTheNextView) {
  const std::string dir = FreshDir("fault_late_real_backends");
  auto sections =
      WithRetries(SimWithFaults("    - {kind: download_timeout, device: SIM-CAM-UPPER, at: 2, " +
                                std::string(kLateFrameDelay) + "}"),
                  "retries:\n  camera: {attempts: 3, backoff_s: 0.01}\n  " +
                      std::string(kLateFrameTimeout) + "\n");
  sections["devices"] = SmallRigDevices(
      "{name: turntable, backend: sim, serial: SIM-TT-0001}",
      "{name: upper, backend: gphoto2, serial: SIM-CAM-UPPER, port: sim, trigger_line: trig0}",
      "{name: lower, backend: aravis, serial: SIM-CAM-LOWER, address: sim, trigger_line: trig0}");
  const CaptureSummary s = Capture(WriteSmallRig(dir, sections), dir + "/c");
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.views_completed, 38);
  const auto journal = ReadJournal(s.dir);
  // The late shot did arrive while a later view was awaited, and was set aside.
  EXPECT_GE(CountEvents(journal, "stale_frame_discarded"), 1);
  ExpectConsistent(s);
  ExpectEveryFrameShowsItsStop(s.dir, "SIM-CAM-UPPER");
  ExpectEveryFrameShowsItsStop(s.dir, "SIM-CAM-LOWER");
}

TEST(CaptureFaults, TurntableTimeoutIsRetried) {
  const std::string dir = FreshDir("fault_tt_retry");
  const CaptureSummary s = Capture(
      WriteSmallRig(dir, SimWithFaults("    - {kind: turntable_timeout, at: 4}")), dir + "/c");
  EXPECT_EQ(s.status, "complete") << s.message;
  EXPECT_EQ(s.faults, 1);
  ExpectConsistent(s);
}

TEST(CaptureFaults, TurntableThatNeverArrivesStopsTheRun) {
  const std::string dir = FreshDir("fault_tt_timeout");
  const CaptureSummary s =
      Capture(WriteSmallRig(dir, SimWithFaults("    - {kind: turntable_timeout, at: 4, count: 5}")),
              dir + "/c");
  EXPECT_EQ(s.status, "stopped");
  EXPECT_NE(s.message.find("not in position"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("--resume"), std::string::npos) << s.message;
  EXPECT_EQ(s.views_completed,
            6);  // home is move 1; stop 0 needs no move; stops 1, 2 are moves 2, 3
  ExpectConsistent(s);
}

TEST(CaptureFaults, TurntableStallStopsTheRun) {
  const std::string dir = FreshDir("fault_stall");
  const CaptureSummary s = Capture(
      WriteSmallRig(dir, SimWithFaults("    - {kind: turntable_stall, at: 6}")), dir + "/c");
  EXPECT_EQ(s.status, "stopped");
  EXPECT_NE(s.message.find("stall"), std::string::npos) << s.message;
  EXPECT_EQ(s.views_completed, 10);
  ExpectConsistent(s);
}

// A run a safety input stopped: its one safety_stop record, which says the
// lights were off and the turntable still (empty when the checks failed).
nlohmann::json ExpectSafetyStopped(const CaptureSummary& s) {
  EXPECT_EQ(s.status, "stopped");
  const auto journal = ReadJournal(s.dir);
  EXPECT_EQ(CountEvents(journal, "safety_stop"), 1);
  for (const auto& r : journal) {
    if (r["event"] != "safety_stop") continue;
    EXPECT_TRUE(r["lights_on"].empty()) << r.dump();
    EXPECT_FALSE(r["turntable_moving"].get<bool>()) << r.dump();
    return r;
  }
  return nlohmann::json::object();
}

TEST(CaptureFaults, EstopStopsMotionAndSwitchesLightsOff) {
  const std::string dir = FreshDir("fault_estop");
  const CaptureSummary s =
      Capture(WriteSmallRig(dir, SimWithFaults("    - {kind: estop, at: 3}")), dir + "/c");
  EXPECT_NE(s.message.find("e-stop"), std::string::npos) << s.message;
  const nlohmann::json stop = ExpectSafetyStopped(s);
  ASSERT_TRUE(stop.contains("turntable_deg")) << stop.dump();
  // Pressed early in the move from stop 1 to stop 2 (a loaded machine may
  // deliver the press later, but never after the next stop's views).
  EXPECT_GE(stop["turntable_deg"].get<double>(), 360.0 / 19 - 1e-9);
  EXPECT_LE(stop["turntable_deg"].get<double>(), 2 * 360.0 / 19 + 1e-9);
  EXPECT_GE(s.views_completed, 4);
  EXPECT_LE(s.views_completed, 6);
  ExpectConsistent(s);
}

// The e-stop's wiring breaks during the third move: a safety input that cannot
// be read counts as pressed, so the run stops there as for an e-stop, and
// the message says the line cannot be read rather than that it was pressed.
TEST(CaptureFaults, ASafetyInputThatCannotBeReadStopsTheRun) {
  const std::string dir = FreshDir("fault_input_lost");
  const CaptureSummary s =
      Capture(WriteSmallRig(dir, SimWithFaults("    - {kind: input_lost, at: 3}")), dir + "/c");
  EXPECT_NE(s.message.find("cannot be read"), std::string::npos) << s.message;
  ExpectSafetyStopped(s);
  EXPECT_LE(s.views_completed, 6);
  ExpectConsistent(s);
  // No maps of the views never shot (at most a stop in flight beyond the
  // stored ones): the session that shoots them writes theirs.
  ExpectGroundTruthOfEveryStoredView(s.dir, 38);
  int views_with_maps = 0;
  for (const auto& e : fs::directory_iterator(s.dir + "/ground_truth/views"))
    views_with_maps += e.path().filename().string().ends_with("_label.png") ? 1 : 0;
  EXPECT_LE(views_with_maps, s.views_completed + 2);
}

// Index of the first record of `event` in `journal`; journal.size() if none.
size_t FirstEvent(const std::vector<nlohmann::json>& journal, const std::string& event) {
  for (size_t i = 0; i < journal.size(); ++i) {
    if (journal[i].value("event", "") == event) return i;
  }
  return journal.size();
}

// The run stopped at its first fault: no stop was reached after it.
void ExpectNoStopAfterTheFirstFault(const std::vector<nlohmann::json>& journal) {
  const size_t fault = FirstEvent(journal, "fault");
  ASSERT_LT(fault, journal.size()) << "no fault journalled";
  EXPECT_EQ(journal[fault]["action"], "stop the run") << journal[fault].dump();
  for (size_t i = fault + 1; i < journal.size(); ++i) {
    EXPECT_NE(journal[i]["event"], "position_reached")
        << "a stop was shot after the fault: " << journal[i].dump();
  }
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The disk fills up at the 11th frame: its write fails with ENOSPC inside
// write(2) (sim_hw/quota_storage.h). The run stops there, the 10 frames
// stored verify, and once space is free (the fault taken out of the
// snapshot) --resume completes the capture without touching them.
TEST(CaptureFaults, FullDiskStopsTheRunAndResumeFinishesIt) {
  const std::string dir = FreshDir("fault_disk");
  const std::string fault = "    - {kind: disk_full, at: 10}";
  const CaptureSummary s = Capture(WriteSmallRig(dir, SimWithFaults(fault)), dir + "/c");
  EXPECT_EQ(s.status, "stopped");
  EXPECT_NE(s.message.find("No space left on device"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("free space"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("--resume"), std::string::npos) << s.message;
  EXPECT_EQ(s.views_completed, 10);
  EXPECT_EQ(s.frames, 10);
  ExpectConsistent(s);
  const auto journal = ReadJournal(s.dir);
  ExpectNoStopAfterTheFirstFault(journal);
  const size_t fault_at = FirstEvent(journal, "fault");
  ASSERT_LT(fault_at, journal.size());
  EXPECT_NE(journal[fault_at]["what"].get<std::string>().find("No space left on device"),
            std::string::npos)
      << journal[fault_at].dump();
  const auto kept = VerifiedFramesOnDisk(s.dir);
  ASSERT_EQ(kept.size(), 10u);
  // Nothing more is written after a storage stop: the contact sheet (which
  // the disk, full only for frames, would take) waits for --resume.
  EXPECT_FALSE(fs::exists(s.dir + "/contact_sheet.png"));

  std::string snapshot = ReadFile(s.dir + "/rig.yaml");
  const std::string faults = "  faults:\n" + fault + "\n";
  const size_t at = snapshot.find(faults);
  ASSERT_NE(at, std::string::npos) << snapshot;
  std::ofstream(s.dir + "/rig.yaml", std::ios::trunc) << snapshot.erase(at, faults.size());
  CaptureOptions o;
  o.out_dir = s.dir;
  o.resume = true;
  const auto resumed = RunCapture(o);
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  EXPECT_EQ(resumed->status, "complete") << resumed->message;
  EXPECT_EQ(resumed->views_kept, 10);
  EXPECT_EQ(resumed->frames, 28);
  ExpectConsistent(*resumed);
  const auto after = VerifiedFramesOnDisk(s.dir);
  for (const auto& [view, record] : kept)
    EXPECT_EQ(after.at(view)["sha256"], record["sha256"]) << "view " << view;
  EXPECT_TRUE(fs::exists(s.dir + "/contact_sheet.png"));
}

// A folder stands where the manifest is written: the run stops naming the
// file, and does not send the operator to free disk space there is.
TEST(CaptureFaults, AFolderWhereTheManifestGoesIsNamedNotTakenForAFullDisk) {
  const std::string dir = FreshDir("manifest_folder");
  const CaptureSummary s = Capture(WriteSmallRig(dir), dir + "/c");
  ASSERT_EQ(s.status, "complete") << s.message;
  fs::remove(s.dir + "/manifest.json");
  fs::create_directories(s.dir + "/manifest.json/in_the_way");
  CaptureOptions o;
  o.out_dir = s.dir;
  o.resume = true;
  const auto resumed = RunCapture(o);
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  EXPECT_EQ(resumed->status, "stopped");
  EXPECT_NE(resumed->message.find("manifest.json"), std::string::npos) << resumed->message;
  EXPECT_NE(resumed->message.find("mend what the error names"), std::string::npos)
      << resumed->message;
  EXPECT_EQ(resumed->message.find("free space"), std::string::npos) << resumed->message;
  EXPECT_EQ(VerifiedFramesOnDisk(s.dir).size(), 38u);
}

// The plan, devices and policies of a rig config, as RunCapture reads them.
struct PlanOfRig {
  std::unique_ptr<Rig> rig;
  CapturePlan plan;
  CapturePolicies policies;
};
PlanOfRig ReadPlanOfRig(const std::string& config_path) {
  PlanOfRig out;
  auto config = LoadRigConfig(config_path);
  EXPECT_TRUE(config.ok()) << config.status().ToString();
  if (!config.ok()) return out;
  auto rig = BuildRig(*config);
  EXPECT_TRUE(rig.ok()) << rig.status().ToString();
  if (!rig.ok()) return out;
  out.rig = std::move(rig).value();
  auto plan = ReadCapturePlan(config->root, out.rig->devices);
  auto policies = ReadCapturePolicies(config->root);
  EXPECT_TRUE(plan.ok() && policies.ok());
  if (plan.ok()) out.plan = *plan;
  if (policies.ok()) out.policies = *policies;
  return out;
}

std::vector<int> AllViews(int count) {
  std::vector<int> views(static_cast<size_t>(count));
  std::iota(views.begin(), views.end(), 0);
  return views;
}

// BytesNeededToFinish for `views` of the rig config at `config_path`.
uint64_t BytesNeeded(const std::string& config_path, const std::vector<int>& views) {
  const PlanOfRig p = ReadPlanOfRig(config_path);
  return p.rig ? BytesNeededToFinish(p.plan, p.rig->devices, views, p.policies) : 0;
}

// A light that can only be switched, as a relay board's or a GPIO line's.
class SwitchOnlyLight : public Light {
 public:
  using Light::Light;
  LightCapabilities capabilities() const override { return {.dimmable = false}; }

 protected:
  Status DoOpen() override { return Status::Ok(); }
  Status DoClose() override { return Status::Ok(); }
  Status DoHealthCheck() override { return Status::Ok(); }
  Status DoSetOn(bool) override { return Status::Ok(); }
  Status DoSetLevel(double) override { return Status::Ok(); }
  Result<bool> DoIsOn() override { return false; }
};

// A level between 0 and 1 is refused for a light that cannot dim (it would
// be switched fully on), naming the light; accepted for one that can.
TEST(CapturePlan, ALevelBetweenOffAndOnNeedsADimmableLight) {
  const std::string dir = FreshDir("plan_dimmable");
  const std::string path = WriteSmallRig(dir, {{"plan", "plan: {stops: 2, lights: {top: 0.5}}\n"}});
  auto config = LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok()) << rig.status().ToString();
  DeviceSet& devices = (*rig)->devices;
  auto dimmed = ReadCapturePlan(config->root, devices);
  ASSERT_TRUE(dimmed.ok()) << dimmed.status().ToString();
  EXPECT_EQ(dimmed->stops.at(0).light_levels.at("top"), 0.5);

  ASSERT_EQ(devices.lights.at(0)->info().name, "top");
  devices.lights[0] = std::make_unique<SwitchOnlyLight>(devices.lights[0]->info());
  auto refused = ReadCapturePlan(config->root, devices);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("light 'top' (backend sim) is not dimmable: give 0 "
                                            "(off) or 1 (on)"),
            std::string::npos)
      << refused.status().ToString();
  EXPECT_NE(refused.status().message().find("rig.yaml"), std::string::npos);
}

TEST(CaptureSpace, BytesNeededToFinishCountsOnlyTheViewsLeft) {
  const std::string dir = FreshDir("space_needed");
  const PlanOfRig p =
      ReadPlanOfRig(WriteSmallRig(dir, {{"storage", "storage: {min_free_mb: 10}\n"}}));
  ASSERT_TRUE(p.rig);
  const DeviceSet& devices = p.rig->devices;
  const uint64_t frame = 300 * 400 * 3;  // the small scene's cameras, rgb8
  const uint64_t min_free = 10'000'000;
  EXPECT_EQ(BytesNeededToFinish(p.plan, devices, {}, p.policies), min_free);
  EXPECT_EQ(BytesNeededToFinish(p.plan, devices, {3, 17, 30, 36, 37}, p.policies),
            min_free + 5 * frame);
  EXPECT_EQ(BytesNeededToFinish(p.plan, devices, AllViews(38), p.policies), min_free + 38 * frame);
  CapturePolicies huge = p.policies;
  huge.min_free_mb = 1e300;
  EXPECT_EQ(BytesNeededToFinish(p.plan, devices, {0}, huge), std::numeric_limits<uint64_t>::max());
}

// Bytes of the files under `dir`.
uint64_t BytesIn(const std::string& dir) {
  uint64_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) bytes += e.file_size();
  }
  return bytes;
}

// A capture stopped by a full disk with 33 of 38 views stored resumes on a
// disk with room for its 5 missing views (and its ground truth), far less than
// the whole plan needs.
TEST(CaptureSpace, ResumeNeedsRoomOnlyForTheMissingViews) {
  const std::string dir = FreshDir("space_resume");
  const std::string config = WriteSmallRig(dir, SimWithFaults("    - {kind: disk_full, at: 33}"));
  const CaptureSummary first = Capture(config, dir + "/c");
  ASSERT_EQ(first.status, "stopped") << first.message;
  ASSERT_EQ(first.views_completed, 33);
  const uint64_t for_missing = BytesNeeded(config, first.missing_views);
  const uint64_t for_all = BytesNeeded(config, AllViews(38));
  ASSERT_GT(for_missing, 0u);
  // The ground truth (every view's maps) is written anew on the same disk, and
  // the contact sheet the stopped session did not write: its 240 px wide
  // thumbnails take less than the 300 x 400 px frames' raw bytes.
  ASSERT_FALSE(fs::exists(first.dir + "/contact_sheet.png"));
  const uint64_t contact_sheet = 38 * 300 * 400 * 3;
  const uint64_t rewritten = BytesIn(first.dir + "/ground_truth") + contact_sheet;
  // A little for the journal and manifest.
  const uint64_t disk_bytes = for_missing + rewritten + 2'000'000;
  ASSERT_LT(disk_bytes, for_all + rewritten);
  CaptureOptions o;
  o.out_dir = first.dir;
  o.resume = true;
  o.storage = std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = disk_bytes});
  const auto resumed = RunCapture(o);
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  EXPECT_EQ(resumed->status, "complete") << resumed->message;
  EXPECT_EQ(resumed->frames, 5);
  ExpectConsistent(*resumed);
}

// Another program fills the capture's disk while frames are written: after
// the 4th frame it leaves room for about two more above storage.min_free_mb.
class DiskFiller : public FrameSink {
 public:
  DiskFiller(std::shared_ptr<QuotaStorage> disk, uint64_t min_free)
      : disk_(std::move(disk)), min_free_(min_free) {}
  void OnFrameStored(const StoredFrame& frame) override {
    if (++frames_ != 4) return;
    const uint64_t frame_bytes = fs::file_size(frame.path);
    const auto free = disk_->FreeBytes(fs::path(frame.path).parent_path().string());
    ASSERT_TRUE(free.ok());
    const uint64_t keep = min_free_ + 5 * frame_bytes / 2;
    if (*free > keep) disk_->Consume(*free - keep);
  }
  void OnCaptureFinished() override {}

 private:
  std::shared_ptr<QuotaStorage> disk_;
  uint64_t min_free_;
  std::atomic<int> frames_{0};
};

// storage.min_free_mb is checked before every frame is written, not only
// when a stop is shot: the run stops (resumable) before a frame would leave
// less free, and says where, how much is free and the limit. Nothing written
// after it (ground truth, journal, manifest, contact sheet) takes the disk
// below the limit either.
TEST(CaptureSpace, MinFreeSpaceIsKeptWhileFramesAreWritten) {
  const std::string dir = FreshDir("space_min_free");
  const std::string config = WriteSmallRig(dir, {{"storage", "storage: {min_free_mb: 1}\n"}});
  const uint64_t for_all = BytesNeeded(config, AllViews(38));
  ASSERT_GT(for_all, 0u);
  const uint64_t min_free = 1'000'000;
  auto disk =
      std::make_shared<QuotaStorage>(QuotaStorageOptions{.quota_bytes = for_all + 2'000'000});
  DiskFiller filler(disk, min_free);
  CaptureOptions o;
  o.config_path = config;
  o.out_dir = dir + "/c";
  o.sink = &filler;
  o.storage = disk;
  const auto s = RunCapture(o);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->status, "stopped") << s->message;
  EXPECT_GE(s->views_completed, 4);
  EXPECT_LT(s->views_completed, 38);
  EXPECT_NE(s->message.find(s->dir + ": "), std::string::npos) << s->message;
  EXPECT_NE(s->message.find("MB free"), std::string::npos) << s->message;
  EXPECT_NE(s->message.find("1.000 MB storage.min_free_mb"), std::string::npos) << s->message;
  EXPECT_NE(s->message.find("--resume"), std::string::npos) << s->message;
  const auto free = disk->FreeBytes(s->dir);
  ASSERT_TRUE(free.ok());
  EXPECT_GE(*free, min_free) << "the capture's files went below storage.min_free_mb";
  ExpectConsistent(*s);
  ExpectNoStopAfterTheFirstFault(ReadJournal(s->dir));
}

// Every file under `dir`: its size and last write time.
std::map<std::string, std::pair<uintmax_t, fs::file_time_type>> FilesIn(const std::string& dir) {
  std::map<std::string, std::pair<uintmax_t, fs::file_time_type>> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files[e.path().string()] = {e.file_size(), e.last_write_time()};
  }
  return files;
}

// Another program fills the capture's disk once the last frame is stored,
// right before the ground truth is finished: it leaves half of
// storage.min_free_mb free. The ground truth files as they were then.
class DiskFillerAtTheEnd : public FrameSink {
 public:
  DiskFillerAtTheEnd(std::shared_ptr<QuotaStorage> disk, std::string capture_dir, uint64_t min_free)
      : disk_(std::move(disk)), dir_(std::move(capture_dir)), min_free_(min_free) {}
  void OnFrameStored(const StoredFrame&) override {}
  void OnCaptureFinished() override {
    const auto free = disk_->FreeBytes(dir_);
    ASSERT_TRUE(free.ok());
    if (*free > min_free_ / 2) disk_->Consume(*free - min_free_ / 2);
    truth_when_full = FilesIn(dir_ + "/ground_truth");
  }
  std::map<std::string, std::pair<uintmax_t, fs::file_time_type>> truth_when_full;

 private:
  std::shared_ptr<QuotaStorage> disk_;
  std::string dir_;
  uint64_t min_free_;
};

// The ground truth honours storage.min_free_mb as the frames do: once the
// disk is below the limit, no ground-truth file is written, the run ends
// stopped (exit code 3, resumable) saying to free space, and --resume on a
// disk with room writes the ground truth of every view, keeping every frame.
TEST(CaptureSpace, GroundTruthIsNotWrittenBelowMinFreeAndResumeWritesIt) {
  const std::string dir = FreshDir("space_truth");
  const std::string config = WriteSmallRig(dir);  // storage.min_free_mb: 10
  const uint64_t min_free = 10'000'000;
  auto disk = std::make_shared<QuotaStorage>(
      QuotaStorageOptions{.quota_bytes = BytesNeeded(config, AllViews(38)) + 100'000'000});
  CaptureOptions o;
  o.config_path = config;
  o.out_dir = dir + "/c";
  o.storage = disk;
  DiskFillerAtTheEnd filler(disk, o.out_dir, min_free);
  o.sink = &filler;
  const auto s = RunCapture(o);
  ASSERT_TRUE(s.ok()) << "a storage failure is a stopped run, not an error: "
                      << s.status().ToString();
  EXPECT_EQ(s->status, "stopped") << s->message;
  EXPECT_EQ(s->views_completed, 38);
  EXPECT_NE(s->message.find("ground_truth/"), std::string::npos) << s->message;
  EXPECT_NE(s->message.find("storage.min_free_mb"), std::string::npos) << s->message;
  EXPECT_NE(s->message.find("--resume"), std::string::npos) << s->message;
  ASSERT_FALSE(filler.truth_when_full.empty());
  EXPECT_EQ(FilesIn(s->dir + "/ground_truth"), filler.truth_when_full)
      << "a ground-truth file was written below storage.min_free_mb";
  ExpectConsistent(*s);
  const auto kept = VerifiedFramesOnDisk(s->dir);
  ASSERT_EQ(kept.size(), 38u);

  CaptureOptions resume;
  resume.out_dir = s->dir;
  resume.resume = true;  // on the file system: room again
  const auto resumed = RunCapture(resume);
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  EXPECT_EQ(resumed->status, "complete") << resumed->message;
  EXPECT_EQ(resumed->views_kept, 38);
  EXPECT_EQ(resumed->frames, 0);
  ExpectConsistent(*resumed);
  ExpectGroundTruthOfEveryStoredView(s->dir, 38);
  const auto after = VerifiedFramesOnDisk(s->dir);
  for (const auto& [view, record] : kept)
    EXPECT_EQ(after.at(view)["sha256"], record["sha256"]) << "view " << view;
}

// The capture's disk fills up while the ground truth is written: from the
// `at`-th file written under ground_truth/ on, each write fails with ENOSPC
// inside write(2) after half its bytes, as a full disk's does (frames and the
// rest still fit).
class GroundTruthFillsTheDisk : public PosixCaptureStorage {
 public:
  explicit GroundTruthFillsTheDisk(int at) : at_(at) {}
  Status WriteFileAtomic(const std::string& path, const void* data, size_t size,
                         const StageHook& on_stage) override {
    if (path.find("/ground_truth/") == std::string::npos || ++files_ < at_)
      return PosixCaptureStorage::WriteFileAtomic(path, data, size, on_stage);
    size_t budget = size / 2;
    return ::hairrig::WriteFileAtomic(
        path, data, size, on_stage, [&budget](int fd, const void* bytes, size_t n) -> ssize_t {
          if (budget == 0) {
            errno = ENOSPC;
            return -1;
          }
          const ssize_t written = ::write(fd, bytes, std::min(n, budget));
          if (written > 0) budget -= static_cast<size_t>(written);
          return written;
        });
  }

 private:
  const int at_;
  std::atomic<int> files_{0};
};

// ENOSPC in a ground-truth write is a full disk like any other: the run stops
// (summary `stopped`, the command line's exit code 3, not an error and exit
// code 1), says to free space, and --resume completes the capture and its
// ground truth without touching the frames stored. The 1st ground-truth file
// is ground_truth.json, written before anything moves; the 8th is one of the
// first stop's maps, written as a simulated camera renders its frame.
TEST(CaptureFaults, FullDiskInAGroundTruthWriteStopsTheRunAndResumeFinishesIt) {
  for (const int at : {1, 8}) {
    SCOPED_TRACE("ENOSPC from ground-truth file " + std::to_string(at));
    const std::string dir = FreshDir("fault_truth_disk_" + std::to_string(at));
    CaptureOptions o;
    o.config_path = WriteSmallRig(dir);
    o.out_dir = dir + "/c";
    o.storage = std::make_shared<GroundTruthFillsTheDisk>(at);
    const auto s = RunCapture(o);
    ASSERT_TRUE(s.ok()) << "a full disk is a stopped run, not an error: " << s.status().ToString();
    EXPECT_EQ(s->status, "stopped") << s->message;
    // The 1st file is written before anything moves. The 8th is written by a
    // camera's thread after it renders one of the first views, so on a busy
    // machine the sweep may have shot every view by the time it fails.
    if (at == 1) {
      EXPECT_LT(s->views_completed, 38);
    }
    EXPECT_NE(s->message.find("No space left on device"), std::string::npos) << s->message;
    EXPECT_NE(s->message.find("/ground_truth/"), std::string::npos) << s->message;
    EXPECT_NE(s->message.find("--resume"), std::string::npos) << s->message;
    ExpectConsistent(*s);
    const auto journal = ReadJournal(s->dir);
    ExpectNoStopAfterTheFirstFault(journal);
    const auto kept = VerifiedFramesOnDisk(s->dir);

    CaptureOptions resume;
    resume.out_dir = s->dir;
    resume.resume = true;
    const auto resumed = RunCapture(resume);
    ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
    EXPECT_EQ(resumed->status, "complete") << resumed->message;
    EXPECT_EQ(resumed->views_kept, static_cast<int>(kept.size()));
    ExpectConsistent(*resumed);
    ExpectGroundTruthOfEveryStoredView(s->dir, 38);
    const auto after = VerifiedFramesOnDisk(s->dir);
    for (const auto& [view, record] : kept)
      EXPECT_EQ(after.at(view)["sha256"], record["sha256"]) << "view " << view;
  }
}

// A capture observer that returns `status` when the capture ends.
class EndingObserver : public CaptureObserver {
 public:
  explicit EndingObserver(Status status) : status_(std::move(status)) {}
  Status OnCaptureBegin(const CapturePlan&, const CaptureFolder&) override { return Status::Ok(); }
  Status OnCaptureEnd(const CaptureSummary&) override { return status_; }

 private:
  Status status_;
};

// Of the observers' errors at the end of a capture, the storage failure
// stops the session and the other error is RunCapture's, whichever observer
// came first.
TEST(CaptureFaults, AnObserversErrorOutranksAnotherObserversStorageFailure) {
  const std::string dir = FreshDir("observer_errors");
  auto config = LoadRigConfig(WriteSmallRig(dir));
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  auto rig = BuildRig(*config);
  ASSERT_TRUE(rig.ok()) << rig.status().ToString();
  (*rig)->capture_observers.push_back(
      std::make_shared<EndingObserver>(IoError(dir + "/c/extra: No space left on device")));
  (*rig)->capture_observers.push_back(
      std::make_shared<EndingObserver>(FailedPrecondition("the observer's own failure")));
  CaptureOptions o;
  o.rig = rig->get();
  o.out_dir = dir + "/c";
  const auto s = RunCapture(o);
  ASSERT_FALSE(s.ok()) << "the observer's failure was lost; status " << s->status;
  EXPECT_EQ(s.status().code(), StatusCode::kFailedPrecondition) << s.status().ToString();
  EXPECT_EQ(s.status().message(), "the observer's own failure");
  EXPECT_FALSE(fs::exists(dir + "/c/contact_sheet.png"));
}

// storage.min_free_mb beyond any disk (1e300, which would refuse every
// capture as short of space), negative or not a number is refused when the
// config is read, naming the file and the field, before the capture folder
// exists. So are the simulated faults' counts and delays.
TEST(Capture, NumbersBeyondAnyRigAreRefusedNamingTheFileAndField) {
  const std::string dir = FreshDir("capture_number_ranges");
  const std::vector<std::pair<std::map<std::string, std::string>, std::string>> cases = {
      {{{"storage", "storage: {min_free_mb: 1e300}\n"}}, "field 'storage.min_free_mb'"},
      {{{"storage", "storage: {min_free_mb: -1}\n"}}, "field 'storage.min_free_mb'"},
      {{{"storage", "storage: {min_free_mb: .nan}\n"}}, "field 'storage.min_free_mb'"},
      {{{"storage", "storage: {min_free_mb: .inf}\n"}}, "field 'storage.min_free_mb'"},
      {SimWithFaults("    - {kind: turntable_timeout, at: 2000000000, count: 2000000000}"),
       "field 'sim.faults[0].at'"},
      {SimWithFaults("    - {kind: download_timeout, device: SIM-CAM-UPPER, delay_s: 1e300}"),
       "field 'sim.faults[0].delay_s'"}};
  for (const auto& [sections, field] : cases) {
    CaptureOptions o;
    o.config_path = WriteSmallRig(dir, sections);
    o.out_dir = dir + "/c";
    const auto s = RunCapture(o);
    ASSERT_FALSE(s.ok()) << field;
    EXPECT_EQ(s.status().code(), StatusCode::kInvalidArgument) << s.status().ToString();
    EXPECT_NE(s.status().message().find(o.config_path + ":"), std::string::npos)
        << s.status().ToString();
    EXPECT_NE(s.status().message().find(field), std::string::npos) << s.status().ToString();
    EXPECT_FALSE(fs::exists(o.out_dir));
  }
}

TEST(CaptureFaults, NotEnoughSpaceForThePlanIsRefusedBeforeStarting) {
  const std::string dir = FreshDir("fault_no_space");
  CaptureOptions o;
  // 100 TB, the largest storage.min_free_mb: more than this machine's disk has free.
  o.config_path = WriteSmallRig(dir, {{"storage", "storage: {min_free_mb: 1.0e8}\n"}});
  o.out_dir = dir + "/c";
  auto s = RunCapture(o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("MB free"), std::string::npos) << s.status().ToString();
  EXPECT_FALSE(fs::exists(o.out_dir));
}

}  // namespace
}  // namespace hairrig
