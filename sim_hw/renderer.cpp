#include "sim_hw/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <opencv2/core.hpp>

#include "sim_hw/render_support.h"
#include "sim_hw/tag_texture.h"
#include "sim_hw/wig.h"

namespace hairrig {
namespace {
using render_support::HashPixel;
using render_support::kEdgeSamples;
using render_support::NoiseSource;
using render_support::RayTable;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kTagBlackAlbedo = 0.04;
constexpr double kWhiteAlbedo = 0.85;
constexpr uint8_t kSurfaceBackdrop = 0, kSurfaceHead = 1, kSurfaceFace0 = 2;

struct FaceTag {
  const BoxTag* tag;
  TagPattern pattern;
};

struct BoxHit {
  bool hit = false;
  int face = -1;
  double albedo = 0;
  double z = 0;  // camera-frame depth (mm)
  int Class() const { return hit ? face * 2 + (albedo > 0.5 ? 1 : 0) : -1; }
};

}  // namespace

struct Renderer::Impl {
  Scene scene;
  StrandSet strands;
  std::vector<RayTable> ray_tables;
  std::vector<std::vector<FaceTag>> face_tags;  // per box face

  // Everything one Render call needs, derived from the view.
  struct View {
    const SceneCamera* camera = nullptr;
    const RayTable* rays = nullptr;
    Rigid3d cam_from_world, cam_from_turntable, box_from_cam;
    std::vector<double> light_power;                 // level * intensity per light
    std::vector<Eigen::Vector3d> light_pos_cam;
    double ambient = 0;
    int width = 0, height = 0;
    cv::Mat3f radiance;
    cv::Mat1f depth;
    cv::Mat1b surface;
    cv::Mat1f hair_alpha;
  };

  double Irradiance(const View& v, const Eigen::Vector3d& p_cam, const Eigen::Vector3d& n_cam) const {
    double e = v.ambient;
    for (size_t i = 0; i < v.light_power.size(); ++i) {
      const Eigen::Vector3d l = (v.light_pos_cam[i] - p_cam).normalized();
      e += v.light_power[i] * std::max(0.0, n_cam.dot(l));
    }
    return e;
  }

  void DrawBackdrop(View& v) const {
    double total = v.ambient;
    for (double p : v.light_power) total += 0.5 * p;
    for (int y = 0; y < v.height; ++y) {
      // A gentle vertical falloff, as a lit backdrop shows.
      const double shade = total * (0.85 + 0.15 * (1.0 - static_cast<double>(y) / v.height));
      const cv::Vec3f c(static_cast<float>(scene.backdrop_albedo.z() * shade), static_cast<float>(scene.backdrop_albedo.y() * shade),
                        static_cast<float>(scene.backdrop_albedo.x() * shade));
      for (int x = 0; x < v.width; ++x) v.radiance(y, x) = c;
    }
  }

  // Bounding rectangle (pixels) of camera-frame points, clipped to the image;
  // empty if any point is behind the camera.
  cv::Rect ProjectedBounds(const View& v, const std::vector<Eigen::Vector3d>& points_cam, int margin) const {
    double u0 = 1e30, v0 = 1e30, u1 = -1e30, v1 = -1e30;
    for (const auto& p : points_cam) {
      Eigen::Vector2d uv;
      if (!ProjectChecked(v.camera->intrinsics, p, &uv)) return {};
      u0 = std::min(u0, uv.x()), u1 = std::max(u1, uv.x());
      v0 = std::min(v0, uv.y()), v1 = std::max(v1, uv.y());
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(u0)) - margin);
    const int y0 = std::max(0, static_cast<int>(std::floor(v0)) - margin);
    const int x1 = std::min(v.width - 1, static_cast<int>(std::ceil(u1)) + margin);
    const int y1 = std::min(v.height - 1, static_cast<int>(std::ceil(v1)) + margin);
    if (x1 < x0 || y1 < y0) return {};
    return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  }

