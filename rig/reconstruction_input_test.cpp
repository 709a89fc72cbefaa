// The views a calibrated capture gives the reconstruction, each frame checked
// against its manifest record (a frame changed, or leading outside the
// capture, is never used); and where the strands' head comes from: a head
// file, or a head fitted to the views' labels (written beside the
// reconstruction for reconstruct --head and simulate --head), on the analytic
// subject of tests/support/head_scene_testing.h.
#include "rig/reconstruction_input.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "calibration/calibration_io.h"
#include "calibration/calibration_report.h"
#include "calibration/capture_calibration.h"
#include "core/head_config.h"
#include "core/sha256.h"
#include "rig/capture_calibration_input.h"
#include "rig/journal_records.h"
#include "tests/support/head_scene_testing.h"
#include "tests/support/image_test_util.h"
#include "tests/support/two_camera_rig.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string FreshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hairrig_reconstruction_input_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir / "reconstruction" / "masks");
  return dir.string();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A calibrated capture of three views from two cameras, with frames of one
// size (no stage decodes them here), so a frame copied over another differs
// only by its SHA-256: rig.yaml, capture.json, manifest.json, frames/ and
// calibration/calibration.json with every view solved. Its path.
std::string CalibratedCapture(const std::string& name) {
  const std::string dir = FreshDir(name);
  fs::create_directories(dir + "/frames");
  WriteText(dir + "/rig.yaml", hairrig_test::kTwoCameraRigYaml);
  CaptureMetadata metadata;
  metadata.config_dir = fs::absolute("etc").string();
  WriteText(dir + "/capture.json", metadata.ToJson().dump());
  nlohmann::json frames = nlohmann::json::array();
  for (int v = 0; v < 3; ++v) {
    const bool upper = v != 1;
    const std::string serial = upper ? "SIM-CAM-UPPER" : "SIM-CAM-LOWER";
    const std::string file = FrameFileName(v, serial, "png");
    const std::string content = "the frame of view " + std::to_string(v);
    WriteText(dir + "/" + file, content);
    frames.push_back({{"view", v},
                      {"stop", v / 2},
                      {"serial", serial},
                      {"camera", upper ? "upper" : "lower"},
                      {"file", file},
                      {"bytes", content.size()},
                      {"sha256", Sha256Hex(content.data(), content.size())},
                      {"angle_measured_deg", 180.0 * (v / 2)}});
  }
  WriteText(
      dir + "/manifest.json",
      nlohmann::json{{"format", "hairrig-capture"}, {"version", 1}, {"frames", frames}}.dump());

  const Result<CaptureCalibrationInput> input = LoadCaptureCalibrationInput(dir);
  EXPECT_TRUE(input.ok()) << input.status().ToString();
  if (!input.ok()) return dir;
  CaptureCalibration result;
  CameraCalibration camera;
  camera.solved = true;
  camera.intrinsics = {
      .width_px = 64, .height_px = 48, .fx_px = 80, .fy_px = 80, .cx_px = 31.5, .cy_px = 23.5};
  camera.initial = camera.intrinsics;
  result.cameras = {camera, camera};
  FrameCalibration frame;
  frame.solved = true;
  frame.cam_from_box = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1000));
  frame.cam_from_box_init = frame.cam_from_box;
  result.frames.assign(input->frames.size(), frame);
  EXPECT_TRUE(WriteCalibration(dir + "/calibration", *input, result).ok());
  return dir;
}

std::vector<int> ViewIds(const ReconstructionInput& input) {
  std::vector<int> ids;
  for (const ReconstructionView& view : input.views) ids.push_back(view.id);
  return ids;
}

// The left_out entry of the view named `name` ("000_SIM-CAM-UPPER: why"), or "".
std::string LeftOut(const ReconstructionInput& input, const std::string& name) {
  for (const std::string& entry : input.left_out)
    if (entry.rfind(name + ": ", 0) == 0) return entry;
  return "";
}

