#include "console/capture_archive.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// A capture folder as the dataset leaves it: manifest.json, capture.json and one frame.
void MakeCapture(const fs::path& root, const std::string& id, const std::string& created,
                 const std::string& status) {
  const fs::path dir = root / id;
  cv::Mat frame(64, 96, CV_8UC3, cv::Scalar(10, 200, 30));
  fs::create_directories(dir / "frames");
  ASSERT_TRUE(cv::imwrite((dir / "frames/000_CAM.png").string(), frame));
  const nlohmann::json manifest = {
      {"format", "hairrig-capture"},
      {"version", 1},
      {"subject", "wig " + id},
      {"status", status},
      {"views_planned", 2},
      {"views_completed", 1},
      {"frames", {{{"view", 0}, {"camera", "upper"}, {"file", "frames/000_CAM.png"}}}}};
  WriteText(dir / "manifest.json", manifest.dump());
  WriteText(dir / "capture.json", nlohmann::json{{"created_utc", created}}.dump());
  WriteText(dir / "journal.jsonl", "{}\n");
}

class CaptureArchiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = testing::FreshDir("capture_archive");
    MakeCapture(root_, "older", "2026-11-01T10:00:00.000Z", "complete");
    MakeCapture(root_, "newer", "2026-11-02T10:00:00.000Z", "stopped");
  }
  std::string root_;
};

TEST_F(CaptureArchiveTest, ListsCapturesNewestFirstWithTheirStatus) {
  WriteText(fs::path(root_) / "broken/manifest.json", "{not json");
  fs::create_directories(fs::path(root_) / "no-manifest");
  const CaptureArchive archive(root_);
  const std::vector<ArchiveEntry> list = archive.List();
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0].id, "newer");
  EXPECT_EQ(list[0].status, "stopped");
  EXPECT_EQ(list[0].subject, "wig newer");
  EXPECT_EQ(list[1].id, "older");
  EXPECT_EQ(list[2].id, "broken");
  EXPECT_EQ(list[2].status, "unreadable");
  EXPECT_NE(list[2].message.find("not valid JSON"), std::string::npos) << list[2].message;
  EXPECT_FALSE(list[0].verdict.has_value());
}

TEST_F(CaptureArchiveTest, IdsArePlainFolderNamesNeverPaths) {
  const CaptureArchive archive(root_);
  for (const std::string id : {"..", ".", "../older", "a/b", "/etc", "", ".hidden", "x y"}) {
    EXPECT_EQ(archive.Entry(id).status().code(), StatusCode::kInvalidArgument) << id;
  }
  EXPECT_EQ(archive.Entry("absent").status().code(), StatusCode::kNotFound);
  EXPECT_TRUE(archive.Entry("older").ok());
}

TEST_F(CaptureArchiveTest, ServesOnlyFilesOfTheKnownKindsInsideTheCapture) {
  const CaptureArchive archive(root_);
  EXPECT_TRUE(archive.FilePath("older", "journal.jsonl").ok());
  EXPECT_EQ(archive.FilePath("older", "contact_sheet.png").status().code(), StatusCode::kNotFound);
  for (const std::string bad :
       {"../newer/journal.jsonl", "rig.yaml", "frames/000_CAM.png", "/etc/passwd",
        "calibration/report/residuals/../../../journal.jsonl", "reconstruction/../journal.jsonl",
        "simulation/../x.png"}) {
    EXPECT_EQ(archive.FilePath("older", bad).status().code(), StatusCode::kInvalidArgument) << bad;
  }
  // A served name that is a symlink out of the capture is refused.
  fs::create_directories(fs::path(root_) / "older/calibration/report");
  fs::create_symlink("/etc/passwd", fs::path(root_) / "older/calibration/report/report.txt");
  EXPECT_EQ(archive.FilePath("older", "calibration/report/report.txt").status().code(),
            StatusCode::kCorruptData);
  // So is a capture folder that is a symlink to elsewhere.
  const std::string outside = testing::FreshDir("capture_archive_outside");
  MakeCapture(outside, "elsewhere", "2026-11-03T10:00:00.000Z", "complete");
  fs::create_directory_symlink(fs::path(outside) / "elsewhere", fs::path(root_) / "linked");
  EXPECT_EQ(archive.Entry("linked").status().code(), StatusCode::kCorruptData);
  for (const ArchiveEntry& e : archive.List()) EXPECT_NE(e.id, "linked");
}