  std::vector<Eigen::Vector3d> BoxCorners(const Rigid3d& cam_from_frame, const Eigen::Vector3d& center,
                                          const Eigen::Vector3d& half) const {
    std::vector<Eigen::Vector3d> corners;
    for (const Eigen::Vector3d& p : BoxCornerPoints(half)) corners.push_back(cam_from_frame * (center + p));
    return corners;
  }

  void DrawHead(View& v) const {
    const SceneHead& head = scene.head;
    const Eigen::Matrix3d r = v.cam_from_turntable.RotationMatrix();
    const Eigen::Vector3d c_cam = v.cam_from_turntable * head.center_turntable_mm;
    const Eigen::Matrix3d a = r * head.radii_mm.asDiagonal();  // unit sphere -> camera
    const Eigen::Matrix3d m = a.inverse();
    const cv::Rect rect = ProjectedBounds(v, BoxCorners(v.cam_from_turntable, head.center_turntable_mm, head.radii_mm), 2);
    const Eigen::Vector3d mc = m * c_cam;
    for (int y = rect.y; y < rect.y + rect.height; ++y) {
      for (int x = rect.x; x < rect.x + rect.width; ++x) {
        const Eigen::Vector3d d = v.rays->Ray(x, y);
        const Eigen::Vector3d md = m * d;
        const double qa = md.squaredNorm(), qb = -2.0 * md.dot(mc), qc = mc.squaredNorm() - 1.0;
        const double disc = qb * qb - 4 * qa * qc;
        if (disc < 0) continue;
        const double t = (-qb - std::sqrt(disc)) / (2 * qa);
        if (t <= 0 || t * d.z() >= v.depth(y, x)) continue;
        const Eigen::Vector3d p = t * d;
        const Eigen::Vector3d n = (m.transpose() * (m * (p - c_cam))).normalized();
        const double e = Irradiance(v, p, n);
        v.radiance(y, x) = cv::Vec3f(static_cast<float>(head.albedo.z() * e), static_cast<float>(head.albedo.y() * e),
                                     static_cast<float>(head.albedo.x() * e));
        v.depth(y, x) = static_cast<float>(t * d.z());
        v.surface(y, x) = kSurfaceHead;
      }
    }
  }

