#include "rig/simulate_run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/file_util.h"
#include "core/json_file.h"
#include "core/strand_io.h"
#include "sim_rig/sim_rig.h"
#include "simulation/fit_strand_file.h"
#include "tests/support/capture_test_util.h"
#include "tests/support/strand_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using hairrig::testing::FreshDir;

// The previews are drawn by the simulated rig's renderer.
[[maybe_unused]] const bool kSimRigRegistered = (RegisterSimRig(), true);

// Four guides fitted to twelve curls, in `dir`; the model's path.
std::string CurlsModel(const std::string& dir) {
  const StrandSet set = TwelveCurls();
  FitStrandFileOptions fit;
  fit.strands_file = dir + "/curls.hair";
  fit.out_file = dir + "/model.json";
  fit.fit.guides.num_guides = 4;
  EXPECT_TRUE(WriteStrands(fit.strands_file, set).ok());
  const auto fitted = FitStrandFile(fit);
  EXPECT_TRUE(fitted.ok()) << fitted.status().ToString();
  return fit.out_file;
}

SimulateRunOptions ShortWind(const std::string& model, const std::string& out) {
  SimulateRunOptions o;
  o.model_file = model;
  o.out_dir = out;
  o.scenario = Scenario::kWind;
  o.seconds = 0.2;
  o.fps = 10;
  o.head_contact = false;
  o.preview_every = 2;
  return o;
}

TEST(SimulateRun, WritesEveryFrameAPreviewEveryNAndTheSummary) {
  const std::string dir = FreshDir("simulate_run");
  const SimulateRunOptions o = ShortWind(CurlsModel(dir), dir + "/out");
  const auto summary = SimulateRun(o);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->frames, 3);
  EXPECT_EQ(summary->guides, 4);
  EXPECT_TRUE(summary->interpolated);
  EXPECT_EQ(summary->strands, 12u) << "every strand of the source, interpolated from the guides";
  EXPECT_GT(summary->max_tip_move_mm, 0.0);
  // The interpolated strands keep their rest lengths in every frame.
  EXPECT_NEAR(summary->strand_stretch_max, 1.0, 1e-4);
  EXPECT_NEAR(summary->strand_stretch_p99, 1.0, 1e-4);
  for (const char* f :
       {"frames/frame_0000.hair", "frames/frame_0001.hair", "frames/frame_0002.hair",
        "guides/frame_0000.hair", "guides/frame_0002.hair", "previews/frame_0000.png",
        "previews/frame_0002.png"}) {
    EXPECT_TRUE(fs::exists(o.out_dir + "/" + f)) << f;
  }
  EXPECT_FALSE(fs::exists(o.out_dir + "/previews/frame_0001.png"));
  const auto guides = ReadStrands(o.out_dir + "/guides/frame_0002.hair");
  ASSERT_TRUE(guides.ok()) << guides.status().ToString();
  EXPECT_EQ(guides->num_strands(), 4u);
  const auto written = ReadJsonFile(o.out_dir + "/summary.json");
  ASSERT_TRUE(written.ok()) << written.status().ToString();
  EXPECT_EQ(*written, summary->ToJson());
  EXPECT_EQ((*written)["scenario"], "wind");

  const auto again = SimulateRun(o);
  ASSERT_FALSE(again.ok());
  EXPECT_NE(again.status().message().find("already exists"), std::string::npos)
      << again.status().ToString();
}

TEST(SimulateRun, GuidesOnlyWritesTheGuides) {
  const std::string dir = FreshDir("simulate_run_guides");
  SimulateRunOptions o = ShortWind(CurlsModel(dir), dir + "/out");
  o.guides_only = true;
  o.preview_every = 0;
  const auto summary = SimulateRun(o);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_FALSE(summary->interpolated);
  EXPECT_EQ(summary->strands, 4u);
  const auto frame = ReadStrands(o.out_dir + "/frames/frame_0002.hair");
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  EXPECT_FALSE(fs::exists(o.out_dir + "/guides")) << "the frames are the guides";
  EXPECT_EQ(frame->num_strands(), 4u);
  EXPECT_TRUE(fs::is_empty(o.out_dir + "/previews"));
}

// Guides do not interact: the frames are the same bytes on one thread or several.
TEST(SimulateRun, TheFramesDoNotDependOnTheThreadCount) {
  const std::string dir = FreshDir("simulate_run_threads");
  const std::string model = CurlsModel(dir);
  std::vector<std::string> frames;
  for (int threads : {1, 3}) {
    SimulateRunOptions o = ShortWind(model, dir + "/out" + std::to_string(threads));
    o.preview_every = 0;
    o.head_contact = true;
    o.threads = threads;
    const auto summary = SimulateRun(o);
    ASSERT_TRUE(summary.ok()) << summary.status().ToString();
    const auto bytes = ReadFileBytes(o.out_dir + "/frames/frame_0002.hair", 1 << 24);
    ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
    frames.emplace_back(bytes->begin(), bytes->end());
  }
  EXPECT_EQ(frames[0], frames[1]);
}

TEST(SimulateRun, OptionsOutOfRangeAreNamed) {
  SimulateRunOptions o = ShortWind("model.json", "out");
  o.fps = 0;
  EXPECT_NE(o.Check().message().find("--fps"), std::string::npos);
  o.fps = 10;
  o.up = Eigen::Vector3d::Zero();
  EXPECT_NE(o.Check().message().find("--up"), std::string::npos);
  o.up = Eigen::Vector3d(0, 0, 2);
  o.preview_every = -1;
  EXPECT_NE(o.Check().message().find("--preview-every"), std::string::npos);
  o.preview_every = 0;
  o.threads = -1;
  EXPECT_NE(o.Check().message().find("--threads"), std::string::npos);
  o.threads = 0;
  o.time_step_s = 0;
  EXPECT_NE(o.Check().message().find("time_step_s"), std::string::npos);
  o.time_step_s = 1.0 / 240;
  EXPECT_TRUE(o.Check().ok());
}

}  // namespace
}  // namespace hairrig