TEST(CaptureReconstructionInput, AFrameWithAnotherViewsBytesIsLeftOutByItsSha256) {
  const std::string dir = CalibratedCapture("frame_swapped");
  const Result<ReconstructionInput> intact = LoadCaptureReconstructionInput(dir);
  ASSERT_TRUE(intact.ok()) << intact.status().ToString();
  EXPECT_EQ(ViewIds(*intact), (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(intact->left_out.empty());

  fs::copy_file(dir + "/frames/001_SIM-CAM-LOWER.png", dir + "/frames/000_SIM-CAM-UPPER.png",
                fs::copy_options::overwrite_existing);
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  EXPECT_EQ(ViewIds(*input), (std::vector<int>{1, 2}));
  ASSERT_EQ(input->left_out.size(), 1u);
  const std::string why = LeftOut(*input, "000_SIM-CAM-UPPER");
  EXPECT_NE(why.find("frames/000_SIM-CAM-UPPER.png"), std::string::npos) << why;
  EXPECT_NE(why.find("SHA-256"), std::string::npos) << why;

  // Calibration reads the frames through the same check.
  const Result<CaptureCalibrationInput> calibration = LoadCaptureCalibrationInput(dir);
  ASSERT_TRUE(calibration.ok()) << calibration.status().ToString();
  EXPECT_NE(calibration->frames[0].unusable.find("SHA-256"), std::string::npos);
  EXPECT_EQ(calibration->frames[1].unusable, "");
}

nlohmann::json ReadManifest(const std::string& dir) {
  std::ifstream in(dir + "/manifest.json");
  return nlohmann::json::parse(in);
}

// Replaces view `view`'s frame by `bytes` and rewrites its manifest entry to
// match them, as a hostile capture would.
void ReplaceFrameAndRecord(const std::string& dir, size_t view, const std::string& bytes) {
  nlohmann::json manifest = ReadManifest(dir);
  nlohmann::json& entry = manifest["frames"][view];
  WriteText(dir + "/" + entry["file"].get<std::string>(), bytes);
  entry["bytes"] = bytes.size();
  entry["sha256"] = Sha256Hex(bytes.data(), bytes.size());
  WriteText(dir + "/manifest.json", manifest.dump());
}

// A frame replaced by a PNG whose header claims 100000 x 100000 px, its
// record rewritten to match: the calibration never decodes it (OpenCV's own
// size check would throw inside a worker thread and end the process); the
// view is left out naming the file and the claimed size.
TEST(CaptureCalibrationInput, AFrameClaimingTooManyPixelsIsLeftOutWithoutDecoding) {
  const std::string dir = CalibratedCapture("frame_too_large");
  ReplaceFrameAndRecord(dir, 2, PngClaiming(100000, 100000));
  const Result<CaptureCalibrationInput> input = LoadCaptureCalibrationInput(dir);
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  ASSERT_EQ(input->frames.size(), 3u);
  EXPECT_EQ(input->frames[2].unusable, "") << "its record matches";

  std::vector<std::string> failures;
  const std::vector<ViewObservations> observations =
      DetectFrames(input->frames, input->box, TagDetectorOptions{}, 2, &failures);
  ASSERT_EQ(failures.size(), 3u);
  const std::string claim = input->frames[2].path + ": its PNG header claims 100000 x 100000 px";
  EXPECT_NE(failures[2].find(claim), std::string::npos) << failures[2];
  EXPECT_TRUE(observations[2].tags.empty());

  // Tags detected as the frames landed: the report reads the file for the
  // view's residual image, and its line in report.txt says why there is none.
  CaptureCalibration result;
  result.cameras.resize(input->cameras.size());
  result.frames.resize(input->frames.size());
  result.frames[2].solved = true;
  result.frames[2].cam_from_box =
      Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1000));
  const CalibrationVerdict verdict = JudgeCalibration(*input, result);
  ASSERT_TRUE(WriteCalibrationReport(dir + "/calibration/report", *input, result, verdict, 2).ok());
  std::ifstream report(dir + "/calibration/report/report.txt");
  const std::string text(std::istreambuf_iterator<char>(report), {});
  EXPECT_NE(text.find("no residual image: " + claim), std::string::npos) << text;
}

