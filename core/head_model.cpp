#include "core/head_model.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "core/transform.h"

namespace hairrig {
namespace {

constexpr double kEllipsoidRings = 96, kEllipsoidSegments = 192;

// Closest point to p on triangle (a, b, c) (Ericson, Real-Time Collision Detection, Sec. 5.1.5).
Eigen::Vector3d ClosestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Linear interpolation of the hairline's elevation between its knots (azimuth deg -> elevation
// deg).
double HairlineElevationDeg(const ScalpSpec& s, double azimuth_deg) {
  const double knots[5][2] = {{0, s.hairline_front_deg},
                              {45, s.hairline_temple_deg},
                              {90, s.hairline_ear_deg},
                              {120, s.hairline_ear_deg},
                              {180, s.hairline_nape_deg}};
  for (int k = 1; k < 5; ++k) {
    if (azimuth_deg <= knots[k][0]) {
      const double f = (azimuth_deg - knots[k - 1][0]) / (knots[k][0] - knots[k - 1][0]);
      return knots[k - 1][1] + f * (knots[k][1] - knots[k - 1][1]);
    }
  }
  return s.hairline_nape_deg;
}

}  // namespace

HeadModel::~HeadModel() = default;

Result<std::unique_ptr<HeadModel>> HeadModel::Build(const HeadSpec& head) {
  std::unique_ptr<HeadModel> model(new HeadModel(head));
  if (model->is_mesh()) {
    auto mesh = ReadTriangleMesh(head.mesh_file);
    if (!mesh.ok()) return mesh.status().WithContext("head.mesh");
    model->mesh_ = std::move(mesh).value();
    model->mesh_.Transform(head.turntable_from_mesh);
  } else {
    model->mesh_ =
        MakeEllipsoidMesh(head.center_turntable_mm, head.radii_mm,
                          static_cast<int>(kEllipsoidRings), static_cast<int>(kEllipsoidSegments));
  }
  model->mesh_centre_mm_ = 0.5 * (model->mesh_.MinCorner() + model->mesh_.MaxCorner());
  // Angle-weighted vertex normals for smooth shading and for the distance's sign.
  model->vertex_normals_.assign(model->mesh_.vertices_mm.size(), Eigen::Vector3d::Zero());
  for (size_t t = 0; t < model->mesh_.num_triangles(); ++t) {
    const Eigen::Vector3d n = model->mesh_.FaceNormal(t);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 =
          (model->mesh_.Corner(t, (k + 1) % 3) - model->mesh_.Corner(t, k)).normalized();
      const Eigen::Vector3d e2 =
          (model->mesh_.Corner(t, (k + 2) % 3) - model->mesh_.Corner(t, k)).normalized();
      const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      model->vertex_normals_[model->mesh_.triangles[t][static_cast<size_t>(k)]] += angle * n;
    }
  }
  for (auto& n : model->vertex_normals_)
    n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
  if (model->is_mesh()) {
    model->bvh_ = MeshBvh(model->mesh_);
    HR_RETURN_IF_ERROR(model->BuildDistanceGrid());
  }
  double area = 0;
  for (size_t t = 0; t < model->mesh_.num_triangles(); ++t) {
    const Eigen::Vector3d centroid =
        (model->mesh_.Corner(t, 0) + model->mesh_.Corner(t, 1) + model->mesh_.Corner(t, 2)) / 3.0;
    if (!model->OnScalp(centroid)) continue;
    area += model->mesh_.FaceArea(t);
    model->scalp_triangles_.push_back(static_cast<uint32_t>(t));
    model->cumulative_scalp_area_.push_back(area);
  }
  if (head.scalp.defined && model->scalp_triangles_.empty()) {
    return InvalidArgument(
        "head.scalp: no part of the head lies above the hairline; lower head.scalp.hairline_*_deg "
        "or move head.scalp.center_mm into the head");
  }
  return model;
}

bool HeadModel::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                          double t_max, HeadHit* hit) const {
  if (is_mesh()) {
    MeshRayHit h;
    if (!bvh_.Intersect(origin, dir, t_min, t_max, &h)) return false;
    const auto& tri = mesh_.triangles[h.triangle];
    Eigen::Vector3d n = (1 - h.u - h.v) * vertex_normals_[tri[0]] + h.u * vertex_normals_[tri[1]] +
                        h.v * vertex_normals_[tri[2]];
    hit->t = h.t;
    hit->normal = n.normalized();
    return true;
  }
  // The ellipsoid in unit-sphere coordinates.
  const Eigen::Vector3d inv_r = head_.radii_mm.cwiseInverse();
  const Eigen::Vector3d o = (origin - head_.center_turntable_mm).cwiseProduct(inv_r);
  const Eigen::Vector3d d = dir.cwiseProduct(inv_r);
  const double qa = d.squaredNorm(), qb = 2.0 * d.dot(o), qc = o.squaredNorm() - 1.0;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return false;
  const double sq = std::sqrt(disc);
  double t = (-qb - sq) / (2 * qa);
  if (t <= t_min) t = (-qb + sq) / (2 * qa);
  if (t <= t_min || t >= t_max) return false;
  hit->t = t;
  hit->normal = (o + t * d).cwiseProduct(inv_r).normalized();
  return true;
}

