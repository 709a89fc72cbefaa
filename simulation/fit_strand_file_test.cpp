#include "simulation/fit_strand_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/strand_io.h"
#include "tests/support/strand_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

// Twelve curls in a strand file; its path.
std::string CurlsFile() {
  const StrandSet set = TwelveCurls();
  const std::string path = ::testing::TempDir() + "/fit_strand_file_curls.hair";
  EXPECT_TRUE(WriteStrands(path, set).ok());
  return path;
}

TEST(FitStrandFile, WritesTheModelInANewFolderWithItsSource) {
  const std::string dir = ::testing::TempDir() + "/fit_strand_file_out";
  fs::remove_all(dir);
  FitStrandFileOptions options;
  options.strands_file = CurlsFile();
  options.out_file = dir + "/simulation/model.json";
  options.fit.guides.num_guides = 4;
  const auto summary = FitStrandFile(options);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->fit.strands, 12);
  EXPECT_EQ(summary->fit.guides, 4);
  EXPECT_EQ(summary->ToJson()["out"], options.out_file);
  EXPECT_NE(summary->BriefReport().find("4 guides for 12 strands"), std::string::npos)
      << summary->BriefReport();
  const auto model = ReadHelixModel(options.out_file);
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  EXPECT_EQ(model->source, options.strands_file);
  EXPECT_EQ(model->guides.size(), 4u);
}

TEST(FitStrandFile, RefusesMoreGuidesThanStrandsAndBadOptions) {
  FitStrandFileOptions options;
  options.strands_file = CurlsFile();
  options.out_file = ::testing::TempDir() + "/fit_strand_file_refused.json";
  options.fit.guides.num_guides = 13;
  auto summary = FitStrandFile(options);
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("more than the 12 strands"), std::string::npos)
      << summary.status().ToString();
  EXPECT_FALSE(fs::exists(options.out_file));

  options.fit.guides.num_guides = -1;
  summary = FitStrandFile(options);
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("num_guides"), std::string::npos)
      << summary.status().ToString();
  options.fit.guides.num_guides = 0;
  options.fit.fitting.target_mean_error_mm = -1;
  summary = FitStrandFile(options);
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("target_mean_error_mm"), std::string::npos)
      << summary.status().ToString();
}

}  // namespace
}  // namespace hairrig