  BoxHit CastBox(const View& v, double u, double w, const Eigen::Vector3d& half) const {
    const Eigen::Vector3d d_cam = v.rays->Ray(u, w);
    const Eigen::Vector3d o = v.box_from_cam.translation;
    const Eigen::Vector3d d = v.box_from_cam.rotation * d_cam;
    double t_near = -1e30, t_far = 1e30;
    int axis = -1;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(d[k]) < 1e-15) {
        if (std::abs(o[k]) > half[k]) return {};
        continue;
      }
      double t0 = (-half[k] - o[k]) / d[k], t1 = (half[k] - o[k]) / d[k];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_near) t_near = t0, axis = k;
      t_far = std::min(t_far, t1);
    }
    if (axis < 0 || t_near > t_far || t_near <= 0) return {};
    const Eigen::Vector3d p = o + t_near * d;
    BoxHit hit;
    hit.hit = true;
    hit.face = 2 * axis + (d[axis] > 0 ? 1 : 0);  // entering through the face whose normal opposes d
    hit.z = t_near * d_cam.z();
    hit.albedo = kWhiteAlbedo;
    const BoxFace& face = scene.box.faces[static_cast<size_t>(hit.face)];
    const Eigen::Vector3d rel = p - face.center_box_mm;
    const double fu = rel.dot(face.right_box), fv = rel.dot(face.down_box);
    for (const FaceTag& ft : face_tags[static_cast<size_t>(hit.face)]) {
      const double cell = ft.tag->size_mm / (ft.pattern.width - 2);
      const double half_printed = 0.5 * cell * ft.pattern.width;
      const double lu = fu - ft.tag->center_face_mm.x() + half_printed;
      const double lv = fv - ft.tag->center_face_mm.y() + half_printed;
      if (lu < 0 || lv < 0 || lu >= 2 * half_printed || lv >= 2 * half_printed) continue;
      const int col = std::min(ft.pattern.width - 1, static_cast<int>(lu / cell));
      const int row = std::min(ft.pattern.width - 1, static_cast<int>(lv / cell));
      hit.albedo = ft.pattern.IsWhite(col, row) ? kWhiteAlbedo : kTagBlackAlbedo;
      break;
    }
    return hit;
  }

  void DrawBox(View& v) const {
    const Eigen::Vector3d half = 0.5 * scene.box.size_mm;
    const Rigid3d cam_from_box = v.box_from_cam.Inverse();
    const cv::Rect rect = ProjectedBounds(v, BoxCorners(cam_from_box, Eigen::Vector3d::Zero(), half), 3);
    if (rect.empty()) return;
    // Per-face radiance factor (the panels are far compared with the box).
    std::array<double, 6> face_irradiance{};
    for (size_t f = 0; f < 6; ++f) {
      const BoxFace& face = scene.box.faces[f];
      face_irradiance[f] = Irradiance(v, cam_from_box * face.center_box_mm, cam_from_box.rotation * face.normal_box);
    }
    // Samples at pixel corners decide which pixels straddle an edge.
    const int gw = rect.width + 1, gh = rect.height + 1;
    std::vector<int> corner_class(static_cast<size_t>(gw * gh));
    for (int j = 0; j < gh; ++j) {
      for (int i = 0; i < gw; ++i) {
        corner_class[static_cast<size_t>(j * gw + i)] = CastBox(v, rect.x + i - 0.5, rect.y + j - 0.5, half).Class();
      }
    }
    for (int j = 0; j < rect.height; ++j) {
      for (int i = 0; i < rect.width; ++i) {
        const int x = rect.x + i, y = rect.y + j;
        const int c00 = corner_class[static_cast<size_t>(j * gw + i)];
        const bool uniform = c00 == corner_class[static_cast<size_t>(j * gw + i + 1)] &&
                             c00 == corner_class[static_cast<size_t>((j + 1) * gw + i)] &&
                             c00 == corner_class[static_cast<size_t>((j + 1) * gw + i + 1)];
        if (uniform && c00 < 0) continue;
        const cv::Vec3f behind = v.radiance(y, x);
        const float behind_depth = v.depth(y, x);
        if (uniform) {
          const BoxHit h = CastBox(v, x, y, half);
          if (!h.hit || h.z >= behind_depth) continue;
          const float value = static_cast<float>(h.albedo * face_irradiance[static_cast<size_t>(h.face)]);
          v.radiance(y, x) = cv::Vec3f(value, value, value);
          v.depth(y, x) = static_cast<float>(h.z);
          v.surface(y, x) = static_cast<uint8_t>(kSurfaceFace0 + h.face);
          continue;
        }
        // Edge pixel: stratified jittered samples over the pixel's square.
        double sum = 0, covered = 0;
        for (int s = 0; s < kEdgeSamples * kEdgeSamples; ++s) {
          const uint32_t h32 = HashPixel(x, y, static_cast<uint32_t>(s));
          const double ju = ((s % kEdgeSamples) + (h32 & 0xffff) / 65536.0) / kEdgeSamples - 0.5;
          const double jv = ((s / kEdgeSamples) + (h32 >> 16) / 65536.0) / kEdgeSamples - 0.5;
          const BoxHit h = CastBox(v, x + ju, y + jv, half);
          if (!h.hit || h.z >= behind_depth) continue;
          sum += h.albedo * face_irradiance[static_cast<size_t>(h.face)];
          covered += 1;
        }
        const double n = kEdgeSamples * kEdgeSamples;
        const float fc = static_cast<float>(covered / n);
        const float value = static_cast<float>(sum / n);
        v.radiance(y, x) = behind * (1.0f - fc) + cv::Vec3f(value, value, value);
        if (covered * 2 >= n) {
          const BoxHit centre = CastBox(v, x, y, half);
          if (centre.hit) {
            v.depth(y, x) = static_cast<float>(centre.z);
            v.surface(y, x) = static_cast<uint8_t>(kSurfaceFace0 + centre.face);
          }
        }
      }
    }
  }

  // Kajiya-Kay shading of a strand segment with tangent t (camera frame).
  cv::Vec3f ShadeStrand(const View& v, const Eigen::Vector3d& p, const Eigen::Vector3d& t) const {
    const Eigen::Vector3d view_dir = (-p).normalized();
    const double cos_tv = t.dot(view_dir), sin_tv = std::sqrt(std::max(0.0, 1 - cos_tv * cos_tv));
    double diffuse = v.ambient, specular = 0;
    for (size_t i = 0; i < v.light_power.size(); ++i) {
      const Eigen::Vector3d l = (v.light_pos_cam[i] - p).normalized();
      const double cos_tl = t.dot(l), sin_tl = std::sqrt(std::max(0.0, 1 - cos_tl * cos_tl));
      diffuse += v.light_power[i] * 0.9 * sin_tl;
      specular += v.light_power[i] * 0.35 * std::pow(std::max(0.0, cos_tl * cos_tv + sin_tl * sin_tv), 30.0);
    }
    const Eigen::Vector3d& a = scene.wig.albedo;
    return {static_cast<float>(a.z() * diffuse + specular), static_cast<float>(a.y() * diffuse + specular),
            static_cast<float>(a.x() * diffuse + specular)};
  }

  void DrawSegment(View& v, const Eigen::Vector2d& a, const Eigen::Vector2d& b, float z, const cv::Vec3f& color) const {
    constexpr float kOpacity = 0.6f;
    constexpr double kOcclusionMarginMm = 3.0;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x(), b.x()) - 1)));
    const int x1 = std::min(v.width - 1, static_cast<int>(std::ceil(std::max(a.x(), b.x()) + 1)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y(), b.y()) - 1)));
    const int y1 = std::min(v.height - 1, static_cast<int>(std::ceil(std::max(a.y(), b.y()) + 1)));
    const Eigen::Vector2d ab = b - a;
    const double len2 = std::max(ab.squaredNorm(), 1e-12);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        if (v.depth(y, x) < z - kOcclusionMarginMm) continue;
        const Eigen::Vector2d p(x, y);
        const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
        const double d = (a + t * ab - p).norm();
        if (d >= 1.0) continue;
        const float alpha = kOpacity * static_cast<float>(1.0 - d);
        v.radiance(y, x) = v.radiance(y, x) * (1.0f - alpha) + color * alpha;
        v.hair_alpha(y, x) = 1.0f - (1.0f - v.hair_alpha(y, x)) * (1.0f - alpha);
      }
    }
  }

  void DrawHair(View& v) const {
    const auto offsets = strands.Offsets();
    const Eigen::Matrix3d r = v.cam_from_turntable.RotationMatrix();
    const Eigen::Vector3d tr = v.cam_from_turntable.translation;
    std::vector<Eigen::Vector3d> p_cam(strands.num_points());
    std::vector<Eigen::Vector2d> uv(strands.num_points());
    const auto params = v.camera->intrinsics.ToParams();
    for (size_t i = 0; i < p_cam.size(); ++i) {
      p_cam[i] = r * strands.points_mm[i].cast<double>() + tr;
      if (p_cam[i].z() > 1.0) ProjectCamPoint(params.data(), p_cam[i].data(), uv[i].data());
    }
    // Back to front by the mean depth of each strand.
    std::vector<double> mean_z(strands.num_strands(), 0.0);
    for (size_t s = 0; s < strands.num_strands(); ++s) {
      for (size_t i = offsets[s]; i < offsets[s + 1]; ++i) mean_z[s] += p_cam[i].z();
      mean_z[s] /= static_cast<double>(offsets[s + 1] - offsets[s]);
    }
    std::vector<size_t> order(strands.num_strands());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return mean_z[a] > mean_z[b]; });
    for (size_t s : order) {
      for (size_t i = offsets[s] + 1; i < offsets[s + 1]; ++i) {
        if (p_cam[i - 1].z() <= 1.0 || p_cam[i].z() <= 1.0) continue;
        const Eigen::Vector3d t = (p_cam[i] - p_cam[i - 1]).normalized();
        const Eigen::Vector3d mid = 0.5 * (p_cam[i] + p_cam[i - 1]);
        DrawSegment(v, uv[i - 1], uv[i], static_cast<float>(mid.z()), ShadeStrand(v, mid, t));
      }
    }
  }

  std::vector<TagTruth> TagTruths(const View& v) const {
    std::vector<TagTruth> truths;
    const Rigid3d cam_from_box = v.box_from_cam.Inverse();
    const Eigen::Vector3d cam_center_box = v.box_from_cam.translation;
    for (const BoxTag& tag : scene.box.tags) {
      TagTruth t;
      t.id = tag.id;
      const BoxFace& face = scene.box.faces[static_cast<size_t>(tag.face)];
      const Eigen::Vector3d to_cam = (cam_center_box - tag.center_box_mm).normalized();
      t.facing_deg = RadToDeg(std::asin(std::clamp(to_cam.dot(face.normal_box), -1.0, 1.0)));
      bool in_front = true;
      for (int k = 0; k < 4; ++k) in_front = ProjectChecked(v.camera->intrinsics, cam_from_box * tag.corners_box_mm[k], &t.corners_px[k]) && in_front;
      t.in_image = in_front;
      for (const auto& c : t.corners_px) {
        t.in_image = t.in_image && c.x() >= 4 && c.y() >= 4 && c.x() <= v.width - 5 && c.y() <= v.height - 5;
      }
      t.unoccluded = t.in_image && t.facing_deg > 0 && TagUnoccluded(v, cam_from_box, tag, face);
      truths.push_back(t);
    }
    return truths;
  }

  // No head or hair over any of 9 x 9 points spread over the printed tag.
  bool TagUnoccluded(const View& v, const Rigid3d& cam_from_box, const BoxTag& tag, const BoxFace& face) const {
    const double half_printed = 0.5 * tag.size_mm * 10.0 / 8.0;
    for (int j = 0; j <= 8; ++j) {
      for (int i = 0; i <= 8; ++i) {
        const double du = (i / 4.0 - 1.0) * half_printed * 0.98, dv = (j / 4.0 - 1.0) * half_printed * 0.98;
        const Eigen::Vector3d p = tag.center_box_mm + du * face.right_box + dv * face.down_box;
        Eigen::Vector2d uv;
        if (!ProjectChecked(v.camera->intrinsics, cam_from_box * p, &uv)) return false;
        const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
        if (x < 0 || y < 0 || x >= v.width || y >= v.height) return false;
        if (v.surface(y, x) != kSurfaceFace0 + tag.face || v.hair_alpha(y, x) > 0.02f) return false;
      }
    }
    return true;
  }

  cv::Mat Expose(const View& v, const RenderOptions& o) const {
    return render_support::ExposeRadiance(v.radiance, *v.camera, o.exposure_s, o.gain_db, o.noise, o.noise_seed);
  }
};

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;
const Scene& Renderer::scene() const { return impl_->scene; }
const StrandSet& Renderer::strands_turntable_mm() const { return impl_->strands; }
void Renderer::SetStrands(StrandSet strands_turntable_mm) { impl_->strands = std::move(strands_turntable_mm); }