double HeadModel::SignedDistance(const Eigen::Vector3d& p, Eigen::Vector3d* outward) const {
  if (!is_mesh()) {
    const Eigen::Vector3d r = head_.radii_mm;
    const Eigen::Vector3d q = (p - head_.center_turntable_mm).cwiseQuotient(r);
    const double level = q.norm();
    const Eigen::Vector3d grad = q.cwiseQuotient(r) / std::max(level, 1e-12);  // gradient of |q|
    if (outward)
      *outward = grad.norm() > 0 ? Eigen::Vector3d(grad.normalized()) : Eigen::Vector3d::UnitZ();
    return (level - 1.0) / std::max(grad.norm(), 1e-12);
  }
  const double d = GridDistance(p);
  if (outward) {
    const double h = 0.5 * grid_step_mm_;
    Eigen::Vector3d g;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[k] = h;
      g[k] = GridDistance(p + e) - GridDistance(p - e);
    }
    *outward = g.norm() > 1e-12 ? Eigen::Vector3d(g.normalized()) : Eigen::Vector3d::UnitZ();
  }
  return d;
}

bool HeadModel::IsNear(const Eigen::Vector3d& p, double margin_mm) const {
  if (!is_mesh()) {
    const Eigen::Vector3d r = head_.radii_mm.array() + margin_mm;
    return (p - head_.center_turntable_mm).cwiseQuotient(r).norm() < 1.0;
  }
  return GridDistance(p) < margin_mm;
}

Eigen::Vector3d HeadModel::KeepOutside(const Eigen::Vector3d& p, double margin_mm) const {
  if (!is_mesh()) {
    // Scaled out along the ellipsoid's radius (its level sets), as a wig pressed against it lies.
    const Eigen::Vector3d r = head_.radii_mm.array() + margin_mm;
    const Eigen::Vector3d q = (p - head_.center_turntable_mm).cwiseQuotient(r);
    const double n = q.norm();
    if (n >= 1.0 || n < 1e-9) return p;
    return head_.center_turntable_mm + (q / n).cwiseProduct(r);
  }
  // Deep inside, the grid's distance is flat at -kBandMm: step away from the
  // mesh's centre until the surface is within the band, then follow the gradient.
  const Eigen::Vector3d& centre = mesh_centre_mm_;
  Eigen::Vector3d q = p;
  for (int iteration = 0; iteration < 64; ++iteration) {
    const double d = GridDistance(q);
    if (d >= margin_mm - 1e-6) break;
    if (d <= -kBandMm + grid_step_mm_) {
      const Eigen::Vector3d away = q - centre;
      q += kBandMm *
           (away.norm() > 1e-9 ? Eigen::Vector3d(away.normalized()) : Eigen::Vector3d::UnitZ());
      continue;
    }
    Eigen::Vector3d outward;
    SignedDistance(q, &outward);
    q += (margin_mm - d) * outward;
  }
  return q;
}

void HeadModel::ScalpAngles(const Eigen::Vector3d& p, double* elevation_deg,
                            double* azimuth_deg) const {
  const ScalpSpec& s = head_.scalp;
  const Eigen::Vector3d d = (p - s.center_turntable_mm).normalized();
  *elevation_deg = RadToDeg(std::asin(std::clamp(d.z(), -1.0, 1.0)));
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(s.face_dir);
  *azimuth_deg = RadToDeg(std::atan2(std::abs(d.dot(side)), d.dot(s.face_dir)));
}

int HeadModel::ScalpSide(const Eigen::Vector3d& p) const {
  const ScalpSpec& s = head_.scalp;
  if (!s.defined || !s.parting) return 0;
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(s.face_dir);
  // The parting plane holds face_dir and the up axis tilted about it by the offset.
  const Eigen::Vector3d normal =
      Eigen::AngleAxisd(DegToRad(s.parting_offset_deg), s.face_dir) * side;
  return (p - s.center_turntable_mm).dot(normal) >= 0 ? 1 : -1;
}

bool HeadModel::AboveHairline(const Eigen::Vector3d& p) const {
  const ScalpSpec& s = head_.scalp;
  if (!s.defined || (p - s.center_turntable_mm).squaredNorm() < 1e-12) return true;
  double elevation, azimuth;
  ScalpAngles(p, &elevation, &azimuth);
  return elevation >= HairlineElevationDeg(s, azimuth);
}

