#include "simulation/helix_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/json_file.h"
#include "core/parallel.h"

namespace hairrig {

namespace {
constexpr int kModelVersion = 1;

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

constexpr int64_t kMaxIndex = std::numeric_limits<int>::max();

// Errors are recorded in `e` (JsonObject).
HelixElement ElementFromJson(const JsonObject& e) {
  HelixElement element;
  element.start_mm = Vector3Field(e, "start_mm");
  element.start_tangent = Vector3Field(e, "start_tangent");
  element.darboux_per_mm = Vector3Field(e, "darboux_per_mm");
  element.length_mm = e.Number("length_mm", {.min = 0});
  if (e.ok() && !(element.length_mm > 0)) e.Fail("length_mm", "must be positive");
  if (e.ok() && std::abs(element.start_tangent.norm() - 1) > 1e-6)
    e.Fail("start_tangent", "is not a unit vector");
  return element;
}
}  // namespace

Status FitOptions::Check() const {
  HR_RETURN_IF_ERROR(guides.Check().WithContext("guides"));
  HR_RETURN_IF_ERROR(fitting.Check().WithContext("fitting"));
  if (threads < 0) return InvalidArgument("threads must be 0 (one per core) or more");
  return Status::Ok();
}

Result<HelixModel> FitHairModel(const StrandSet& strands, const FitOptions& options,
                                FitSummary* summary) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("fit"));
  const auto t0 = std::chrono::steady_clock::now();
  HR_ASSIGN_OR_RETURN(GuideSelection selection, SelectGuides(strands, options.guides));
  HelixModel model;
  model.guide_strands = selection.guide_strands;
  model.cluster_of_strand = selection.cluster_of_strand;
  FitSummary s;
  s.strands = static_cast<int>(strands.num_strands());
  s.guides = static_cast<int>(selection.guide_strands.size());
  s.guide_rms_mm = selection.rms_error_mm;
  const auto offsets = strands.Offsets();
  // Guides are fitted independently: spread over threads, gathered in order.
  const size_t count = selection.guide_strands.size();
  std::vector<Result<PiecewiseHelix>> fitted(count, Result<PiecewiseHelix>(Internal("not fitted")));
  std::vector<StrandFitSummary> fits(count);
  // At most one thread per 8 guides.
  const int threads =
      std::min(ResolveThreads(options.threads), std::max(1, static_cast<int>(count / 8)));
  ParallelFor(count, threads, [&] {
    return [&, points = std::vector<Eigen::Vector3d>()](size_t k) mutable {
      const size_t g = static_cast<size_t>(selection.guide_strands[k]);
      points.clear();
      for (size_t i = offsets[g]; i < offsets[g + 1]; ++i)
        points.push_back(strands.points_mm[i].cast<double>());
      fitted[k] = FitFloatingTangents(points, options.fitting, &fits[k]);
    };
  });
  double error_sum = 0, elements = 0;
  for (size_t k = 0; k < count; ++k) {
    if (!fitted[k].ok())
      return fitted[k].status().WithContext("strand " + std::to_string(selection.guide_strands[k]));
    model.guides.push_back(std::move(fitted[k]).value());
    const StrandFitSummary& fit = fits[k];
    error_sum += fit.mean_error_mm;
    elements += fit.elements;
    s.max_error_mm = std::max(s.max_error_mm, fit.max_error_mm);
    s.max_g1_defect_deg = std::max(s.max_g1_defect_deg, fit.max_g1_defect_deg);
    s.max_cohelical_residual = std::max(s.max_cohelical_residual, fit.max_cohelical_residual);
    s.max_relaxation_elements = std::max(s.max_relaxation_elements, fit.max_relaxation_elements);
  }
  s.mean_error_mm = error_sum / s.guides;
  s.mean_elements = elements / s.guides;
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (summary) *summary = s;
  return model;
}

Status WriteHelixModel(const std::string& path, const HelixModel& model, const FitSummary& s) {
  nlohmann::json guides = nlohmann::json::array();
  for (size_t g = 0; g < model.guides.size(); ++g) {
    nlohmann::json elements = nlohmann::json::array();
    for (const auto& e : model.guides[g].elements) {
      elements.push_back({{"start_mm", Vec(e.start_mm)},
                          {"start_tangent", Vec(e.start_tangent)},
                          {"darboux_per_mm", Vec(e.darboux_per_mm)},
                          {"length_mm", e.length_mm},
                          {"curvature_per_mm", e.curvature_per_mm()},
                          {"torsion_per_mm", e.torsion_per_mm()}});
    }
    guides.push_back({{"strand", model.guide_strands[g]}, {"elements", elements}});
  }
  const nlohmann::json j = {{"format", "hairrig-helix-model"},
                            {"version", kModelVersion},
                            {"source", model.source},
                            {"guides", guides},
                            {"cluster_of_strand", model.cluster_of_strand},
                            {"summary",
                             {{"strands", s.strands},
                              {"guides", s.guides},
                              {"guide_rms_mm", s.guide_rms_mm},
                              {"mean_elements", s.mean_elements},
                              {"mean_error_mm", s.mean_error_mm},
                              {"max_error_mm", s.max_error_mm},
                              {"max_g1_defect_deg", s.max_g1_defect_deg},
                              {"max_relaxation_elements", s.max_relaxation_elements}}}};
  return WriteFileAtomic(path, j.dump(1) + "\n");
}

Result<HelixModel> ReadHelixModel(const std::string& path) {
  HR_ASSIGN_OR_RETURN(const nlohmann::json j,
                      ReadJsonFile(path, "give a model written by `hairrig fit`"));
  const JsonObject root(j, path);
  if (root.StringOr("format", "") != "hairrig-helix-model" || !root.ok()) {
    return CorruptData(path + ": not a hairrig helix model (made by `hairrig fit`)");
  }
  const int64_t version = root.Integer("version");
  if (root.ok() && version != kModelVersion) {
    return CorruptData(path + ": model version " + std::to_string(version) +
                       ", this build reads version " + std::to_string(kModelVersion) +
                       ": fit the strands again with this build");
  }
  HelixModel model;
  model.source = root.StringOr("source", "");
  for (const JsonObject& guide : root.Objects("guides")) {
    PiecewiseHelix helix;
    const std::vector<JsonObject> elements = guide.Objects("elements");
    if (elements.empty()) guide.Fail("elements", "is empty");
    for (const JsonObject& e : elements) helix.elements.push_back(ElementFromJson(e));
    model.guides.push_back(std::move(helix));
    model.guide_strands.push_back(
        static_cast<int>(guide.IntegerOr("strand", -1, {.min = -1, .max = kMaxIndex})));
    if (!root.ok()) break;
  }
  for (int64_t g : root.IntegersOr(
           "cluster_of_strand", {.min = -1, .max = static_cast<int64_t>(model.guides.size()) - 1}))
    model.cluster_of_strand.push_back(static_cast<int>(g));
  HR_RETURN_IF_ERROR(root.status());
  return model;
}

}  // namespace hairrig