Result<std::unique_ptr<Renderer>> Renderer::Create(const Scene& scene) {
  auto impl = std::make_unique<Impl>();
  impl->scene = scene;
  HR_RETURN_IF_ERROR(ValidateScene(scene));
  HR_ASSIGN_OR_RETURN(impl->strands, GenerateWig(scene.wig, scene.head));
  for (const SceneCamera& cam : scene.cameras) {
    HR_ASSIGN_OR_RETURN(RayTable table, RayTable::Build(cam.intrinsics));
    impl->ray_tables.push_back(std::move(table));
  }
  impl->face_tags.resize(impl->scene.box.faces.size());
  for (const BoxTag& tag : impl->scene.box.tags) {
    HR_ASSIGN_OR_RETURN(TagPattern pattern, MakeTagPattern(scene.box.family, tag.id));
    impl->face_tags[static_cast<size_t>(tag.face)].push_back({nullptr, std::move(pattern)});
  }
  // Point at the tags in the Impl's own copy of the scene.
  std::vector<size_t> next(impl->face_tags.size(), 0);
  for (const BoxTag& tag : impl->scene.box.tags) impl->face_tags[static_cast<size_t>(tag.face)][next[static_cast<size_t>(tag.face)]++].tag = &tag;
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

Result<RenderedView> Renderer::Render(int camera_index, double turntable_deg, const RenderOptions& options) const {
  const Scene& scene = impl_->scene;
  if (camera_index < 0 || camera_index >= static_cast<int>(scene.cameras.size())) {
    return OutOfRange("camera index " + std::to_string(camera_index) + " is outside the scene's " +
                      std::to_string(scene.cameras.size()) + " cameras");
  }
  if (!std::isfinite(turntable_deg)) return InvalidArgument("turntable angle is not a finite number");
  std::vector<double> levels = options.light_levels;
  if (levels.empty()) levels.assign(scene.lights.size(), 1.0);
  if (levels.size() != scene.lights.size()) {
    return InvalidArgument("got " + std::to_string(levels.size()) + " light levels for " +
                           std::to_string(scene.lights.size()) + " lights");
  }
  Impl::View v;
  v.camera = &scene.cameras[static_cast<size_t>(camera_index)];
  v.rays = &impl_->ray_tables[static_cast<size_t>(camera_index)];
  v.width = v.camera->intrinsics.width_px;
  v.height = v.camera->intrinsics.height_px;
  v.cam_from_world = v.camera->cam_from_world;
  v.cam_from_turntable = v.cam_from_world * WorldFromTurntable(turntable_deg);
  v.box_from_cam = (v.cam_from_turntable * scene.turntable_from_box).Inverse();
  double total_power = 0;
  for (size_t i = 0; i < levels.size(); ++i) {
    if (!(levels[i] >= 0 && levels[i] <= 1)) return InvalidArgument("light level outside 0..1 for light " + scene.lights[i].name);
    v.light_power.push_back(levels[i] * scene.lights[i].intensity);
    v.light_pos_cam.push_back(v.cam_from_world * scene.lights[i].position_world_mm);
    total_power += levels[i];
  }
  v.ambient = total_power > 0 ? scene.ambient : 0.0;  // the room is dark; the panels are the light
  v.radiance = cv::Mat3f(v.height, v.width);
  v.depth = cv::Mat1f(v.height, v.width, kInf);
  v.surface = cv::Mat1b(v.height, v.width, kSurfaceBackdrop);
  v.hair_alpha = cv::Mat1f(v.height, v.width, 0.0f);
  impl_->DrawBackdrop(v);
  impl_->DrawHead(v);
  impl_->DrawBox(v);
  if (options.draw_hair) impl_->DrawHair(v);
  RenderedView out;
  out.tags = impl_->TagTruths(v);
  out.image = impl_->Expose(v, options);
  return out;
}

}  // namespace hairrig
