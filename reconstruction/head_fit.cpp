#include "reconstruction/head_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <unordered_map>

#include "core/image_file.h"
#include "core/parallel.h"
#include "core/transform.h"
#include "reconstruction/hair_segmentation.h"
#include "reconstruction/visual_hull.h"

namespace hairrig {

namespace {

struct SurfaceSample {
  Eigen::Vector3d p;
  bool skin = false;
};

// The distance from p to the ellipsoid (centre c, radii r, axis-aligned)
// along the ray from its centre: positive outside, negative inside. Exact on
// a sphere, within the radii's ratio elsewhere; smooth away from the centre.
template <typename T>
T RadialDistance(const T* c, const T* r, const Eigen::Vector3d& p) {
  const T q0 = T(p.x()) - c[0], q1 = T(p.y()) - c[1], q2 = T(p.z()) - c[2];
  const T length = ceres::sqrt(q0 * q0 + q1 * q1 + q2 * q2);
  const T scaled = ceres::sqrt((q0 / r[0]) * (q0 / r[0]) + (q1 / r[1]) * (q1 / r[1]) +
                               (q2 / r[2]) * (q2 / r[2]));
  return length - length / scaled;
}

// A surface sample lies outside the head.
struct OutsideResidual {
  Eigen::Vector3d p;
  double scale_mm;
  template <typename T>
  bool operator()(const T* c, const T* r, T* residual) const {
    const T d = RadialDistance(c, r, p);
    residual[0] = d < T(0) ? d / T(scale_mm) : T(0);
    return true;
  }
};

// A skin sample lies on the head, a hair sample near it (robustly: the loss
// function's job).
struct SkinResidual {
  Eigen::Vector3d p;
  double scale_mm;
  template <typename T>
  bool operator()(const T* c, const T* r, T* residual) const {
    residual[0] = RadialDistance(c, r, p) / T(scale_mm);
    return true;
  }
};

struct RadiiPrior {
  Eigen::Vector3d typical_mm;
  double weight;  // 1 / sigma, times sqrt(the samples it stands for)
  template <typename T>
  bool operator()(const T* r, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (r[i] - T(typical_mm[i])) * T(weight);
    return true;
  }
};

// Head or hair is the subject; the box is carved like the backdrop, so that
// no skin pixel's ray stops on the box's volume (HeadFitOptions::
// max_empty_views tolerates the few views where the box hides part of the head).
std::vector<SilhouetteView> Silhouettes(const std::vector<HeadFitView>& views) {
  std::vector<SilhouetteView> silhouettes;
  for (const HeadFitView& v : views) {
    cv::Mat1b s(v.label.size(), uint8_t{kSilhouetteEmpty});
    s.setTo(kSilhouetteSubject, (v.label == kSegHead) | (v.label == kSegHair));
    silhouettes.push_back({v.camera, v.cam_from_object, s});
  }
  return silhouettes;
}

// One view's head and hair pixels on the hull's front surface, each with its label.
std::vector<SurfaceSample> CastOntoHull(const VisualHull& hull, const HeadFitView& v, int stride) {
  const cv::Mat region = (v.label == kSegHead) | (v.label == kSegHair);
  const cv::Mat1f depth = HullDepthMap(hull, v.camera, v.cam_from_object, region, stride);
  const Rigid3d object_from_cam = v.cam_from_object.Inverse();
  std::vector<SurfaceSample> samples;
  for (int y = 0; y < depth.rows; y += stride) {
    for (int x = 0; x < depth.cols; x += stride) {
      const float z = depth(y, x);
      if (!(z > 0)) continue;
      const Result<Eigen::Vector2d> n = UndistortPixel(v.camera, Eigen::Vector2d(x, y));
      if (!n.ok()) continue;
      samples.push_back({object_from_cam * (z * Eigen::Vector3d(n->x(), n->y(), 1.0)),
                         v.label(y, x) == kSegHead});
    }
  }
  return samples;
}

// The views' samples pooled per cell: the mean position, skin where more of
// the samples in it are skin than hair (a tie is hair).
std::vector<SurfaceSample> PoolSamples(const std::vector<std::vector<SurfaceSample>>& per_view,
                                       double cell_mm) {
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int skin = 0, hair = 0;
  };
  std::unordered_map<int64_t, Cell> cells;
  for (const auto& samples : per_view) {
    for (const SurfaceSample& s : samples) {
      const Eigen::Vector3i k = (s.p / cell_mm).array().floor().cast<int>();
      const int64_t key = ((int64_t{k.x()} + (1 << 20)) << 42) |
                          ((int64_t{k.y()} + (1 << 20)) << 21) | (int64_t{k.z()} + (1 << 20));
      Cell& cell = cells[key];
      cell.sum += s.p;
      (s.skin ? cell.skin : cell.hair) += 1;
    }
  }
  std::vector<SurfaceSample> pooled;
  pooled.reserve(cells.size());
  for (const auto& [key, cell] : cells)
    pooled.push_back({cell.sum / (cell.skin + cell.hair), cell.skin > cell.hair});
  std::sort(pooled.begin(), pooled.end(), [](const SurfaceSample& a, const SurfaceSample& b) {
    return std::tie(a.p.x(), a.p.y(), a.p.z()) < std::tie(b.p.x(), b.p.y(), b.p.z());
  });
  return pooled;
}

double Cauchy(double x) { return std::log1p(x * x); }
double Huber(double x, double k) {
  const double a = std::abs(x);
  return a <= k ? a * a : 2 * k * a - k * k;
}

// The fit's cost at (c, r) over `samples` (the same terms as the solver's,
// without the prior).
double FitCost(const Eigen::Vector3d& c, const Eigen::Vector3d& r,
               const std::vector<SurfaceSample>& samples, const HeadFitOptions& o) {
  double cost = 0;
  const double huber = o.outside_huber_mm / o.outside_scale_mm;
  for (const SurfaceSample& s : samples) {
    const double d = RadialDistance(c.data(), r.data(), s.p);
    if (d < 0) cost += Huber(d / o.outside_scale_mm, huber);
    if (s.skin)
      cost += Cauchy(d / o.skin_scale_mm);
    else
      cost += o.hair_weight * Cauchy(d / o.hair_scale_mm);
  }
  return cost;
}

// The typical radii with the face along `face_axis` (0 = x, 1 = y).
Eigen::Vector3d TypicalRadii(const HeadFitOptions& o, int face_axis) {
  Eigen::Vector3d r = o.typical_radii_mm;
  if (face_axis == 0) std::swap(r.x(), r.y());
  return r;
}

struct Start {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double cost = std::numeric_limits<double>::infinity();
};

// Whether a typical head centred at c could carry the skin: c lies inside the
// hull (the head is part of the subject) and within the largest typical
// radius of a skin sample. Elsewhere (empty space, the calibration box, which
// the hull keeps) an ellipsoid contradicts no sample and the skin's
// saturating loss hardly grows with the distance, so the fit would settle there.
bool PlausibleCentre(const Eigen::Vector3d& c, const std::vector<SurfaceSample>& subset,
                     const VisualHull& hull, const HeadFitOptions& o) {
  if (!hull.OccupiedAt(c)) return false;
  const double reach = o.typical_radii_mm.maxCoeff();
  for (const SurfaceSample& s : subset)
    if (s.skin && (s.p - c).squaredNorm() <= reach * reach) return true;
  return false;
}

// The best plausible centre on the grid lo + k * grid_mm (k up to n along
// each axis), with the typical radii for the face along `face_axis` times
// radii_scale.
Start SearchGrid(const std::vector<SurfaceSample>& subset, const VisualHull& hull,
                 const HeadFitOptions& o, int face_axis, double radii_scale,
                 const Eigen::Vector3d& lo, const Eigen::Vector3i& n, double grid_mm) {
  const Eigen::Vector3d radii = radii_scale * TypicalRadii(o, face_axis);
  const size_t count = static_cast<size_t>(n.x()) * n.y() * n.z();
  std::vector<Start> best(count);
  ParallelFor(count, o.threads, [&] {
    return [&](size_t i) {
      const int ix = static_cast<int>(i % n.x()), iy = static_cast<int>(i / n.x() % n.y()),
                iz = static_cast<int>(i / n.x() / n.y());
      const Eigen::Vector3d c = lo + grid_mm * Eigen::Vector3d(ix, iy, iz);
      if (PlausibleCentre(c, subset, hull, o)) best[i] = {c, FitCost(c, radii, subset, o)};
    };
  });
  return *std::min_element(best.begin(), best.end(),
                           [](const Start& a, const Start& b) { return a.cost < b.cost; });
}

// The best centre within a typical head's radius of the skin: a 20 mm grid
// with radii shrunk to 3/4 (so that a centre up to half a cell off the head's
// does not push the ellipsoid out through the hair), then a 5 mm grid with
// the typical radii around its best.
Start SearchCentre(const std::vector<SurfaceSample>& samples, const VisualHull& hull,
                   const HeadFitOptions& o, int face_axis) {
  std::vector<SurfaceSample> subset;
  const size_t step = std::max<size_t>(1, samples.size() / 3000);
  for (size_t i = 0; i < samples.size(); i += step) subset.push_back(samples[i]);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e18), hi = -lo;
  for (const SurfaceSample& s : samples) {
    if (!s.skin) continue;
    lo = lo.cwiseMin(s.p);
    hi = hi.cwiseMax(s.p);
  }
  const double margin = o.typical_radii_mm.maxCoeff();
  lo -= Eigen::Vector3d::Constant(margin);
  hi += Eigen::Vector3d::Constant(margin);
  const double coarse_mm = 20.0, fine_mm = 5.0;
  const Start coarse =
      SearchGrid(subset, hull, o, face_axis, 0.75, lo,
                 ((hi - lo) / coarse_mm).array().ceil().cast<int>() + 1, coarse_mm);
  const Eigen::Vector3d fine_lo = coarse.centre - Eigen::Vector3d::Constant(coarse_mm);
  return SearchGrid(subset, hull, o, face_axis, 1.0, fine_lo,
                    Eigen::Vector3i::Constant(2 * coarse_mm / fine_mm + 1), fine_mm);
}

