#include "sim_hw/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/head_model.h"
#include "core/parallel.h"
#include "sim_hw/deep_opacity.h"
#include "sim_hw/hair_shading.h"
#include "sim_hw/render_support.h"
#include "sim_hw/tag_texture.h"
#include "sim_hw/wig.h"

namespace hairrig {
namespace {
using render_support::HashPixel;
using render_support::kEdgeSamples;
using render_support::MixBits;
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

// One hair segment as the camera sees it.
struct HairSegment {
  Eigen::Vector2f a, b;  // pixel positions of its ends
  float za = 0, zb = 0;  // their depths (mm)
  float width_px = 0;    // the fibre's projected diameter
  uint32_t strand = 0;
  cv::Vec3f color_a, color_b;  // radiance at its ends (BGR)
  float angle_deg = 0;         // 2D direction in [0, 180)
  float grains = 0;            // fibre grains along it (HairShading::fibre_grain_mm); 0: smooth
  uint32_t grain_seed = 0;
  float Depth() const { return 0.5f * (za + zb); }
};

struct BoxHit {
  bool hit = false;
  int face = -1;
  double albedo = 0;
  double z = 0;  // camera-frame depth (mm)
  int Class() const { return hit ? face * 2 + (albedo > 0.5 ? 1 : 0) : -1; }
};

// DrawSegment skips a pixel whose opaque surface (head, box) lies this far or
// more in front of the fibre.
constexpr float kOcclusionMarginMm = 3.0f;

// Whether no pixel within 1 px of the segment a-b (pixels) could show a fibre
// at depth `nearest_z_mm` or farther: `farthest_nearby` holds, per pixel, the
// farthest opaque depth within 2 px (Chebyshev), and samples 2 px apart along
// the segment leave no pixel within 1 px of it more than 2 px from a sample.
bool HiddenBehindOpaque(const cv::Mat1f& farthest_nearby, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b, float nearest_z_mm) {
  const int samples = 1 + static_cast<int>(std::ceil((b - a).norm() / 2.0));
  for (int k = 0; k <= samples; ++k) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(k) / samples);
    const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
    if (x < 0 || y < 0 || x >= farthest_nearby.cols || y >= farthest_nearby.rows) return false;
    if (!(farthest_nearby(y, x) < nearest_z_mm - kOcclusionMarginMm)) return false;
  }
  return true;
}

}  // namespace

// The buffers one view's hair needs, kept between renders: a view of a
// 50,000-strand wig needs a few hundred MB, and fresh pages cost more than the
// arithmetic that fills them.
struct HairScratch {
  std::vector<Eigen::Vector3d> p_cam;    // strand points, camera frame (mm)
  std::vector<Eigen::Vector2d> uv;       // their projections (px)
  std::vector<uint8_t> segment_visible;  // [i]: the segment ending at point i is drawn
  std::vector<size_t> first_segment;     // per strand: index of its first drawn segment
  std::vector<HairSegment> segments;
  std::vector<std::vector<std::vector<uint64_t>>> share_keys;  // per thread, per band
};

struct Renderer::Impl {
  Scene scene;
  std::unique_ptr<HeadModel> head;
  StrandSet strands;
  std::vector<RayTable> ray_tables;
  std::vector<std::vector<FaceTag>> face_tags;  // per box face

  // Scratch buffers of finished renders, for the next ones (as many as renders ran at once, up to
  // 2).
  static constexpr size_t kMaxSpareScratch = 2;
  mutable std::mutex scratch_mutex;
  mutable std::vector<std::unique_ptr<HairScratch>> spare_scratch;

  // Lends a scratch to one render and takes it back when the render is done.
  class ScratchLease {
   public:
    explicit ScratchLease(const Impl& impl) : impl_(impl) {
      std::lock_guard<std::mutex> lock(impl_.scratch_mutex);
      if (!impl_.spare_scratch.empty()) {
        scratch_ = std::move(impl_.spare_scratch.back());
        impl_.spare_scratch.pop_back();
      } else {
        scratch_ = std::make_unique<HairScratch>();
      }
    }
    ~ScratchLease() {
      std::lock_guard<std::mutex> lock(impl_.scratch_mutex);
      if (impl_.spare_scratch.size() < kMaxSpareScratch)
        impl_.spare_scratch.push_back(std::move(scratch_));
    }
    ScratchLease(const ScratchLease&) = delete;
    ScratchLease& operator=(const ScratchLease&) = delete;
    HairScratch& operator*() const { return *scratch_; }

   private:
    const Impl& impl_;
    std::unique_ptr<HairScratch> scratch_;
  };