bool HeadModel::OnScalp(const Eigen::Vector3d& p) const {
  const ScalpSpec& s = head_.scalp;
  if (!AboveHairline(p)) return false;
  if (!s.defined || !s.parting) return true;
  // The parting's bare line runs from the face over the crown to parting_back_deg past it.
  const Eigen::Vector3d rel = p - s.center_turntable_mm;
  const double over_top_deg = RadToDeg(std::atan2(rel.z(), rel.dot(s.face_dir)));
  if (over_top_deg > 90 + s.parting_back_deg || over_top_deg < 0) return true;
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(s.face_dir);
  const Eigen::Vector3d normal =
      Eigen::AngleAxisd(DegToRad(s.parting_offset_deg), s.face_dir) * side;
  return std::abs(rel.dot(normal)) > 0.5 * s.parting_width_mm;
}

Eigen::Vector3d HeadModel::SampleScalp(std::mt19937_64& rng, Eigen::Vector3d* normal) const {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (;;) {
    const double pick = uniform(rng) * cumulative_scalp_area_.back();
    const size_t i = static_cast<size_t>(
        std::lower_bound(cumulative_scalp_area_.begin(), cumulative_scalp_area_.end(), pick) -
        cumulative_scalp_area_.begin());
    const uint32_t t = scalp_triangles_[std::min(i, scalp_triangles_.size() - 1)];
    double a = uniform(rng), b = uniform(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    Eigen::Vector3d p = mesh_.Corner(t, 0) + a * (mesh_.Corner(t, 1) - mesh_.Corner(t, 0)) +
                        b * (mesh_.Corner(t, 2) - mesh_.Corner(t, 0));
    if (!OnScalp(p)) continue;  // triangles across the hairline or the parting
    const auto& tri = mesh_.triangles[t];
    Eigen::Vector3d n = (1 - a - b) * vertex_normals_[tri[0]] + a * vertex_normals_[tri[1]] +
                        b * vertex_normals_[tri[2]];
    if (!is_mesh()) {
      // Onto the exact ellipsoid.
      const Eigen::Vector3d q = (p - head_.center_turntable_mm).cwiseQuotient(head_.radii_mm);
      p = head_.center_turntable_mm + (q / q.norm()).cwiseProduct(head_.radii_mm);
      SignedDistance(p, &n);
    }
    *normal = n.normalized();
    return p;
  }
}

// The distance grid: exact distances to nearby triangles in a band around the
// surface, signed by the interpolated vertex normal at the closest point;
// beyond the band +-kBandMm, inside found by a flood fill from the grid's border.
Status HeadModel::BuildDistanceGrid() {
  const double margin = kBandMm + 2 * grid_step_mm_;
  grid_origin_ = mesh_.MinCorner().array() - margin;
  const Eigen::Vector3d extent =
      mesh_.MaxCorner() - grid_origin_ + Eigen::Vector3d::Constant(margin);
  for (int k = 0; k < 3; ++k)
    grid_size_[k] = static_cast<int>(std::ceil(extent[k] / grid_step_mm_)) + 1;
  const size_t cells = static_cast<size_t>(grid_size_.x()) * grid_size_.y() * grid_size_.z();
  if (cells > 64u * 1000 * 1000) {
    return InvalidArgument("head.mesh " + head_.mesh_file +
                           ": the mesh spans more than 64 million 2 mm cells; is it in mm?");
  }
  constexpr float kUnset = std::numeric_limits<float>::infinity();
  grid_.assign(cells, kUnset);
  std::vector<float> unsigned_distance(cells, kUnset);
  const auto index = [&](int x, int y, int z) {
    return (static_cast<size_t>(z) * grid_size_.y() + y) * grid_size_.x() + x;
  };
  const int reach = static_cast<int>(std::ceil(kBandMm / grid_step_mm_));
  for (size_t t = 0; t < mesh_.num_triangles(); ++t) {
    const Eigen::Vector3d lo =
        mesh_.Corner(t, 0).cwiseMin(mesh_.Corner(t, 1)).cwiseMin(mesh_.Corner(t, 2));
    const Eigen::Vector3d hi =
        mesh_.Corner(t, 0).cwiseMax(mesh_.Corner(t, 1)).cwiseMax(mesh_.Corner(t, 2));
    Eigen::Vector3i a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::max(
          0, static_cast<int>(std::floor((lo[k] - grid_origin_[k]) / grid_step_mm_)) - reach);
      b[k] =
          std::min(grid_size_[k] - 1,
                   static_cast<int>(std::ceil((hi[k] - grid_origin_[k]) / grid_step_mm_)) + reach);
    }
    const auto& tri = mesh_.triangles[t];
    for (int z = a.z(); z <= b.z(); ++z) {
      for (int y = a.y(); y <= b.y(); ++y) {
        for (int x = a.x(); x <= b.x(); ++x) {
          const Eigen::Vector3d p = grid_origin_ + grid_step_mm_ * Eigen::Vector3d(x, y, z);
          const Eigen::Vector3d c =
              ClosestOnTriangle(p, mesh_.Corner(t, 0), mesh_.Corner(t, 1), mesh_.Corner(t, 2));
          const double d = (p - c).norm();
          const size_t i = index(x, y, z);
          if (d >= kBandMm || d >= unsigned_distance[i]) continue;
          unsigned_distance[i] = static_cast<float>(d);
          // Sign from the smooth normal at the closest point (barycentric weights by areas).
          const Eigen::Vector3d n0 = vertex_normals_[tri[0]], n1 = vertex_normals_[tri[1]],
                                n2 = vertex_normals_[tri[2]];
          const double w0 = (mesh_.Corner(t, 1) - c).cross(mesh_.Corner(t, 2) - c).norm();
          const double w1 = (mesh_.Corner(t, 2) - c).cross(mesh_.Corner(t, 0) - c).norm();
          const double w2 = (mesh_.Corner(t, 0) - c).cross(mesh_.Corner(t, 1) - c).norm();
          const Eigen::Vector3d n = w0 * n0 + w1 * n1 + w2 * n2;
          grid_[i] = static_cast<float>((p - c).dot(n) >= 0 ? d : -d);
        }
      }
    }
  }
  // Flood fill the outside from the border through cells that are unset or outside.
  std::vector<uint8_t> outside(cells, 0);
  std::deque<Eigen::Vector3i> queue;
  const auto push = [&](int x, int y, int z) {
    if (x < 0 || y < 0 || z < 0 || x >= grid_size_.x() || y >= grid_size_.y() ||
        z >= grid_size_.z())
      return;
    const size_t i = index(x, y, z);
    if (outside[i] || grid_[i] < 0) return;
    outside[i] = 1;
    if (grid_[i] == kUnset) queue.emplace_back(x, y, z);  // band cells stop the fill
  };
  for (int z = 0; z < grid_size_.z(); ++z)
    for (int y = 0; y < grid_size_.y(); ++y)
      for (int x = 0; x < grid_size_.x(); ++x)
        if (x == 0 || y == 0 || z == 0 || x == grid_size_.x() - 1 || y == grid_size_.y() - 1 ||
            z == grid_size_.z() - 1)
          push(x, y, z);
  while (!queue.empty()) {
    const Eigen::Vector3i c = queue.front();
    queue.pop_front();
    push(c.x() + 1, c.y(), c.z()), push(c.x() - 1, c.y(), c.z());
    push(c.x(), c.y() + 1, c.z()), push(c.x(), c.y() - 1, c.z());
    push(c.x(), c.y(), c.z() + 1), push(c.x(), c.y(), c.z() - 1);
  }
  for (size_t i = 0; i < cells; ++i) {
    if (grid_[i] == kUnset) grid_[i] = static_cast<float>(outside[i] ? kBandMm : -kBandMm);
  }
  return Status::Ok();
}