// Returns the final cost (prior included); infinity when the solver found no
// usable solution.
double SolveEllipsoid(const std::vector<SurfaceSample>& samples, const HeadFitOptions& o,
                      const Eigen::Vector3d& typical, Eigen::Vector3d* centre,
                      Eigen::Vector3d* radii) {
  ceres::Problem problem;
  double* c = centre->data();
  double* r = radii->data();
  // Each loss is shared by its residual blocks; the problem deletes it once.
  // Held here until its first block, so that an unused one is freed too.
  auto outside_loss = std::make_unique<ceres::HuberLoss>(o.outside_huber_mm / o.outside_scale_mm);
  auto skin_loss = std::make_unique<ceres::CauchyLoss>(1.0);
  auto hair_loss = std::make_unique<ceres::ScaledLoss>(new ceres::CauchyLoss(1.0), o.hair_weight,
                                                       ceres::TAKE_OWNERSHIP);
  ceres::LossFunction *outside = outside_loss.release(), *skin = skin_loss.get(),
                      *hair = hair_loss.get();
  for (const SurfaceSample& s : samples) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OutsideResidual, 1, 3, 3>(
                                 new OutsideResidual{s.p, o.outside_scale_mm}),
                             outside, c, r);
    const double scale = s.skin ? o.skin_scale_mm : o.hair_scale_mm;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<SkinResidual, 1, 3, 3>(new SkinResidual{s.p, scale}),
        s.skin ? skin : hair, c, r);
    if (s.skin) {
      skin_loss.release();
    } else {
      hair_loss.release();
    }
  }
  const double weight = std::sqrt(o.prior_samples) / o.radii_sigma_mm;
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<RadiiPrior, 3, 3>(new RadiiPrior{typical, weight}), nullptr,
      r);
  for (int i = 0; i < 3; ++i) problem.SetParameterLowerBound(r, i, 0.3 * typical[i]);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 100;
  solver.num_threads = std::max(1, o.threads);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  const bool usable = summary.IsSolutionUsable() && std::isfinite(summary.final_cost) &&
                      centre->allFinite() && radii->allFinite();
  return usable ? summary.final_cost : std::numeric_limits<double>::infinity();
}