// A manifest entry of a camera the capture's rig.yaml does not list names
// the entry's serial field and what to do.
TEST(CaptureCalibrationInput, AFrameOfACameraNotInRigYamlNamesTheSerialField) {
  const std::string dir = CalibratedCapture("frame_unknown_camera");
  nlohmann::json manifest = ReadManifest(dir);
  manifest["frames"][1]["serial"] = "SIM-CAM-OTHER";
  manifest["frames"][1]["file"] = FrameFileName(1, "SIM-CAM-OTHER", "png");
  WriteText(dir + "/manifest.json", manifest.dump());
  const Result<CaptureCalibrationInput> input = LoadCaptureCalibrationInput(dir);
  ASSERT_EQ(input.status().code(), StatusCode::kCorruptData) << input.status().ToString();
  const std::string message = input.status().message();
  EXPECT_NE(message.find(dir + "/manifest.json: field 'frames[1].serial': camera SIM-CAM-OTHER"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("add the camera to rig.yaml or restore the capture's rig.yaml"),
            std::string::npos)
      << message;
}

// A frame and its manifest entry copied onto another view: each record
// verifies on its own, and the capture is refused as resume refuses the
// same copy in the journal.
TEST(CaptureReconstructionInput, AFrameCopiedWithItsEntryOntoAnotherViewIsRefused) {
  const std::string dir = CalibratedCapture("frame_and_entry_copied");
  const nlohmann::json manifest = ReadManifest(dir);
  ReplaceFrameAndRecord(dir, 2, "the frame of view 0");
  ASSERT_EQ(ReadManifest(dir)["frames"][2]["sha256"], manifest["frames"][0]["sha256"]);
  const std::string why = "field 'frames[2].sha256': view 2 has the same frame content as view 0";
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  EXPECT_EQ(input.status().code(), StatusCode::kCorruptData) << input.status().ToString();
  EXPECT_NE(input.status().message().find(dir + "/manifest.json: " + why), std::string::npos)
      << input.status().ToString();
  const Result<CaptureCalibrationInput> calibration = LoadCaptureCalibrationInput(dir);
  EXPECT_EQ(calibration.status().code(), StatusCode::kCorruptData)
      << calibration.status().ToString();
  EXPECT_NE(calibration.status().message().find(why), std::string::npos)
      << calibration.status().ToString();
}

// A frame that is a symlink to a file inside the capture is read from the
// file its record was checked against, not through the link.
TEST(CaptureReconstructionInput, AViewReadsTheFileItsFrameWasVerifiedAs) {
  const std::string dir = CalibratedCapture("frame_symlink_inside");
  const std::string frame = dir + "/frames/002_SIM-CAM-UPPER.png";
  fs::create_directories(dir + "/kept");
  fs::rename(frame, dir + "/kept/002.png");
  fs::create_symlink("../kept/002.png", frame);
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  ASSERT_EQ(ViewIds(*input), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(input->views[2].image_path, fs::canonical(dir + "/kept/002.png").string());
  EXPECT_EQ(input->views[0].image_path,
            fs::canonical(dir + "/frames/000_SIM-CAM-UPPER.png").string());
}

// A calibrated view whose frame no manifest entry lists is left out, naming
// the frame's full path.
TEST(CaptureReconstructionInput, AViewWithoutAManifestEntryIsLeftOutNamingItsFile) {
  const std::string dir = CalibratedCapture("frame_unlisted");
  nlohmann::json manifest = ReadManifest(dir);
  manifest["frames"].erase(1);
  WriteText(dir + "/manifest.json", manifest.dump());
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  EXPECT_EQ(ViewIds(*input), (std::vector<int>{0, 2}));
  const std::string why = LeftOut(*input, "001_SIM-CAM-LOWER");
  EXPECT_NE(why.find(dir + "/frames/001_SIM-CAM-LOWER.png: no manifest.json record vouches for it"),
            std::string::npos)
      << why;
}

TEST(CaptureReconstructionInput, AFramesFolderLeadingOutsideTheCaptureIsRefused) {
  const std::string dir = CalibratedCapture("frames_symlink");
  const std::string outside = dir + "_outside_frames";
  fs::remove_all(outside);
  fs::copy(dir + "/frames", outside);
  fs::remove_all(dir + "/frames");
  fs::create_directory_symlink(outside, dir + "/frames");
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_EQ(input.status().code(), StatusCode::kFailedPrecondition) << input.status().ToString();
  EXPECT_NE(input.status().message().find(dir + "/frames"), std::string::npos)
      << input.status().message();
  EXPECT_NE(input.status().message().find("outside"), std::string::npos)
      << input.status().message();
  const Result<CaptureCalibrationInput> calibration = LoadCaptureCalibrationInput(dir);
  ASSERT_EQ(calibration.status().code(), StatusCode::kFailedPrecondition)
      << calibration.status().ToString();
  EXPECT_NE(calibration.status().message().find(dir + "/frames"), std::string::npos)
      << calibration.status().message();
}

TEST(CaptureReconstructionInput, AFrameLeadingOutsideTheCaptureIsLeftOut) {
  const std::string dir = CalibratedCapture("frame_symlink");
  const std::string frame = dir + "/frames/002_SIM-CAM-UPPER.png";
  const std::string outside = dir + "_outside_frame.png";
  fs::remove(outside);
  fs::rename(frame, outside);  // the same bytes, so only where it lies is wrong
  fs::create_symlink(outside, frame);
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_TRUE(input.ok()) << input.status().ToString();
  EXPECT_EQ(ViewIds(*input), (std::vector<int>{0, 1}));
  const std::string why = LeftOut(*input, "002_SIM-CAM-UPPER");
  EXPECT_NE(why.find("outside"), std::string::npos) << why;
}

TEST(CaptureReconstructionInput, TooFewVerifiedViewsRefuseTheCapture) {
  const std::string dir = CalibratedCapture("frames_changed");
  for (const char* file : {"000_SIM-CAM-UPPER.png", "001_SIM-CAM-LOWER.png"})
    WriteText(dir + "/frames/" + file, "changed after capture");
  const Result<ReconstructionInput> input = LoadCaptureReconstructionInput(dir);
  ASSERT_EQ(input.status().code(), StatusCode::kFailedPrecondition) << input.status().ToString();
  const std::string message = input.status().message();
  EXPECT_NE(message.find("only 1 view(s) can be used"), std::string::npos) << message;
  EXPECT_NE(message.find("000_SIM-CAM-UPPER: "), std::string::npos) << message;
  EXPECT_NE(message.find("001_SIM-CAM-LOWER: "), std::string::npos) << message;
}

// The subject's views as a reconstruction sees them, their labels written
// where the points stage writes them.
std::vector<ReconstructionView> LabelledViews(const std::string& reconstruction_dir) {
  const HeadSpec truth = head_scene::TrueHead(Eigen::Vector3d(0, -1, 0));
  std::vector<ReconstructionView> views;
  int id = 0;
  for (const HeadFitView& v : head_scene::Views(truth)) {
    ReconstructionView view;
    view.id = id++;
    view.name = "view" + std::to_string(view.id);
    view.camera = v.camera;
    view.cam_from_object = v.cam_from_object;
    EXPECT_TRUE(cv::imwrite(reconstruction_dir + "/masks/" + view.name + "_label.png", v.label));
    views.push_back(view);
  }
  return views;
}

TEST(SubjectHead, AHeadFileIsTakenAsItIs) {
  const std::string dir = FreshDir("file");
  HeadSpec head;
  head.center_turntable_mm = Eigen::Vector3d(1, 2, 300);
  ASSERT_TRUE(WriteHeadFile(dir + "/head.yaml", head).ok());
  SubjectHeadRequest request;
  request.head_file = dir + "/head.yaml";
  const Result<SubjectHead> resolved = ResolveSubjectHead(request);
  ASSERT_TRUE(resolved.ok()) << resolved.status().ToString();
  EXPECT_EQ(resolved->source, dir + "/head.yaml");
  EXPECT_FALSE(resolved->fit.has_value());
  EXPECT_EQ(resolved->spec.center_turntable_mm, head.center_turntable_mm);
}

TEST(SubjectHead, AFittedHeadIsWrittenForTheNextStages) {
  const std::string dir = FreshDir("fit");
  const std::vector<ReconstructionView> views = LabelledViews(dir + "/reconstruction");
  SubjectHeadRequest request;  // no head file and no capture (a COLMAP model): refused
  request.reconstruction_dir = dir + "/reconstruction";
  request.views = &views;
  const Result<SubjectHead> refused = ResolveSubjectHead(request);
  ASSERT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("--head fit"), std::string::npos);
  request.head_file = kFittedHead;
  const Result<SubjectHead> resolved = ResolveSubjectHead(request);
  ASSERT_TRUE(resolved.ok()) << resolved.status().ToString();
  ASSERT_TRUE(resolved->fit.has_value());
  EXPECT_NE(resolved->source.find("fitted"), std::string::npos) << resolved->source;
  const Result<HeadSpec> written = LoadHeadFile(dir + "/reconstruction/head.yaml");
  ASSERT_TRUE(written.ok()) << written.status().ToString();
  EXPECT_TRUE(written->center_turntable_mm.isApprox(resolved->spec.center_turntable_mm, 1e-4));
  EXPECT_TRUE(written->radii_mm.isApprox(resolved->spec.radii_mm, 1e-4));
  EXPECT_TRUE(written->scalp.defined);
  EXPECT_FALSE(written->scalp.parting);
}

TEST(SubjectHead, AFitWithoutLabelsSaysToRunThePointsStage) {
  const std::string dir = FreshDir("no_labels");
  std::vector<ReconstructionView> views(3);
  for (size_t i = 0; i < views.size(); ++i) views[i].name = "view" + std::to_string(i);
  SubjectHeadRequest request;
  request.head_file = kFittedHead;
  request.reconstruction_dir = dir + "/reconstruction";
  request.views = &views;
  const Result<SubjectHead> resolved = ResolveSubjectHead(request);
  ASSERT_EQ(resolved.status().code(), StatusCode::kNotFound);
  EXPECT_NE(resolved.status().message().find("run the points stage first"), std::string::npos)
      << resolved.status().message();
  EXPECT_FALSE(fs::exists(dir + "/reconstruction/head.yaml"));
}

}  // namespace
}  // namespace hairrig