TEST_F(CaptureArchiveTest, ThumbnailsAndDetailsComeFromTheManifest) {
  const CaptureArchive archive(root_);
  const Result<std::vector<uint8_t>> thumb = archive.Thumbnail("older", 0, 48);
  ASSERT_TRUE(thumb.ok()) << thumb.status().ToString();
  const cv::Mat decoded = cv::imdecode(*thumb, cv::IMREAD_COLOR);
  ASSERT_FALSE(decoded.empty());
  EXPECT_LE(decoded.cols, 48);
  EXPECT_NEAR(decoded.at<cv::Vec3b>(decoded.rows / 2, decoded.cols / 2)[1], 200, 12);
  EXPECT_EQ(archive.Thumbnail("older", 1, 48).status().code(), StatusCode::kNotFound);

  const Result<nlohmann::json> details = archive.Details("older");
  ASSERT_TRUE(details.ok());
  ASSERT_EQ((*details)["views"].size(), 1u);
  EXPECT_EQ((*details)["views"][0]["thumb"], "/api/captures/older/views/0/thumb.jpg");
  EXPECT_TRUE((*details)["calibration"].is_null());
  EXPECT_TRUE((*details)["reconstruction"].is_null());
  EXPECT_EQ((*details)["files"]["journal"], "/api/captures/older/files/journal.jsonl");
  EXPECT_TRUE((*details)["files"]["contact_sheet"].is_null());
  EXPECT_TRUE((*details)["files"]["reconstruction"].empty());
}

TEST_F(CaptureArchiveTest, ThePipelinesPicturesAreListedWhenItsStagesRan) {
  const fs::path dir = fs::path(root_) / "older";
  WriteText(dir / "reconstruction/strands/preview.jpg", "jpeg");
  WriteText(dir / "reconstruction/strands/strands.ply", "ply");  // data: a download
  WriteText(dir / "reconstruction/strands/hair.display.glb", "glTF");
  WriteText(dir / "reconstruction/strands/segments.ply", "ply");  // an intermediate: not served
  WriteText(dir / "simulation/head-shake/frame_0000.png", "png");
  WriteText(dir / "calibration/report/verdict.json",
            R"({"verdict": "good", "reasons": [], "views_to_check": []})");
  WriteText(dir / "calibration/calibration.json",
            R"({"rms_px": 0.1, "views": [{"frame": "frames/000_CAM.png", "solved": true,
                "rms_px": 0.1}, {"frame": "frames/001_CAM.png", "solved": false}]})");
  WriteText(dir / "calibration/report/residuals/000_CAM.jpg", "jpeg");
  WriteText(dir / "reconstruction/verdict.json",
            R"({"verdict": "check", "reasons": ["the strands are short"], "views_to_check": []})");
  const CaptureArchive archive(root_);
  const Result<nlohmann::json> details = archive.Details("older");
  ASSERT_TRUE(details.ok()) << details.status().ToString();
  const nlohmann::json& files = (*details)["files"];
  EXPECT_EQ(
      files["reconstruction"],
      nlohmann::json::array({"/api/captures/older/files/reconstruction/strands/preview.jpg"}));
  EXPECT_EQ(
      files["simulation"],
      nlohmann::json::array({"/api/captures/older/files/simulation/head-shake/frame_0000.png"}));
  const nlohmann::json& calibration = (*details)["calibration"];
  EXPECT_EQ(calibration["verdict"], "good");
  ASSERT_EQ(calibration["views"].size(), 2u);
  EXPECT_FALSE(calibration["views"][1]["solved"].get<bool>());
  EXPECT_EQ(calibration["residuals"].size(), 1u);
  EXPECT_TRUE(archive.Entry("older")->reconstructed);
  EXPECT_EQ(archive.Entry("older")->verdict.value_or(""), "good");
  const nlohmann::json& reconstruction = (*details)["reconstruction"];
  EXPECT_EQ(reconstruction["verdict"], "check");
  EXPECT_EQ(reconstruction["reasons"], nlohmann::json::array({"the strands are short"}));
  EXPECT_TRUE(archive.FilePath("older", "reconstruction/verdict.json").ok());
  // A verdict whose reasons are not a list of strings is not shown (the page maps over them).
  WriteText(dir / "reconstruction/verdict.json", R"({"verdict": "good", "reasons": "none"})");
  EXPECT_TRUE((*archive.Details("older"))["reconstruction"].is_null());
  EXPECT_TRUE(archive.FilePath("older", "reconstruction/strands/preview.jpg").ok());
  EXPECT_TRUE(archive.FilePath("older", "reconstruction/strands/strands.ply").ok());
  EXPECT_EQ(ContentTypeOf("x/hair.display.glb"), "model/gltf-binary");
  EXPECT_EQ(
      files["downloads"],
      nlohmann::json::array({"/api/captures/older/files/reconstruction/strands/hair.display.glb",
                             "/api/captures/older/files/reconstruction/strands/strands.ply"}));
  EXPECT_EQ(archive.FilePath("older", "reconstruction/strands/segments.ply").status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(files["model"], "/api/captures/older/files/reconstruction/strands/hair.display.glb");
}