// The skin samples within skin_scale_mm of the fitted ellipsoid.
std::vector<Eigen::Vector3d> SkinOnHead(const std::vector<SurfaceSample>& samples,
                                        const HeadSpec& head, double within_mm) {
  std::vector<Eigen::Vector3d> on;
  for (const SurfaceSample& s : samples) {
    if (!s.skin) continue;
    const double d = RadialDistance(head.center_turntable_mm.data(), head.radii_mm.data(), s.p);
    if (std::abs(d) <= within_mm) on.push_back(s.p);
  }
  return on;
}

// The face: the horizontal mean direction of the skin on the head above half
// its height radius below the centre (the face; the ears cancel out). False when it is too weak to
// say.
bool FaceDirection(const std::vector<Eigen::Vector3d>& skin, const HeadSpec& head,
                   Eigen::Vector3d* face) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (const Eigen::Vector3d& p : skin) {
    Eigen::Vector3d d = p - head.center_turntable_mm;
    if (d.z() < -0.5 * head.radii_mm.z()) continue;
    d.z() = 0;
    if (d.norm() < 1e-9) continue;
    sum += d.normalized();
    ++count;
  }
  if (count == 0 || sum.norm() < 0.2 * count) return false;
  *face = sum.normalized();
  return true;
}

void FitScalp(const std::vector<SurfaceSample>& samples, const HeadFitOptions& o,
              HeadFitSummary* summary) {
  HeadSpec& head = summary->head;
  ScalpSpec& scalp = head.scalp;
  scalp = ScalpSpec{};
  scalp.defined = true;
  scalp.parting = false;
  scalp.center_turntable_mm = head.center_turntable_mm;
  const std::vector<Eigen::Vector3d> skin = SkinOnHead(samples, head, o.skin_scale_mm);
  summary->skin_on_surface_share =
      summary->skin_samples > 0
          ? static_cast<double>(skin.size()) / static_cast<double>(summary->skin_samples)
          : 0;
  summary->face_measured = FaceDirection(skin, head, &scalp.face_dir);
}

}  // namespace

