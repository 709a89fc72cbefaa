// Where the strands' head comes from: a head file, or a head fitted to the
// views' labels (written beside the reconstruction for reconstruct --head
// and simulate --head), on the analytic subject of reconstruction/head_scene_testing.h.
#include "rig/reconstruction_input.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/head_config.h"
#include "reconstruction/head_scene_testing.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

std::string FreshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hairrig_reconstruction_input_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir / "reconstruction" / "masks");
  return dir.string();
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
