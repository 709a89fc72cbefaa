#include "simulation/helix_model.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/file_util.h"

namespace hairrig {

namespace {
constexpr int kModelVersion = 1;

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

bool ReadVec(const nlohmann::json& j, const char* key, Eigen::Vector3d* out) {
  if (!j.contains(key) || !j[key].is_array() || j[key].size() != 3) return false;
  for (int i = 0; i < 3; ++i) {
    if (!j[key][static_cast<size_t>(i)].is_number()) return false;
    (*out)[i] = j[key][static_cast<size_t>(i)].get<double>();
  }
  return out->allFinite();
}
}  // namespace

Result<HelixModel> FitHairModel(const StrandSet& strands, const FitOptions& options, FitSummary* summary) {
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
  auto fit_range = [&](size_t begin, size_t end) {
    std::vector<Eigen::Vector3d> points;
    for (size_t k = begin; k < end; ++k) {
      const size_t g = static_cast<size_t>(selection.guide_strands[k]);
      points.clear();
      for (size_t i = offsets[g]; i < offsets[g + 1]; ++i) points.push_back(strands.points_mm[i].cast<double>());
      fitted[k] = FitFloatingTangents(points, options.fitting, &fits[k]);
    }
  };
  size_t threads = options.threads > 0 ? static_cast<size_t>(options.threads) : std::thread::hardware_concurrency();
  threads = std::clamp<size_t>(threads, 1, std::max<size_t>(1, count / 8));
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(fit_range, count * t / threads, count * (t + 1) / threads);
  fit_range(0, count / threads);
  for (std::thread& thread : pool) thread.join();
  double error_sum = 0, elements = 0;
  for (size_t k = 0; k < count; ++k) {
    if (!fitted[k].ok()) return fitted[k].status().WithContext("strand " + std::to_string(selection.guide_strands[k]));
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
  HR_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(path));
  const nlohmann::json j = nlohmann::json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (!j.is_object() || j.value("format", "") != "hairrig-helix-model") {
    return CorruptData(path + ": not a hairrig helix model (made by `hairrig fit`)");
  }
  if (j.value("version", 0) != kModelVersion) {
    return CorruptData(path + ": model version " + std::to_string(j.value("version", 0)) + ", this build reads version " +
                       std::to_string(kModelVersion) + ": fit the strands again with this build");
  }
  HelixModel model;
  model.source = j.value("source", "");
  if (!j.contains("guides") || !j["guides"].is_array()) return CorruptData(path + ": field 'guides' is missing");
  for (size_t g = 0; g < j["guides"].size(); ++g) {
    const auto& guide = j["guides"][g];
    const std::string where = path + ": guides[" + std::to_string(g) + "]";
    if (!guide.contains("elements") || !guide["elements"].is_array() || guide["elements"].empty()) {
      return CorruptData(where + ".elements is missing or empty");
    }
    PiecewiseHelix helix;
    for (size_t k = 0; k < guide["elements"].size(); ++k) {
      const auto& e = guide["elements"][k];
      HelixElement element;
      const bool ok = ReadVec(e, "start_mm", &element.start_mm) && ReadVec(e, "start_tangent", &element.start_tangent) &&
                      ReadVec(e, "darboux_per_mm", &element.darboux_per_mm) && e.contains("length_mm") &&
                      e["length_mm"].is_number() && e["length_mm"].get<double>() > 0;
      if (!ok || std::abs(element.start_tangent.norm() - 1) > 1e-6) {
        return CorruptData(where + ".elements[" + std::to_string(k) +
                           "]: needs finite start_mm, unit start_tangent, darboux_per_mm and a positive length_mm");
      }
      element.length_mm = e["length_mm"].get<double>();
      helix.elements.push_back(element);
    }
    model.guides.push_back(std::move(helix));
    model.guide_strands.push_back(guide.value("strand", -1));
  }
  model.cluster_of_strand = j.value("cluster_of_strand", std::vector<int>{});
  return model;
}

}  // namespace hairrig