double HeadModel::GridDistance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d g = (p - grid_origin_) / grid_step_mm_;
  // Outside the grid: the distance to its box plus the band.
  Eigen::Vector3d clamped;
  for (int k = 0; k < 3; ++k) clamped[k] = std::clamp(g[k], 0.0, grid_size_[k] - 1.0001);
  const double outside_mm = (g - clamped).norm() * grid_step_mm_;
  const int x = static_cast<int>(clamped.x()), y = static_cast<int>(clamped.y()),
            z = static_cast<int>(clamped.z());
  const double fx = clamped.x() - x, fy = clamped.y() - y, fz = clamped.z() - z;
  const auto at = [&](int dx, int dy, int dz) {
    return static_cast<double>(
        grid_[(static_cast<size_t>(z + dz) * grid_size_.y() + (y + dy)) * grid_size_.x() +
              (x + dx)]);
  };
  const double c00 = at(0, 0, 0) * (1 - fx) + at(1, 0, 0) * fx,
               c10 = at(0, 1, 0) * (1 - fx) + at(1, 1, 0) * fx;
  const double c01 = at(0, 0, 1) * (1 - fx) + at(1, 0, 1) * fx,
               c11 = at(0, 1, 1) * (1 - fx) + at(1, 1, 1) * fx;
  const double d = (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz;
  return outside_mm > 0 ? kBandMm + outside_mm : d;
}

}  // namespace hairrig