  // Everything one Render call needs, derived from the view.
  struct View {
    const SceneCamera* camera = nullptr;
    const RayTable* rays = nullptr;
    Rigid3d cam_from_world, cam_from_turntable, box_from_cam;
    std::vector<double> light_power;  // level * intensity per light
    std::vector<Eigen::Vector3d> light_pos_cam;
    double ambient = 0;
    int width = 0, height = 0;
    cv::Mat3f radiance;
    cv::Mat1f depth;
    cv::Mat1b surface;
    cv::Mat1f hair_alpha;
    // Ground truth of the front-most strand per pixel.
    cv::Mat1f hair_front_z, hair_angle;
    cv::Mat1i hair_id;
    std::vector<LightShadowMap> shadows;  // per light, when the scene shades with shadows
    int threads = 1;
    bool shade_hair = true;
  };

  double Irradiance(const View& v, const Eigen::Vector3d& p_cam,
                    const Eigen::Vector3d& n_cam) const {
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
      const cv::Vec3f c(static_cast<float>(scene.backdrop_albedo.z() * shade),
                        static_cast<float>(scene.backdrop_albedo.y() * shade),
                        static_cast<float>(scene.backdrop_albedo.x() * shade));
      for (int x = 0; x < v.width; ++x) v.radiance(y, x) = c;
    }
  }

  // Bounding rectangle (pixels) of camera-frame points, clipped to the image;
  // empty if any point is behind the camera.
  cv::Rect ProjectedBounds(const View& v, const std::vector<Eigen::Vector3d>& points_cam,
                           int margin) const {
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

  std::vector<Eigen::Vector3d> BoxCorners(const Rigid3d& cam_from_frame,
                                          const Eigen::Vector3d& center,
                                          const Eigen::Vector3d& half) const {
    std::vector<Eigen::Vector3d> corners;
    for (const Eigen::Vector3d& p : BoxCornerPoints(half))
      corners.push_back(cam_from_frame * (center + p));
    return corners;
  }

  // Skin: Lambert with a little wrap-around (light scattered under the skin)
  // and the shadows of the hair and the head.
  cv::Vec3f ShadeSkin(const View& v, const Eigen::Vector3d& p, const Eigen::Vector3d& n) const {
    double e = v.ambient;
    for (size_t i = 0; i < v.light_power.size(); ++i) {
      const Eigen::Vector3d l = (v.light_pos_cam[i] - p).normalized();
      const double wrapped = std::max(0.0, (n.dot(l) + 0.15) / 1.15);
      if (wrapped <= 0 || v.light_power[i] <= 0) continue;
      double power = v.light_power[i];
      if (!v.shadows.empty()) {
        const LightShadowMap::Visibility seen = v.shadows[i].VisibilityAt(p, &n);
        power *= seen.hair_transmittance * seen.head_visibility;
      }
      e += power * wrapped;
    }
    const Eigen::Vector3d& a = scene.head.albedo;
    return {static_cast<float>(a.z() * e), static_cast<float>(a.y() * e),
            static_cast<float>(a.x() * e)};
  }

  // The head, ray cast per pixel (rows spread over the view's threads).
  void DrawHead(View& v) const {
    const Rigid3d turntable_from_cam = v.cam_from_turntable.Inverse();
    const Eigen::Matrix3d r = turntable_from_cam.RotationMatrix();
    const Eigen::Matrix3d cam_r = v.cam_from_turntable.RotationMatrix();
    std::vector<Eigen::Vector3d> corners_cam;
    const Eigen::Vector3d lo = head->mesh().MinCorner(), hi = head->mesh().MaxCorner();
    for (int c = 0; c < 8; ++c) {
      corners_cam.push_back(v.cam_from_turntable * Eigen::Vector3d((c & 1) ? hi.x() : lo.x(),
                                                                   (c & 2) ? hi.y() : lo.y(),
                                                                   (c & 4) ? hi.z() : lo.z()));
    }
    const cv::Rect rect = ProjectedBounds(v, corners_cam, 2);
    ParallelFor(static_cast<size_t>(rect.height), v.threads, [&] {
      return [&](size_t row) {
        const int y = rect.y + static_cast<int>(row);
        for (int x = rect.x; x < rect.x + rect.width; ++x) {
          const Eigen::Vector3d d = v.rays->Ray(x, y);
          HeadHit hit;
          if (!head->Intersect(turntable_from_cam.translation, r * d, 0.0, v.depth(y, x), &hit))
            continue;
          const Eigen::Vector3d p = hit.t * d;  // the ray's z is 1: t is the depth
          v.radiance(y, x) = ShadeSkin(v, p, cam_r * hit.normal);
          v.depth(y, x) = static_cast<float>(hit.t);
          v.surface(y, x) = kSurfaceHead;
        }
      };
    });
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
    BoxHit hit;
    hit.hit = true;
    hit.face =
        2 * axis + (d[axis] > 0 ? 1 : 0);  // entering through the face whose normal opposes d
    hit.z = t_near * d_cam.z();
    hit.albedo = kWhiteAlbedo;
    // The box's outline is the drawn cuboid; a tag's pattern is looked up
    // where the ray meets the tag's own plane (as built: moved, turned, tilted).
    for (const FaceTag& ft : face_tags[static_cast<size_t>(hit.face)]) {
      const BoxTag& tag = *ft.tag;
      const Eigen::Vector3d tag_normal = tag.right_box.cross(tag.down_box);
      const double along = d.dot(tag_normal);
      if (std::abs(along) < 1e-12) continue;
      const Eigen::Vector3d rel =
          o + ((tag.center_box_mm - o).dot(tag_normal) / along) * d - tag.center_box_mm;
      const double cell = tag.size_mm / (ft.pattern.width - 2);
      const double half_printed = 0.5 * cell * ft.pattern.width;
      const double lu = rel.dot(tag.right_box) + half_printed;
      const double lv = rel.dot(tag.down_box) + half_printed;
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
    const cv::Rect rect =
        ProjectedBounds(v, BoxCorners(cam_from_box, Eigen::Vector3d::Zero(), half), 3);
    if (rect.empty()) return;
    // Per-face radiance factor (the panels are far compared with the box).
    std::array<double, 6> face_irradiance{};
    for (size_t f = 0; f < 6; ++f) {
      const BoxFace& face = scene.box.faces[f];
      face_irradiance[f] =
          Irradiance(v, cam_from_box * face.center_box_mm, cam_from_box.rotation * face.normal_box);
    }
    // Samples at pixel corners decide which pixels straddle an edge.
    const int gw = rect.width + 1, gh = rect.height + 1;
    std::vector<int> corner_class(static_cast<size_t>(gw * gh));
    for (int j = 0; j < gh; ++j) {
      for (int i = 0; i < gw; ++i) {
        corner_class[static_cast<size_t>(j * gw + i)] =
            CastBox(v, rect.x + i - 0.5, rect.y + j - 0.5, half).Class();
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
          const float value =
              static_cast<float>(h.albedo * face_irradiance[static_cast<size_t>(h.face)]);
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

  // Radiance of a fibre segment at p with tangent t (camera frame).
  // `albedo` is the fibre's own colour.
  cv::Vec3f ShadeStrand(const View& v, const Eigen::Vector3d& p, const Eigen::Vector3d& t,
                        const Eigen::Vector3d& albedo) const {
    const Eigen::Vector3d to_camera = (-p).normalized();
    Eigen::Vector3d radiance = 0.9 * v.ambient * albedo;
    for (size_t i = 0; i < v.light_power.size(); ++i) {
      if (v.light_power[i] <= 0) continue;
      const FibreRadiance f = ShadeFibre(scene.hair_shading, albedo, t,
                                         (v.light_pos_cam[i] - p).normalized(), to_camera);
      if (v.shadows.empty()) {
        radiance += v.light_power[i] * (f.single + f.diffuse);
        continue;
      }
      // Light scattered many times inside the volume is shadowed more softly than direct light.
      const LightShadowMap::Visibility seen = v.shadows[i].VisibilityAt(p);
      const double hair = seen.hair_transmittance;
      radiance +=
          v.light_power[i] * seen.head_visibility * (hair * f.single + std::sqrt(hair) * f.diffuse);
    }
    return {static_cast<float>(radiance.z()), static_cast<float>(radiance.y()),
            static_cast<float>(radiance.x())};
  }

  // A fibre's colour: the wig's, scaled by the fibre's own log-normal factor.
  Eigen::Vector3d FibreAlbedo(size_t strand) const {
    const double sd = scene.hair_shading.fibre_albedo_sd;
    if (sd <= 0) return scene.wig.albedo;
    NoiseSource source(MixBits((scene.wig.seed << 32) + strand));
    const double scale = std::exp(sd * source.Next() - 0.5 * sd * sd);
    return (scene.wig.albedo * scale).cwiseMin(1.0);
  }

  // The fibre's grain at `t` along a segment: log-normal, mean 1, interpolated
  // between grains (HairShading::fibre_grain_sd).
  float Grain(const HairSegment& seg, float t) const {
    const float g = t * seg.grains;
    const uint64_t i = static_cast<uint64_t>(g);
    const float f = g - static_cast<float>(i);
    const uint64_t base = static_cast<uint64_t>(seg.grain_seed) << 24;
    const float n = NoiseSource(MixBits(base + i)).Next() * (1 - f) +
                    NoiseSource(MixBits(base + i + 1)).Next() * f;
    const float sd = static_cast<float>(scene.hair_shading.fibre_grain_sd);
    return std::exp(sd * n - 0.5f * sd * sd);
  }

  // Draws `seg` into the rows [y_begin, y_end) of the view: per pixel within
  // one pixel of the centre line, coverage = width x tent(distance), composited
  // over what is there; the front-most strand within half a pixel is the
  // pixel's ground truth.
  void DrawSegment(View& v, const HairSegment& seg, int y_begin, int y_end) const {
    const float ax = seg.a.x(), ay = seg.a.y();
    const float dx = seg.b.x() - ax, dy = seg.b.y() - ay;
    const float len2 = dx * dx + dy * dy;
    if (len2 < 1e-12f) return;
    const float inv_len2 = 1.0f / len2, inv_len = std::sqrt(inv_len2);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(ax, seg.b.x()) - 1)));
    const int x1 = std::min(v.width - 1, static_cast<int>(std::ceil(std::max(ax, seg.b.x()) + 1)));
    const int y0 = std::max(y_begin, static_cast<int>(std::floor(std::min(ay, seg.b.y()) - 1)));
    const int y1 = std::min(y_end - 1, static_cast<int>(std::ceil(std::max(ay, seg.b.y()) + 1)));
    const bool steep = std::abs(dy) > std::abs(dx);
    // A pixel within 1 px of the line lies within `reach` of it along the minor axis.
    const float reach = std::sqrt(len2) / std::max(std::abs(dx), std::abs(dy));
    const float w = seg.width_px;
    const int major0 = steep ? y0 : x0, major1 = steep ? y1 : x1;
    for (int m = major0; m <= major1; ++m) {
      const float mf = static_cast<float>(m);
      const float t_line = steep ? (mf - ay) / dy : (mf - ax) / dx;
      const float centre = steep ? ax + t_line * dx : ay + t_line * dy;
      const int lo = std::max(steep ? x0 : y0, static_cast<int>(std::floor(centre - reach)));
      const int hi = std::min(steep ? x1 : y1, static_cast<int>(std::ceil(centre + reach)));
      for (int k = lo; k <= hi; ++k) {
        const int x = steep ? k : m, y = steep ? m : k;
        const float px = static_cast<float>(x) - ax, py = static_cast<float>(y) - ay;
        const float t = (px * dx + py * dy) * inv_len2;
        if (t < 0 || t >= 1) continue;  // each pixel belongs to one segment of a strand's chain
        const float d = std::abs(px * dy - py * dx) * inv_len;
        if (d >= 1.0f) continue;
        const float z = seg.za + t * (seg.zb - seg.za);
        if (v.depth(y, x) < z - kOcclusionMarginMm) continue;
        const float alpha = std::min(1.0f, w < 1 ? w * (1.0f - d) : 0.5f * w + 0.5f - d);
        if (alpha <= 0) continue;
        cv::Vec3f color = seg.color_a + t * (seg.color_b - seg.color_a);
        if (seg.grains > 0) color *= Grain(seg, t);
        cv::Vec3f& radiance = v.radiance(y, x);
        radiance = radiance * (1.0f - alpha) + color * alpha;
        float& coverage = v.hair_alpha(y, x);
        coverage = 1.0f - (1.0f - coverage) * (1.0f - alpha);
        float& front = v.hair_front_z(y, x);
        if (d <= 0.5f && z < front) {
          front = z;
          v.hair_id(y, x) = static_cast<int>(seg.strand);
          v.hair_angle(y, x) = seg.angle_deg;
        }
      }
    }
  }

  // Per pixel, the farthest opaque depth (head, box; infinite on the
  // backdrop) within 2 px: where it is nearer than a segment, the segment is hidden.
  static cv::Mat1f FarthestOpaqueNearby(const View& v) {
    cv::Mat1f farthest;
    cv::dilate(v.depth, farthest, cv::Mat(5, 5, CV_8U, cv::Scalar(1)));
    return farthest;
  }

  // Every visible segment projected and shaded at its ends (strands spread
  // over threads); the colour is interpolated along it. Segments are laid out
  // strand by strand: a count per strand first, then one array filled in place.
  void HairSegments(const View& v, HairScratch& scratch) const {
    const std::vector<Eigen::Vector3d>& p_cam = scratch.p_cam;
    const std::vector<Eigen::Vector2d>& uv = scratch.uv;
    const auto offsets = strands.Offsets();
    const cv::Mat1f occluders = FarthestOpaqueNearby(v);
    const double fibre_mm = 1e-3 * scene.wig.fibre_diameter_um;
    const double grain_sd = scene.hair_shading.fibre_grain_sd;
    const double grain_mm = scene.hair_shading.fibre_grain_mm;
    const double focal = 0.5 * (v.camera->intrinsics.fx_px + v.camera->intrinsics.fy_px);
    const auto visible = [&](size_t i) {
      const Eigen::Vector2d& a = uv[i - 1];
      const Eigen::Vector2d& b = uv[i];
      return p_cam[i - 1].z() > 1.0 && p_cam[i].z() > 1.0 && std::max(a.x(), b.x()) >= -2 &&
             std::min(a.x(), b.x()) <= v.width + 1 && std::max(a.y(), b.y()) >= -2 &&
             std::min(a.y(), b.y()) <= v.height + 1 &&
             !HiddenBehindOpaque(occluders, a, b,
                                 static_cast<float>(std::min(p_cam[i - 1].z(), p_cam[i].z())));
    };
    const size_t n = strands.num_strands();
    std::vector<size_t>& first_segment = scratch.first_segment;
    first_segment.assign(n + 1, 0);
    std::vector<uint8_t>& segment_visible = scratch.segment_visible;
    segment_visible.assign(strands.num_points(), 0);
    ParallelFor(n, v.threads, [&] {
      return [&](size_t s) {
        size_t count = 0;
        for (size_t i = offsets[s] + 1; i < offsets[s + 1]; ++i) {
          segment_visible[i] = visible(i) ? 1 : 0;
          count += segment_visible[i];
        }
        first_segment[s + 1] = count;
      };
    });
    for (size_t s = 0; s < n; ++s) first_segment[s + 1] += first_segment[s];
    std::vector<HairSegment>& all = scratch.segments;
    all.resize(first_segment[n]);
    ParallelFor(n, v.threads, [&] {
      return [&, color = std::vector<cv::Vec3f>()](size_t s) mutable {
        const size_t first = offsets[s], last = offsets[s + 1];
        if (first_segment[s + 1] == first_segment[s]) return;
        // Radiance at each end of a visible segment, with the tangent of the chord around it.
        color.assign(last - first, cv::Vec3f(0, 0, 0));
        const Eigen::Vector3d albedo = FibreAlbedo(s);
        for (size_t i = first; i < last && v.shade_hair; ++i) {
          const bool needed =
              (i > first && segment_visible[i]) || (i + 1 < last && segment_visible[i + 1]);
          if (!needed) continue;
          const size_t a = i == first ? i : i - 1, b = i + 1 < last ? i + 1 : i;
          color[i - first] = ShadeStrand(v, p_cam[i], (p_cam[b] - p_cam[a]).normalized(), albedo);
        }
        HairSegment* out = &all[first_segment[s]];
        for (size_t i = first + 1; i < last; ++i) {
          if (!segment_visible[i]) continue;
          const Eigen::Vector2d a = uv[i - 1], b = uv[i];
          HairSegment& seg = *out++;
          seg.a = a.cast<float>(), seg.b = b.cast<float>();
          seg.za = static_cast<float>(p_cam[i - 1].z()), seg.zb = static_cast<float>(p_cam[i].z());
          seg.width_px = static_cast<float>(fibre_mm * focal / (0.5 * (seg.za + seg.zb)));
          seg.strand = static_cast<uint32_t>(s);
          if (grain_sd > 0) {
            seg.grains = static_cast<float>((p_cam[i] - p_cam[i - 1]).norm() / grain_mm);
            seg.grain_seed = static_cast<uint32_t>(i);
          }
          seg.color_a = color[i - 1 - first], seg.color_b = color[i - first];
          double angle = RadToDeg(std::atan2(b.y() - a.y(), b.x() - a.x()));
          if (angle < 0) angle += 180;
          seg.angle_deg = static_cast<float>(angle >= 180 ? angle - 180 : angle);
        }
      };
    });
  }

  void DrawHair(View& v, HairScratch& scratch) const {
    const std::vector<Eigen::Vector3d>& p_cam = scratch.p_cam;
    const auto params = v.camera->intrinsics.ToParams();
    std::vector<Eigen::Vector2d>& uv = scratch.uv;
    uv.resize(p_cam.size());
    constexpr size_t kChunk = 4096;
    ParallelFor((p_cam.size() + kChunk - 1) / kChunk, v.threads, [&] {
      return [&](size_t chunk) {
        for (size_t i = chunk * kChunk; i < std::min(p_cam.size(), (chunk + 1) * kChunk); ++i) {
          uv[i] = Eigen::Vector2d(-1e9, -1e9);
          if (p_cam[i].z() > 1.0) ProjectCamPoint(params.data(), p_cam[i].data(), uv[i].data());
        }
      };
    });
    HairSegments(v, scratch);
    const std::vector<HairSegment>& segments = scratch.segments;
    // Horizontal bands, each with the segments that reach it, far to near:
    // a key per segment, its depth's bits above its index, sorted descending
    // (positive floats order as their bit patterns do).
    constexpr int kBandRows = 16;
    const int bands = (v.height + kBandRows - 1) / kBandRows;
    // Keys are gathered per band by each of the view's threads over its share of the segments.
    const size_t shares = static_cast<size_t>(v.threads);
    auto& share_keys = scratch.share_keys;
    share_keys.resize(shares);
    for (auto& band_keys : share_keys) {
      band_keys.resize(static_cast<size_t>(bands));
      for (auto& keys : band_keys) keys.clear();
    }
    ParallelFor(shares, v.threads, [&] {
      return [&](size_t share) {
        auto& band_keys = share_keys[share];
        const size_t begin = segments.size() * share / shares,
                     end = segments.size() * (share + 1) / shares;
        for (size_t i = begin; i < end; ++i) {
          const HairSegment& s = segments[i];
          uint32_t depth_bits;
          const float depth = std::max(0.0f, s.Depth());
          std::memcpy(&depth_bits, &depth, sizeof depth_bits);
          const uint64_t key = (static_cast<uint64_t>(depth_bits) << 32) | static_cast<uint32_t>(i);
          const int b0 = std::max(
              0, static_cast<int>(std::floor(std::min(s.a.y(), s.b.y()) - 1.5f)) / kBandRows);
          const int b1 =
              std::min(bands - 1,
                       static_cast<int>(std::ceil(std::max(s.a.y(), s.b.y()) + 1.5f)) / kBandRows);
          for (int b = b0; b <= b1; ++b) band_keys[static_cast<size_t>(b)].push_back(key);
        }
      };
    });
    ParallelFor(static_cast<size_t>(bands), v.threads, [&] {
      return [&, keys = std::vector<uint64_t>()](size_t b) mutable {
        keys.clear();
        for (auto& band_keys : share_keys) {
          keys.insert(keys.end(), band_keys[b].begin(), band_keys[b].end());
        }
        std::sort(keys.begin(), keys.end(), std::greater<uint64_t>());
        const int y_begin = static_cast<int>(b) * kBandRows,
                  y_end = std::min(v.height, y_begin + kBandRows);
        for (uint64_t key : keys)
          DrawSegment(v, segments[static_cast<uint32_t>(key)], y_begin, y_end);
      };
    });
  }

  // The strands' points in the camera frame.
  void StrandsInCamera(const View& v, std::vector<Eigen::Vector3d>& p_cam) const {
    const Eigen::Matrix3d r = v.cam_from_turntable.RotationMatrix();
    const Eigen::Vector3d tr = v.cam_from_turntable.translation;
    p_cam.resize(strands.num_points());
    constexpr size_t kChunk = 1 << 14;
    ParallelFor((p_cam.size() + kChunk - 1) / kChunk, v.threads, [&] {
      return [&](size_t chunk) {
        for (size_t i = chunk * kChunk; i < std::min(p_cam.size(), (chunk + 1) * kChunk); ++i) {
          p_cam[i] = r * strands.points_mm[i].cast<double>() + tr;
        }
      };
    });
  }

  // A deep opacity map per lit panel, over the hair and the head.
  void BuildShadows(View& v, const std::vector<Eigen::Vector3d>& p_cam, bool with_hair) const {
    TriangleMesh head_cam = head->mesh();
    head_cam.Transform(v.cam_from_turntable);
    const auto offsets = with_hair ? strands.Offsets() : std::vector<size_t>{0};
    const std::vector<Eigen::Vector3d> none;
    // Hair opacity: a texel per 6 pixels of the view's larger side (a full-size
    // view: 266); the head's depth twice as fine.
    ShadowMapOptions options;
    options.resolution = std::clamp(std::max(v.width, v.height) / 6, 64, 512);
    options.head_resolution = 2 * options.resolution;
    v.shadows.resize(v.light_power.size());
    ParallelFor(v.light_power.size(), v.threads, [&] {
      return [&](size_t i) {
        v.shadows[i] = LightShadowMap::Build(v.light_pos_cam[i], with_hair ? p_cam : none, offsets,
                                             1e-3 * scene.wig.fibre_diameter_um, head_cam, options);
      };
    });
  }

  // The ground-truth maps from the view's buffers.
  ViewTruthMaps TruthMaps(const View& v) const {
    ViewTruthMaps t;
    t.label = cv::Mat(v.height, v.width, CV_8U);
    t.hair_alpha = v.hair_alpha.clone();
    t.orientation_deg = cv::Mat(v.height, v.width, CV_32F);
    t.depth_mm = cv::Mat(v.height, v.width, CV_32F);
    t.strand_id = cv::Mat(v.height, v.width, CV_32S);
    for (int y = 0; y < v.height; ++y) {
      for (int x = 0; x < v.width; ++x) {
        const uint8_t surface = v.surface(y, x);
        const bool hair = v.hair_alpha(y, x) >= 0.5f && v.hair_id(y, x) >= 0;
        uint8_t label = surface == kSurfaceBackdrop ? ViewTruthMaps::kBackdrop
                        : surface == kSurfaceHead   ? ViewTruthMaps::kHead
                                                    : ViewTruthMaps::kBox;
        if (hair) label = ViewTruthMaps::kHair;
        t.label.at<uint8_t>(y, x) = label;
        t.strand_id.at<int>(y, x) = hair ? v.hair_id(y, x) : -1;
        t.orientation_deg.at<float>(y, x) =
            hair ? v.hair_angle(y, x) : std::numeric_limits<float>::quiet_NaN();
        const float opaque = std::isfinite(v.depth(y, x)) ? v.depth(y, x) : 0.0f;
        t.depth_mm.at<float>(y, x) = hair ? v.hair_front_z(y, x) : opaque;
      }
    }
    return t;
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
      for (int k = 0; k < 4; ++k)
        in_front = ProjectChecked(v.camera->intrinsics, cam_from_box * tag.corners_box_mm[k],
                                  &t.corners_px[k]) &&
                   in_front;
      t.in_image = in_front;
      for (const auto& c : t.corners_px) {
        t.in_image =
            t.in_image && c.x() >= 4 && c.y() >= 4 && c.x() <= v.width - 5 && c.y() <= v.height - 5;
      }
      t.unoccluded = t.in_image && t.facing_deg > 0 && TagUnoccluded(v, cam_from_box, tag);
      truths.push_back(t);
    }
    return truths;
  }

  // No head or hair over any of 9 x 9 points spread over the printed tag.
  bool TagUnoccluded(const View& v, const Rigid3d& cam_from_box, const BoxTag& tag) const {
    const double half_printed = 0.5 * tag.size_mm * 10.0 / 8.0;
    for (int j = 0; j <= 8; ++j) {
      for (int i = 0; i <= 8; ++i) {
        const double du = (i / 4.0 - 1.0) * half_printed * 0.98,
                     dv = (j / 4.0 - 1.0) * half_printed * 0.98;
        const Eigen::Vector3d p = tag.center_box_mm + du * tag.right_box + dv * tag.down_box;
        Eigen::Vector2d uv;
        if (!ProjectChecked(v.camera->intrinsics, cam_from_box * p, &uv)) return false;
        const int x = static_cast<int>(std::lround(uv.x())),
                  y = static_cast<int>(std::lround(uv.y()));
        if (x < 0 || y < 0 || x >= v.width || y >= v.height) return false;
        if (v.surface(y, x) != kSurfaceFace0 + tag.face || v.hair_alpha(y, x) > 0.02f) return false;
      }
    }
    return true;
  }

  // The lens' depth of field over the radiance, by the nearest surface's depth
  // (the hair where it covers at least half a pixel).
  void Defocus(View& v) const {
    const CameraPipeline& pipeline = v.camera->pipeline;
    if (pipeline.f_number <= 0 && pipeline.lens_blur_px <= 0) return;
    cv::Mat1f depth = v.depth.clone();
    for (int y = 0; y < v.height; ++y) {
      for (int x = 0; x < v.width; ++x) {
        if (v.hair_alpha(y, x) >= 0.5f) depth(y, x) = std::min(depth(y, x), v.hair_front_z(y, x));
      }
    }
    const double focal = 0.5 * (v.camera->intrinsics.fx_px + v.camera->intrinsics.fy_px);
    const double focus = pipeline.focus_mm > 0 ? pipeline.focus_mm : v.camera->target_distance_mm;
    v.radiance = DefocusRadiance(v.radiance, depth, pipeline, focal, focus);
  }

  cv::Mat Expose(const View& v, const RenderOptions& o) const {
    return render_support::ExposeRadiance(v.radiance, *v.camera, o.exposure_s, o.gain_db, o.noise,
                                          o.noise_seed);
  }
};

