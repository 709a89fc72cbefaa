// Reconstruction I end to end on a reduced simulated capture (half-size
// cameras, 10,000 strands, 12 stops x 2 cameras): segmentation, orientation,
// hull, line stereo and fusion, scored by `eval reconstruction`'s library
// against the ground truth. Two views are damaged on purpose (a black frame,
// a frame of the wrong size): they are left out by name and the rest is
// reconstructed. The true strands, given as the reconstruction's strands,
// check the strand protocol's plumbing (frames, true samples, the true head).
// The reconstructed strand files are read back and fitted as `fit` does.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/head_config.h"
#include "core/strand_io.h"
#include "core/truth_maps.h"
#include "reconstruction/head_fit.h"
#include "reconstruction/point_cloud.h"
#include "reconstruction/point_reconstruction.h"
#include "reconstruction/reconstruction_evaluation.h"
#include "reconstruction/strand_reconstruction.h"
#include "simulation/helix_model.h"
#include "tests/support/reconstruction_scene.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

bool LeftOutWith(const PointReconstructionSummary& s, const std::string& name,
                 const std::string& why) {
  for (const std::string& l : s.left_out)
    if (l.find(name) != std::string::npos && l.find(why) != std::string::npos) return true;
  return false;
}

TEST(ReconstructionPoints, AReducedCaptureAgainstItsGroundTruth) {
  const std::string dir = ::testing::TempDir() + "/reconstruction_points";
  fs::remove_all(dir);
  ReconstructionInput input = hairrig_test::RenderReducedCapture(dir, {});
  ASSERT_EQ(input.views.size(), 24u);
  // View 5: a black frame; view 6: a frame of another size.
  const cv::Mat black(input.views[5].camera.height_px, input.views[5].camera.width_px, CV_8UC3,
                      cv::Scalar::all(0));
  ASSERT_TRUE(cv::imwrite(input.views[5].image_path, black));
  ASSERT_TRUE(
      cv::imwrite(input.views[6].image_path, cv::Mat(100, 80, CV_8UC3, cv::Scalar::all(90))));

  PointReconstructionOptions options;
  options.mvs.stride_px = 2;  // half-size images: as dense on the hair as stride 4 at full size
  auto summary = ReconstructPoints(input, dir + "/reconstruction", options);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  std::printf("%s", summary->BriefReport().c_str());
  EXPECT_EQ(summary->views.size(), 22u);
  EXPECT_TRUE(LeftOutWith(*summary, input.views[5].name, "black frame"));
  EXPECT_TRUE(LeftOutWith(*summary, input.views[6].name, "80x100 px"));
  for (const char* file : {"points.ply", "summary.json"})
    EXPECT_TRUE(fs::exists(dir + "/reconstruction/" + file));
  EXPECT_TRUE(fs::exists(dir + "/reconstruction/report/" + input.views[0].name + ".jpg"));
  EXPECT_TRUE(fs::exists(dir + "/reconstruction/depth/" + input.views[0].name + "_depth.png"));
  auto points = ReadPointCloudPly(dir + "/reconstruction/points.ply");
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  EXPECT_EQ(static_cast<int64_t>(points->size()), summary->fusion.points);

  auto evaluation = EvaluateReconstruction(dir, {});
  ASSERT_TRUE(evaluation.ok()) << evaluation.status().ToString();
  std::printf("%s", evaluation->BriefReport().c_str());
  const ReconstructionEvaluation& e = *evaluation;
  // Measured at half size (the full-size capture does better, docs/accuracy.md): hair
  // IoU median 0.78, orientation median 13.7 deg with 97 % kept, depth median
  // 10 mm, at (3 mm, 30 deg) precision 0.79 and visible-surface recall 0.60.
  ASSERT_EQ(e.visible.size(), 5u);
  EXPECT_EQ(e.views.size(), 22u);
  EXPECT_GT(e.mask_iou_median, 0.7);
  EXPECT_LT(e.orientation_median_deg, 20.0);
  EXPECT_GT(e.orientation_kept_fraction, 0.8);
  EXPECT_LT(e.depth_median_mm, 15.0);
  EXPECT_GT(e.points, 30000);
  EXPECT_GT(e.visible[2].precision, 0.65);
  EXPECT_GT(e.visible[2].recall, 0.45);
  // The looser the threshold, the more matches.
  for (size_t k = 1; k < e.visible.size(); ++k)
    EXPECT_GE(e.visible[k].precision, e.visible[k - 1].precision);
  EXPECT_FALSE(e.strands.has_value()) << "no strands/strands.ply: no strand scores";
  EXPECT_FALSE(e.ToJson().contains("strands"));

  // Points made from the truth (the strand stage's ceiling input), scored as the points are: the
  // true visible surface matches at the tightest threshold, and the true directions at the
  // points' own places match more often than the points' own directions.
  const std::string points_file = dir + "/reconstruction/points.ply";
  fs::copy_file(points_file, dir + "/points_as_reconstructed.ply");
  for (const TruthPointsKind kind :
       {TruthPointsKind::kVisibleSurface, TruthPointsKind::kTrueDirections}) {
    fs::copy_file(dir + "/points_as_reconstructed.ply", points_file,
                  fs::copy_options::overwrite_existing);
    auto from_truth = PointsFromTruth(dir, kind, {});
    ASSERT_TRUE(from_truth.ok()) << from_truth.status().ToString();
    ASSERT_TRUE(WritePointCloudPly(points_file, *from_truth).ok());
    auto scored = EvaluateReconstruction(dir, {});
    ASSERT_TRUE(scored.ok()) << scored.status().ToString();
    if (kind == TruthPointsKind::kVisibleSurface) {
      EXPECT_NEAR(static_cast<double>(from_truth->size()), static_cast<double>(e.points),
                  0.05 * static_cast<double>(e.points));
      EXPECT_GT(scored->visible[0].precision, 0.99);
    } else {
      EXPECT_EQ(static_cast<int64_t>(from_truth->size()), e.points);
      EXPECT_GT(scored->visible[1].precision, e.visible[1].precision + 0.05);
    }
  }
  fs::rename(dir + "/points_as_reconstructed.ply", points_file);

  // The ground truth records the true head: the scene's mannequin, its mesh copied beside it.
  auto truth = ReadCaptureTruth(dir);
  ASSERT_TRUE(truth.ok()) << truth.status().ToString();
  ASSERT_TRUE(truth->head.has_value());
  EXPECT_EQ(fs::path(truth->head->mesh_file).filename().string(), "head_mesh.ply");
  EXPECT_TRUE(fs::exists(truth->head->mesh_file));
  EXPECT_TRUE(truth->head->scalp.defined);

  // Reconstruction II on these points: strands rooted on the rig's head
  // (etc/heads/mannequin.yaml, as the rig config gives it), by every method.
  auto rig_head = LoadHeadFile("etc/heads/mannequin.yaml");
  ASSERT_TRUE(rig_head.ok()) << rig_head.status().ToString();
  std::map<std::string, StrandEvaluation> by_method;
  int64_t strands_read_back = 0;
  // bao-qi last (and again on the fitted head below): its files are the ones read back.
  for (const StrandMethod method :
       {StrandMethod::kNaive, StrandMethod::kLuo, StrandMethod::kBaoQi}) {
    StrandReconstructionOptions strand_options;
    strand_options.method = method;
    strand_options.strands = 4000;
    auto grown = ReconstructStrands(dir + "/reconstruction", *rig_head, "etc/heads/mannequin.yaml",
                                    strand_options);
    ASSERT_TRUE(grown.ok()) << grown.status().ToString();
    std::printf("%s", grown->BriefReport().c_str());
    // Every root's strand; bao-qi adds strands through the seen strands they miss.
    EXPECT_EQ(grown->growth.strands - grown->growth.cover_strands, 4000);
    if (method == StrandMethod::kBaoQi) {
      EXPECT_GT(grown->growth.cover_strands, 0);
    }
    auto scored = EvaluateReconstruction(dir, {});
    ASSERT_TRUE(scored.ok()) << scored.status().ToString();
    ASSERT_TRUE(scored->strands.has_value());
    std::printf("%s:\n%s", StrandMethodName(method), scored->strands->BriefReport().c_str());
    by_method[StrandMethodName(method)] = *scored->strands;
    // The model above the truth, from four sides: two rows of four views.
    EXPECT_EQ(scored->strands_preview, dir + "/reconstruction/strands/preview_truth.jpg");
    const cv::Mat preview = cv::imread(scored->strands_preview);
    ASSERT_FALSE(preview.empty()) << scored->strands_preview;
    EXPECT_EQ(preview.cols, 2 * preview.rows);
  }
  // Measured here (directed, (3 mm, 30 deg)): bao-qi precision 0.85, all-strands
  // recall 0.72, roots on the scalp 98.0 % (6,839 strands: 2,839 through the
  // seen strands the roots' miss); luo 0.67, 0.51 and 99.8 %; the naive
  // baseline 0.85 and 0.30.
  const StrandEvaluation& bao_qi = by_method.at("bao-qi");
  const StrandEvaluation& luo = by_method.at("luo");
  const StrandEvaluation& naive = by_method.at("naive");
  ASSERT_EQ(bao_qi.all.directed.size(), 4u);
  EXPECT_GT(bao_qi.all.directed[1].precision, 0.8);
  EXPECT_GT(bao_qi.all.directed[1].recall, 0.35);
  EXPECT_GT(bao_qi.all.directed[1].f1, 1.3 * naive.all.directed[1].f1)
      << "the structure analysis pays";
  EXPECT_GT(luo.all.directed[1].precision, 0.6);
  EXPECT_GT(luo.all.directed[1].recall, 0.38);
  EXPECT_GT(luo.all.directed[1].f1, 1.3 * naive.all.directed[1].f1)
      << "the structure analysis pays";
  for (const StrandEvaluation* method : {&bao_qi, &luo, &naive}) {
    ASSERT_TRUE(method->rooted_on_scalp_fraction.has_value());
    // 0.97: a strand traced back from a seen strand roots where it meets the
    // scalp, often right at the hairline, where the evaluation's own hairline
    // test may differ (bao-qi 98.0 %).
    EXPECT_GT(*method->rooted_on_scalp_fraction, 0.97);
  }

  // A rig config without a head: the head fitted to the views' labels. Its
  // ellipsoid lies near the rig's skull-sized one, and bao-qi's strands
  // rooted on it still score against the truth. Measured here: centre 17 mm
  // from the rig's, radii within 6 mm, face 11 deg off; bao-qi's precision
  // 0.83 and all-strands recall 0.44 at (3 mm, 30 deg), against 0.91 and
  // 0.46 on the rig's head.
  auto fitted_head =
      FitHeadToReconstruction(input.views, dir + "/reconstruction", HeadFitOptions{});
  ASSERT_TRUE(fitted_head.ok()) << fitted_head.status().ToString();
  std::printf("%s", fitted_head->BriefReport().c_str());
  EXPECT_LT((fitted_head->head.center_turntable_mm - rig_head->center_turntable_mm).norm(), 25.0);
  EXPECT_LT((fitted_head->head.radii_mm - rig_head->radii_mm).cwiseAbs().maxCoeff(), 25.0);
  EXPECT_GT(fitted_head->head.scalp.face_dir.dot(rig_head->scalp.face_dir), std::cos(DegToRad(15)));
  {
    StrandReconstructionOptions strand_options;
    strand_options.strands = 4000;
    auto grown =
        ReconstructStrands(dir + "/reconstruction", fitted_head->head, "fitted", strand_options);
    ASSERT_TRUE(grown.ok()) << grown.status().ToString();
    strands_read_back = grown->growth.strands;  // its files are the last written
    auto scored = EvaluateReconstruction(dir, {});
    ASSERT_TRUE(scored.ok()) << scored.status().ToString();
    ASSERT_TRUE(scored->strands.has_value());
    std::printf("bao-qi on the fitted head:\n%s", scored->strands->BriefReport().c_str());
    const StrandEvaluation& on_fitted = *scored->strands;
    EXPECT_GT(on_fitted.all.directed[1].precision, 0.7);
    EXPECT_GT(on_fitted.all.directed[1].f1, 0.6 * bao_qi.all.directed[1].f1);
  }

  // The three strand files hold the same model, and `fit` takes them as they are.
  const std::string strands_dir = dir + "/reconstruction/strands";
  auto from_ply = ReadStrands(strands_dir + "/strands.ply");
  ASSERT_TRUE(from_ply.ok()) << from_ply.status().ToString();
  EXPECT_EQ(static_cast<int64_t>(from_ply->num_strands()), strands_read_back);
  for (size_t s = 0; s < from_ply->num_strands(); ++s)
    EXPECT_GE(from_ply->point_counts[s], 2) << "strand " << s << ": `fit` refuses a single point";
  for (const char* other : {"/strands.hair", "/strands.data"}) {
    auto read = ReadStrands(strands_dir + other);
    ASSERT_TRUE(read.ok()) << read.status().ToString();
    EXPECT_EQ(read->point_counts, from_ply->point_counts) << other;
    EXPECT_EQ(read->points_mm, from_ply->points_mm) << other;
  }
  FitOptions fit;
  fit.guides.num_guides = 60;
  FitSummary fitted;
  auto model = FitHairModel(*from_ply, fit, &fitted);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  std::printf(
      "fit of the reconstructed strands: %d guides, %.1f elements per guide, error mean %.3f mm, "
      "max %.3f mm\n",
      fitted.guides, fitted.mean_elements, fitted.mean_error_mm, fitted.max_error_mm);
  EXPECT_EQ(fitted.strands, strands_read_back);
  EXPECT_EQ(fitted.guides, 60);
  EXPECT_LT(fitted.mean_error_mm, 0.5);

  // The true strands given as the reconstruction's (its object frame is the
  // turntable frame here): the strand protocol scores them 1, on the same
  // true samples and visible surface as the points.
  auto true_strands = ReadStrands(truth->strands_file);
  ASSERT_TRUE(true_strands.ok()) << true_strands.status().ToString();
  fs::create_directories(dir + "/reconstruction/strands");
  ASSERT_TRUE(WriteStrands(dir + "/reconstruction/strands/strands.ply", *true_strands).ok());
  auto with_strands = EvaluateReconstruction(dir, {});
  ASSERT_TRUE(with_strands.ok()) << with_strands.status().ToString();
  ASSERT_TRUE(with_strands->strands.has_value());
  const StrandEvaluation& st = *with_strands->strands;
  std::printf("%s", st.BriefReport().c_str());
  EXPECT_EQ(st.strands, st.truth_strands);
  EXPECT_EQ(st.truth_samples, with_strands->truth_samples);
  ASSERT_TRUE(st.visible_truth_samples.has_value());
  EXPECT_EQ(*st.visible_truth_samples, with_strands->visible_truth_samples);
  for (const auto* scores :
       {&st.all.undirected, &st.all.directed, &st.visible.undirected, &st.visible.directed}) {
    ASSERT_EQ(scores->size(), 4u);
    for (const MatchScore& s : *scores) {
      EXPECT_GT(s.precision, 0.999);
      EXPECT_GT(s.recall, 0.999);
    }
  }
  EXPECT_GT(st.consistency, 0.99);
  ASSERT_TRUE(st.rooted_on_scalp_fraction.has_value());
  EXPECT_GT(*st.rooted_on_scalp_fraction, 0.9) << "the wig's roots lie on the scalp";
  EXPECT_NEAR(st.lengths.median_mm, st.truth_lengths.median_mm, 0.01);
  EXPECT_TRUE(with_strands->ToJson().contains("strands"));
  // In front of the true bare skin: the truth as the reconstruction scores
  // the truth's own share (near 0); a curtain hung in front of the face
  // scores mostly skin, from the views that see it over the face.
  ASSERT_TRUE(with_strands->strands_over_true_skin && with_strands->truth_over_true_skin);
  std::printf("in front of the true skin: %.2f %% (the truth's own %.2f %%)\n",
              100 * *with_strands->strands_over_true_skin,
              100 * *with_strands->truth_over_true_skin);
  EXPECT_NEAR(*with_strands->strands_over_true_skin, *with_strands->truth_over_true_skin, 1e-9);
  EXPECT_LT(*with_strands->truth_over_true_skin, 0.01);
  ASSERT_TRUE(truth->head.has_value());
  const HeadSpec& head = *truth->head;
  StrandSet face_curtain;
  for (int k = -20; k <= 20; ++k) {
    const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(head.scalp.face_dir);
    std::vector<Eigen::Vector3f> strand;
    for (double dz = 10; dz >= -60; dz -= 1) {
      const Eigen::Vector3d p = head.center_turntable_mm +
                                (head.radii_mm.maxCoeff() + 15) * head.scalp.face_dir +
                                1.5 * k * side + dz * Eigen::Vector3d::UnitZ();
      strand.push_back(p.cast<float>());
    }
    face_curtain.AddStrand(strand);
  }
  ASSERT_TRUE(WriteStrands(dir + "/reconstruction/strands/strands.ply", face_curtain).ok());
  auto with_curtain = EvaluateReconstruction(dir, {});
  ASSERT_TRUE(with_curtain.ok()) << with_curtain.status().ToString();
  ASSERT_TRUE(with_curtain->strands_over_true_skin.has_value());
  std::printf("a curtain in front of the face: %.1f %% in front of the true skin\n",
              100 * *with_curtain->strands_over_true_skin);
  EXPECT_GT(*with_curtain->strands_over_true_skin, 0.3);
}

}  // namespace
}  // namespace hairrig