double EllipsoidRadialDistance(const HeadSpec& head, const Eigen::Vector3d& p) {
  return RadialDistance(head.center_turntable_mm.data(), head.radii_mm.data(), p);
}

Status HeadFitOptions::Check() const {
  if (!(voxel_mm >= 0.5 && voxel_mm <= 20))
    return InvalidArgument("head fit voxel_mm must be in [0.5, 20]");
  if (stride_px < 1) return InvalidArgument("head fit stride_px must be at least 1");
  if (max_empty_views < 0) return InvalidArgument("head fit max_empty_views must not be negative");
  if (!(skin_scale_mm > 0) || !(outside_scale_mm > 0) || !(outside_huber_mm > 0))
    return InvalidArgument(
        "head fit skin_scale_mm, outside_scale_mm and outside_huber_mm must be "
        "positive");
  if (!(typical_radii_mm.minCoeff() > 10) || !typical_radii_mm.allFinite())
    return InvalidArgument("head fit typical_radii_mm must be over 10 mm each");
  if (!(radii_sigma_mm > 0)) return InvalidArgument("head fit radii_sigma_mm must be positive");
  if (!(prior_samples >= 0)) return InvalidArgument("head fit prior_samples must not be negative");
  if (min_skin_samples < 1) return InvalidArgument("head fit min_skin_samples must be at least 1");
  return Status::Ok();
}

Result<HeadFitSummary> FitHeadToViews(const std::vector<HeadFitView>& views,
                                      const HeadFitOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  if (views.size() < 2) return InvalidArgument("the head fit needs at least two views");
  for (size_t i = 0; i < views.size(); ++i) {
    const HeadFitView& v = views[i];
    if (v.label.cols != v.camera.width_px || v.label.rows != v.camera.height_px)
      return InvalidArgument("head fit: view " + std::to_string(i) + "'s labels are " +
                             std::to_string(v.label.cols) + " x " + std::to_string(v.label.rows) +
                             ", its camera " + std::to_string(v.camera.width_px) + " x " +
                             std::to_string(v.camera.height_px));
  }
  VisualHullOptions hull_options;
  hull_options.voxel_mm = o.voxel_mm;
  hull_options.threads = o.threads;
  hull_options.max_empty_views = o.max_empty_views;
  HR_ASSIGN_OR_RETURN(const VisualHull hull, CarveVisualHull(Silhouettes(views), hull_options));

  std::vector<std::vector<SurfaceSample>> per_view(views.size());
  ParallelFor(views.size(), o.threads, [&] {
    return [&](size_t i) { per_view[i] = CastOntoHull(hull, views[i], o.stride_px); };
  });
  const std::vector<SurfaceSample> samples = PoolSamples(per_view, o.voxel_mm);

  HeadFitSummary summary;
  summary.views = static_cast<int>(views.size());
  for (const SurfaceSample& s : samples) ++(s.skin ? summary.skin_samples : summary.hair_samples);
  if (summary.skin_samples < o.min_skin_samples) {
    return FailedPrecondition("the views show " + std::to_string(summary.skin_samples) +
                              " cells of skin (head) where the head fit needs " +
                              std::to_string(o.min_skin_samples) +
                              ": give the subject's head instead");
  }
  // The face along x or along y: each searched and solved, the cheaper kept.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), radii = o.typical_radii_mm;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int face_axis : {0, 1}) {
    const Eigen::Vector3d typical = TypicalRadii(o, face_axis);
    const Start start = SearchCentre(samples, hull, o, face_axis);
    if (!std::isfinite(start.cost)) continue;
    Eigen::Vector3d c = start.centre, r = typical;
    double cost = SolveEllipsoid(samples, o, typical, &c, &r);
    if (!PlausibleCentre(c, samples, hull, o)) cost = std::numeric_limits<double>::infinity();
    if (cost < best_cost) {
      best_cost = cost;
      centre = c;
      radii = r;
    }
  }
  if (!std::isfinite(best_cost))
    return FailedPrecondition(
        "the head fit found no ellipsoid centred inside the subject's hull that the solver could "
        "settle; give the subject's head instead");
  summary.head.center_turntable_mm = centre;
  summary.head.radii_mm = radii;

  int64_t inside = 0;
  for (const SurfaceSample& s : samples)
    inside += RadialDistance(centre.data(), radii.data(), s.p) < -2 * o.voxel_mm;
  summary.inside_share = static_cast<double>(inside) / static_cast<double>(samples.size());
  FitScalp(samples, o, &summary);
  return summary;
}