namespace {

Status CheckCameraIndex(const Scene& scene, int camera_index) {
  if (camera_index >= 0 && camera_index < static_cast<int>(scene.cameras.size()))
    return Status::Ok();
  return OutOfRange("camera index " + std::to_string(camera_index) + " is outside the scene's " +
                    std::to_string(scene.cameras.size()) + " cameras");
}

}  // namespace

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;
const Scene& Renderer::scene() const { return impl_->scene; }
const StrandSet& Renderer::strands_turntable_mm() const { return impl_->strands; }
const HeadModel& Renderer::head() const { return *impl_->head; }
void Renderer::SetStrands(StrandSet strands_turntable_mm) {
  impl_->strands = std::move(strands_turntable_mm);
}

Result<std::unique_ptr<Renderer>> Renderer::Create(const Scene& scene) {
  auto impl = std::make_unique<Impl>();
  impl->scene = scene;
  HR_RETURN_IF_ERROR(ValidateScene(scene));
  HR_ASSIGN_OR_RETURN(impl->head, HeadModel::Build(scene.head));
  HR_ASSIGN_OR_RETURN(impl->strands, GenerateWig(scene.wig, *impl->head));
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
  for (const BoxTag& tag : impl->scene.box.tags)
    impl->face_tags[static_cast<size_t>(tag.face)][next[static_cast<size_t>(tag.face)]++].tag =
        &tag;
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

Status RenderOptions::Check() const {
  for (size_t i = 0; i < light_levels.size(); ++i) {
    if (!(light_levels[i] >= 0 && light_levels[i] <= 1))
      return InvalidArgument("light_levels[" + std::to_string(i) + "] must lie in 0..1");
  }
  if (!(exposure_s >= 0) || !std::isfinite(exposure_s))
    return InvalidArgument("exposure_s must be 0 (the nominal exposure) or a finite positive time");
  if (!std::isfinite(gain_db)) return InvalidArgument("gain_db must be finite");
  if (threads < 1)
    return InvalidArgument("threads must be at least 1, got " + std::to_string(threads));
  return Status::Ok();
}

Result<RenderedView> Renderer::Render(int camera_index, double turntable_deg,
                                      const RenderOptions& options) const {
  HR_RETURN_IF_ERROR(options.Check().WithContext("render options"));
  const Scene& scene = impl_->scene;
  HR_RETURN_IF_ERROR(CheckCameraIndex(scene, camera_index));
  if (!std::isfinite(turntable_deg))
    return InvalidArgument("turntable angle is not a finite number");
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
    if (!(levels[i] >= 0 && levels[i] <= 1))
      return InvalidArgument("light level outside 0..1 for light " + scene.lights[i].name);
    v.light_power.push_back(levels[i] * scene.lights[i].intensity);
    v.light_pos_cam.push_back(v.cam_from_world * scene.lights[i].position_world_mm);
    total_power += levels[i];
  }
  v.ambient = total_power > 0 ? scene.ambient : 0.0;  // the room is dark; the panels are the light
  v.radiance = cv::Mat3f(v.height, v.width);
  v.depth = cv::Mat1f(v.height, v.width, kInf);
  v.surface = cv::Mat1b(v.height, v.width, kSurfaceBackdrop);
  v.hair_alpha = cv::Mat1f(v.height, v.width, 0.0f);
  v.hair_front_z = cv::Mat1f(v.height, v.width, kInf);
  v.hair_angle = cv::Mat1f(v.height, v.width, 0.0f);
  v.hair_id = cv::Mat1i(v.height, v.width, -1);
  v.threads = std::max(1, options.threads);
  v.shade_hair = options.shade_hair;
  const Impl::ScratchLease scratch(*impl_);
  (*scratch).p_cam.clear();
  if (options.draw_hair) impl_->StrandsInCamera(v, (*scratch).p_cam);
  if (scene.hair_shading.shadows && total_power > 0 && options.shade_hair) {
    impl_->BuildShadows(v, (*scratch).p_cam, options.draw_hair);
  }
  impl_->DrawBackdrop(v);
  impl_->DrawHead(v);
  impl_->DrawBox(v);
  if (options.draw_hair) impl_->DrawHair(v, *scratch);
  impl_->Defocus(v);
  RenderedView out;
  out.tags = impl_->TagTruths(v);
  out.image = impl_->Expose(v, options);
  if (options.ground_truth) out.truth = impl_->TruthMaps(v);
  if (options.keep_radiance) out.radiance = std::move(v.radiance);
  return out;
}

Result<cv::Mat> Renderer::Expose(int camera_index, const cv::Mat3f& radiance,
                                 const RenderOptions& options) const {
  HR_RETURN_IF_ERROR(options.Check().WithContext("render options"));
  const Scene& scene = impl_->scene;
  HR_RETURN_IF_ERROR(CheckCameraIndex(scene, camera_index));
  const SceneCamera& camera = scene.cameras[static_cast<size_t>(camera_index)];
  if (radiance.cols != camera.intrinsics.width_px || radiance.rows != camera.intrinsics.height_px) {
    return InvalidArgument("radiance of " + std::to_string(radiance.cols) + "x" +
                           std::to_string(radiance.rows) + " px for camera " + camera.serial +
                           " of " + std::to_string(camera.intrinsics.width_px) + "x" +
                           std::to_string(camera.intrinsics.height_px) + " px");
  }
  return render_support::ExposeRadiance(radiance, camera, options.exposure_s, options.gain_db,
                                        options.noise, options.noise_seed);
}

}  // namespace hairrig