TEST_F(CaptureArchiveTest, TheReconstructionsFiguresComeFromItsSummaries) {
  const fs::path dir = fs::path(root_) / "older";
  const CaptureArchive archive(root_);
  nlohmann::json figures = (*archive.Details("older"))["reconstruction_figures"];
  EXPECT_TRUE(figures["points"].is_null());
  EXPECT_TRUE(figures["strands"].is_null());
  EXPECT_TRUE((*archive.Details("older"))["files"]["model"].is_null());
  WriteText(dir / "reconstruction/summary.json",
            R"({"fusion": {"points": 420, "depth_pairs": 1000, "direction_pairs": 524}})");
  WriteText(dir / "reconstruction/strands/summary.json",
            R"({"strands": {"count": 20, "mean_length_mm": 241.5}})");
  figures = (*archive.Details("older"))["reconstruction_figures"];
  EXPECT_EQ(figures["points"], 420);
  EXPECT_DOUBLE_EQ(figures["direction_agreement"].get<double>(), 0.524);
  EXPECT_EQ(figures["strands"], 20);
  EXPECT_DOUBLE_EQ(figures["strand_mean_length_mm"].get<double>(), 241.5);
  // A summary with a field of the wrong kind shows nothing of it rather than a wrong figure.
  WriteText(dir / "reconstruction/strands/summary.json",
            R"({"strands": {"count": "many", "mean_length_mm": 241.5}})");
  figures = (*archive.Details("older"))["reconstruction_figures"];
  EXPECT_TRUE(figures["strands"].is_null());
  EXPECT_EQ(figures["points"], 420);
}

TEST(ContentTypeOf, ByExtension) {
  EXPECT_EQ(ContentTypeOf("a/b.jpg"), "image/jpeg");
  EXPECT_EQ(ContentTypeOf("x.png"), "image/png");
  EXPECT_EQ(ContentTypeOf("journal.jsonl"), "text/plain; charset=utf-8");
  EXPECT_EQ(ContentTypeOf("m.json"), "application/json");
}

}  // namespace
}  // namespace hairrig