Result<HeadFitSummary> FitHeadToReconstruction(const std::vector<ReconstructionView>& views,
                                               const std::string& reconstruction_dir,
                                               const HeadFitOptions& options) {
  std::vector<HeadFitView> labelled;
  for (const ReconstructionView& v : views) {
    const std::string path = reconstruction_dir + "/masks/" + v.name + "_label.png";
    Result<cv::Mat> read = ReadImageFile(path, cv::IMREAD_UNCHANGED);
    if (read.status().code() == StatusCode::kNotFound) continue;
    HR_ASSIGN_OR_RETURN(const cv::Mat label, std::move(read));
    if (label.type() != CV_8UC1 || label.cols != v.camera.width_px ||
        label.rows != v.camera.height_px)
      return CorruptData(path + " is not an 8-bit label image of its camera's size (" +
                         std::to_string(v.camera.width_px) + " x " +
                         std::to_string(v.camera.height_px) + ")");
    labelled.push_back({v.camera, v.cam_from_object, label});
  }
  if (labelled.size() < 2)
    return NotFound("the head fit found labels for " + std::to_string(labelled.size()) +
                    " view(s) in " + reconstruction_dir +
                    "/masks and needs two: run the points stage first");
  return FitHeadToViews(labelled, options);
}

nlohmann::json HeadFitSummary::ToJson() const {
  const ScalpSpec& s = head.scalp;
  const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  return {{"center_mm", vec(head.center_turntable_mm)},
          {"radii_mm", vec(head.radii_mm)},
          {"face_dir", vec(s.face_dir)},
          {"face_measured", face_measured},
          {"hairline_deg",
           {{"front", s.hairline_front_deg},
            {"temple", s.hairline_temple_deg},
            {"ear", s.hairline_ear_deg},
            {"nape", s.hairline_nape_deg}}},
          {"views", views},
          {"skin_samples", skin_samples},
          {"hair_samples", hair_samples},
          {"skin_on_surface_share", skin_on_surface_share},
          {"inside_share", inside_share}};
}

std::string HeadFitSummary::BriefReport() const {
  const ScalpSpec& s = head.scalp;
  std::ostringstream out;
  out.precision(3);
  const auto vec = [](const Eigen::Vector3d& v) {
    std::ostringstream o;
    o.precision(4);
    o << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return o.str();
  };
  out << "head fitted to the skin of " << views << " views: ellipsoid centre "
      << vec(head.center_turntable_mm) << " mm, radii " << vec(head.radii_mm) << " mm\n"
      << "  " << skin_samples << " skin and " << hair_samples << " hair surface cells; "
      << 100 * skin_on_surface_share << " % of the skin on the ellipsoid, " << 100 * inside_share
      << " % of the cells inside it\n"
      << "  face towards " << vec(s.face_dir) << (face_measured ? "" : " (default)")
      << "; a typical hairline (front " << s.hairline_front_deg << ", temple "
      << s.hairline_temple_deg << ", ear " << s.hairline_ear_deg << ", nape " << s.hairline_nape_deg
      << " deg), no parting\n";
  return out.str();
}

}  // namespace hairrig
