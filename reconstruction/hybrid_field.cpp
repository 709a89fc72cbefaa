#include "reconstruction/hybrid_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "reconstruction/central_gradient.h"
#include "reconstruction/point_grid.h"
#include "reconstruction/polyline_overlap.h"

namespace hairrig {

namespace {

constexpr int64_t kMaxVoxels = int64_t{64} << 20;

struct Grid {
  Eigen::Vector3i size;
  int64_t Index(int x, int y, int z) const {
    return x + static_cast<int64_t>(size.x()) * (y + static_cast<int64_t>(size.y()) * z);
  }
  int64_t count() const { return static_cast<int64_t>(size.x()) * size.y() * size.z(); }
};

// One SOR update of voxel i from its n neighbours nb[0 .. n), summed in
// that order, for each of its `channels` values.
template <int kChannels>
inline void SorUpdate(float* v, int64_t i, const int64_t* nb, int n, int channels) {
  constexpr float kOmega = 1.7f;
  const int count = kChannels > 0 ? kChannels : channels;
  for (int c = 0; c < count; ++c) {
    float sum = 0;
    for (int k = 0; k < n; ++k) sum += v[nb[k] * count + c];
    float& value = v[i * count + c];
    value += kOmega * (sum / static_cast<float>(n) - value);
  }
}

// Gauss-Seidel sweeps in x-fastest order. A voxel off the grid's faces has
// all six neighbours (taken -x, +x, -y, +y, -z, +z, as at the faces, where
// the missing ones are left out), so the arithmetic is the same everywhere.
// kChannels: the channel count when known at compile time, 0 otherwise.
template <int kChannels>
void SorSweepsOf(const Grid& g, int channels, const std::vector<uint8_t>& fixed,
                 std::vector<float>* values, int sweeps) {
  float* v = values->data();
  const int nx = g.size.x(), ny = g.size.y(), nz = g.size.z();
  const int64_t sx = 1, sy = nx, sz = static_cast<int64_t>(nx) * ny;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (int z = 0; z < nz; ++z)
      for (int y = 0; y < ny; ++y) {
        const bool inner_row = y > 0 && y + 1 < ny && z > 0 && z + 1 < nz;
        for (int x = 0; x < nx; ++x) {
          const int64_t i = g.Index(x, y, z);
          if (fixed[i]) continue;
          std::array<int64_t, 6> nb;
          int n = 0;
          if (inner_row && x > 0 && x + 1 < nx) {
            nb = {i - sx, i + sx, i - sy, i + sy, i - sz, i + sz};
            n = 6;
          } else {
            if (x > 0) nb[n++] = i - sx;
            if (x + 1 < nx) nb[n++] = i + sx;
            if (y > 0) nb[n++] = i - sy;
            if (y + 1 < ny) nb[n++] = i + sy;
            if (z > 0) nb[n++] = i - sz;
            if (z + 1 < nz) nb[n++] = i + sz;
          }
          SorUpdate<kChannels>(v, i, nb.data(), n, channels);
        }
      }
  }
}

void SorSweeps(const Grid& g, int channels, const std::vector<uint8_t>& fixed,
               std::vector<float>* values, int sweeps) {
  if (channels == 1) return SorSweepsOf<1>(g, channels, fixed, values, sweeps);
  if (channels == 3) return SorSweepsOf<3>(g, channels, fixed, values, sweeps);
  SorSweepsOf<0>(g, channels, fixed, values, sweeps);
}

// Approximate Euclidean distance (voxels) to the nearest `source` voxel: a
// two-pass chamfer transform with 26-neighbour weights 1, sqrt 2, sqrt 3.
std::vector<float> ChamferDistance(const Grid& g, const std::vector<uint8_t>& source) {
  constexpr float kFar = 1e9f;
  std::vector<float> d(static_cast<size_t>(g.count()), kFar);
  for (int64_t i = 0; i < g.count(); ++i)
    if (source[i]) d[i] = 0;
  const auto pass = [&](int direction) {
    const int z0 = direction > 0 ? 0 : g.size.z() - 1, z1 = direction > 0 ? g.size.z() : -1;
    const int y0 = direction > 0 ? 0 : g.size.y() - 1, y1 = direction > 0 ? g.size.y() : -1;
    const int x0 = direction > 0 ? 0 : g.size.x() - 1, x1 = direction > 0 ? g.size.x() : -1;
    for (int z = z0; z != z1; z += direction)
      for (int y = y0; y != y1; y += direction)
        for (int x = x0; x != x1; x += direction) {
          float best = d[g.Index(x, y, z)];
          // The 13 neighbours already visited in this pass's order.
          for (int dz = -1; dz <= 0; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0))) continue;
                const int nx = x + dx * direction, ny = y + dy * direction, nz = z + dz * direction;
                if (nx < 0 || ny < 0 || nz < 0 || nx >= g.size.x() || ny >= g.size.y() ||
                    nz >= g.size.z())
                  continue;
                const float step = std::sqrt(static_cast<float>(dx * dx + dy * dy + dz * dz));
                best = std::min(best, d[g.Index(nx, ny, nz)] + step);
              }
          d[g.Index(x, y, z)] = best;
        }
  };
  pass(1);
  pass(-1);
  return d;
}

}  // namespace

void SolveLaplace(const Eigen::Vector3i& size, int channels, const std::vector<uint8_t>& fixed,
                  std::vector<float>* values, int sweeps_per_level) {
  const Grid g{size};
  if (size.minCoeff() >= 8) {
    const Grid coarse{(size.array() + 1) / 2};
    std::vector<float> coarse_values(static_cast<size_t>(coarse.count() * channels), 0.0f);
    std::vector<uint8_t> coarse_fixed(static_cast<size_t>(coarse.count()), 0);
    std::vector<int> counts(static_cast<size_t>(coarse.count()), 0);
    for (int z = 0; z < size.z(); ++z)
      for (int y = 0; y < size.y(); ++y)
        for (int x = 0; x < size.x(); ++x) {
          const int64_t i = g.Index(x, y, z);
          if (!fixed[i]) continue;
          const int64_t c = coarse.Index(x / 2, y / 2, z / 2);
          coarse_fixed[c] = 1;
          ++counts[c];
          for (int k = 0; k < channels; ++k)
            coarse_values[c * channels + k] += (*values)[i * channels + k];
        }
    for (int64_t c = 0; c < coarse.count(); ++c)
      for (int k = 0; k < channels && counts[c] > 0; ++k)
        coarse_values[c * channels + k] /= static_cast<float>(counts[c]);
    SolveLaplace(coarse.size, channels, coarse_fixed, &coarse_values, sweeps_per_level);
    for (int z = 0; z < size.z(); ++z)
      for (int y = 0; y < size.y(); ++y)
        for (int x = 0; x < size.x(); ++x) {
          const int64_t i = g.Index(x, y, z);
          if (fixed[i]) continue;
          const int64_t c = coarse.Index(x / 2, y / 2, z / 2);
          for (int k = 0; k < channels; ++k)
            (*values)[i * channels + k] = coarse_values[c * channels + k];
        }
  }
  SorSweeps(g, channels, fixed, values, sweeps_per_level);
}

Status HybridFieldOptions::Check() const {
  if (!(voxel_mm > 0)) return InvalidArgument("field voxel_mm must be positive");
  if (!(margin_mm >= 0)) return InvalidArgument("field margin_mm must be non-negative");
  if (sweeps_per_level < 1) return InvalidArgument("field sweeps_per_level must be at least 1");
  if (!(ribbon_min_length_mm >= 0))
    return InvalidArgument("field ribbon_min_length_mm must be non-negative");
  return Status::Ok();
}

struct HybridOrientationField::SegmentIndex {
  std::vector<Eigen::Vector3f> positions, tangents;
  std::unique_ptr<PointGrid> grid;  // over `positions`, which stay put
};

std::shared_ptr<const HybridOrientationField::SegmentIndex> HybridOrientationField::IndexSegments(
    const std::vector<StrandSegment>& segments) {
  auto index = std::make_shared<SegmentIndex>();
  for (const StrandSegment& s : segments) {
    for (size_t k = 0; k < s.points_mm.size(); ++k) {
      const Eigen::Vector3f t = PolylineTangent(s.points_mm, k);
      if (t.isZero()) continue;
      index->positions.push_back(s.points_mm[k]);
      index->tangents.push_back(t);
    }
  }
  index->grid = std::make_unique<PointGrid>(index->positions, 1.0);
  return index;
}

bool HybridOrientationField::NearestSegmentTangent(const Eigen::Vector3f& p, double radius_mm,
                                                   Eigen::Vector3f* tangent) const {
  if (!segment_index_) return false;
  // A vertex within radius_mm of p puts every voxel centre around p within
  // radius_mm + sqrt(3) voxel_mm of a segment's voxel; the chamfer distance
  // (within a few % of the Euclidean) stays under this bound there, and is
  // cheaper to read than the point grid.
  if (SegmentDistance(p) > radius_mm + 3 * voxel_mm_) return false;
  const int64_t found = segment_index_->grid->Nearest(p, radius_mm);
  if (found < 0) return false;
  *tangent = segment_index_->tangents[static_cast<size_t>(found)];
  return true;
}

Result<HybridOrientationField> HybridOrientationField::Build(
    const std::vector<StrandSegment>& segments, const std::vector<DirectedRoot>& roots,
    const HeadModel* head, const HybridFieldOptions& o) {
  HR_RETURN_IF_ERROR(o.Check());
  if (segments.empty())
    return InvalidArgument("the hybrid field needs at least one strand segment");
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const StrandSegment& s : segments)
    for (const Eigen::Vector3f& p : s.points_mm) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (const DirectedRoot& r : roots)
    lo = lo.cwiseMin(r.position_mm), hi = hi.cwiseMax(r.position_mm);
  HybridOrientationField f;
  f.voxel_mm_ = o.voxel_mm;
  f.directed_ = o.directed;
  f.origin_ = lo.array() - static_cast<float>(o.margin_mm);
  const Eigen::Vector3f extent = (hi - lo).array() + static_cast<float>(2 * o.margin_mm);
  f.size_ = (extent / static_cast<float>(o.voxel_mm)).array().ceil().cast<int>() + 1;
  const Grid g{f.size_};
  if (g.count() > kMaxVoxels) {
    return InvalidArgument(
        "the hybrid field's grid would have " + std::to_string(g.count()) +
        " voxels; the points span too much space (are they in mm?) or voxel_mm is too small");
  }
  const int channels = o.directed ? 3 : 6;
  const auto voxel_of = [&](const Eigen::Vector3f& p) {
    const Eigen::Vector3i v =
        ((p - f.origin_) / static_cast<float>(o.voxel_mm)).array().round().cast<int>();
    return g.Index(std::clamp(v.x(), 0, g.size.x() - 1), std::clamp(v.y(), 0, g.size.y() - 1),
                   std::clamp(v.z(), 0, g.size.z() - 1));
  };
  const auto store = [&](std::vector<float>* field, int64_t i, const Eigen::Vector3f& d) {
    float* out = field->data() + i * channels;
    if (o.directed) {
      out[0] = d.x(), out[1] = d.y(), out[2] = d.z();
    } else {
      out[0] = d.x() * d.x(), out[1] = d.y() * d.y(), out[2] = d.z() * d.z();
      out[3] = d.x() * d.y(), out[4] = d.x() * d.z(), out[5] = d.y() * d.z();
    }
  };
  const size_t n = static_cast<size_t>(g.count());
  f.interior_.assign(n * channels, 0.0f);
  f.surface_.assign(n * channels, 0.0f);
  std::vector<uint8_t> interior_fixed(n, 0), surface_fixed(n, 0), hair_boundary(n, 0), ribbon(n, 0);
  for (const StrandSegment& s : segments) {
    const bool is_ribbon = s.Length() >= o.ribbon_min_length_mm;
    for (size_t k = 0; k < s.points_mm.size(); ++k) {
      const size_t a = k == 0 ? 0 : k - 1, b = std::min(k + 1, s.points_mm.size() - 1);
      const Eigen::Vector3f t = (s.points_mm[b] - s.points_mm[a]).normalized();
      const int64_t i = voxel_of(s.points_mm[k]);
      store(&f.interior_, i, t);
      interior_fixed[i] = hair_boundary[i] = 1;
      if (is_ribbon) store(&f.surface_, i, t), surface_fixed[i] = ribbon[i] = 1;
    }
  }
  f.segment_index_ = IndexSegments(segments);
  for (const DirectedRoot& r : roots) {
    const int64_t i = voxel_of(r.position_mm);
    store(&f.interior_, i, r.direction);
    interior_fixed[i] = 1;
  }
  f.segment_distance_ = ChamferDistance(g, hair_boundary);  // segments only, before the head joins
  for (float& d : f.segment_distance_) d *= static_cast<float>(o.voxel_mm);
  ParallelFor(2, o.threads, [&] {
    return [&](size_t k) {
      if (k == 0) SolveLaplace(f.size_, channels, interior_fixed, &f.interior_, o.sweeps_per_level);
      if (k == 1) SolveLaplace(f.size_, channels, surface_fixed, &f.surface_, o.sweeps_per_level);
    };
  });

  // I_d: zero on the hair and in the head (above its hairline unless
  // whole_head_in_volume), the distance to them on the box's faces.
  if (head != nullptr) {
    for (int z = 0; z < g.size.z(); ++z)
      for (int y = 0; y < g.size.y(); ++y)
        for (int x = 0; x < g.size.x(); ++x) {
          const Eigen::Vector3d p =
              (f.origin_ + Eigen::Vector3i(x, y, z).cast<float>() * static_cast<float>(o.voxel_mm))
                  .cast<double>();
          if (head->SignedDistance(p, nullptr) < 0.5 * o.voxel_mm &&
              (o.whole_head_in_volume || head->AboveHairline(p)))
            hair_boundary[g.Index(x, y, z)] = 1;
        }
  }
  const std::vector<float> boundary_distance = ChamferDistance(g, hair_boundary);
  f.distance_.assign(n, 0.0f);
  std::vector<uint8_t> distance_fixed = hair_boundary;
  for (int z = 0; z < g.size.z(); ++z)
    for (int y = 0; y < g.size.y(); ++y)
      for (int x = 0; x < g.size.x(); ++x) {
        const bool face = x == 0 || y == 0 || z == 0 || x + 1 == g.size.x() ||
                          y + 1 == g.size.y() || z + 1 == g.size.z();
        const int64_t i = g.Index(x, y, z);
        if (!face || hair_boundary[i]) continue;
        distance_fixed[i] = 1;
        f.distance_[i] = boundary_distance[i] * static_cast<float>(o.voxel_mm);
      }
  SolveLaplace(f.size_, 1, distance_fixed, &f.distance_, o.sweeps_per_level);
  f.ribbon_distance_ = ChamferDistance(g, ribbon);
  for (float& d : f.ribbon_distance_) d *= static_cast<float>(o.voxel_mm);
  return f;
}

void HybridOrientationField::Sample(const std::vector<float>& field, int channels,
                                    const Eigen::Vector3f& p, float* out) const {
  const Grid g{size_};
  const Eigen::Vector3f u = (p - origin_) / static_cast<float>(voxel_mm_);
  int i0[3];
  float w[3];
  for (int a = 0; a < 3; ++a) {
    const float c = std::clamp(u[a], 0.0f, static_cast<float>(size_[a] - 1));
    i0[a] = std::min(static_cast<int>(std::floor(c)), size_[a] - 2 >= 0 ? size_[a] - 2 : 0);
    w[a] = size_[a] > 1 ? c - static_cast<float>(i0[a]) : 0.0f;
  }
  for (int c = 0; c < channels; ++c) out[c] = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const float weight = (dx ? w[0] : 1 - w[0]) * (dy ? w[1] : 1 - w[1]) * (dz ? w[2] : 1 - w[2]);
    if (weight == 0) continue;
    const int64_t i =
        g.Index(std::min(i0[0] + dx, size_.x() - 1), std::min(i0[1] + dy, size_.y() - 1),
                std::min(i0[2] + dz, size_.z() - 1));
    for (int c = 0; c < channels; ++c) out[c] += weight * field[i * channels + c];
  }
}

Eigen::Vector3f HybridOrientationField::Direction(const std::vector<float>& field,
                                                  const Eigen::Vector3f& p,
                                                  const Eigen::Vector3f& previous) const {
  float v[6];
  if (directed_) {
    Sample(field, 3, p, v);
    return Eigen::Vector3f(v[0], v[1], v[2]);
  }
  Sample(field, 6, p, v);
  Eigen::Matrix3f tensor;
  tensor << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eigen(tensor);
  Eigen::Vector3f d = eigen.eigenvectors().col(2) * std::max(eigen.eigenvalues()(2), 0.0f);
  if (d.dot(previous) < 0) d = -d;
  return d;
}

Eigen::Vector3f HybridOrientationField::Interior(const Eigen::Vector3f& p,
                                                 const Eigen::Vector3f& previous) const {
  return Direction(interior_, p, previous);
}

Eigen::Vector3f HybridOrientationField::Surface(const Eigen::Vector3f& p,
                                                const Eigen::Vector3f& previous) const {
  return Direction(surface_, p, previous);
}

double HybridOrientationField::Distance(const Eigen::Vector3f& p) const {
  float d;
  Sample(distance_, 1, p, &d);
  return d;
}

Eigen::Vector3f HybridOrientationField::DistanceGradient(const Eigen::Vector3f& p) const {
  return CentralGradient([this](const Eigen::Vector3f& q) { return Distance(q); }, p,
                         static_cast<float>(voxel_mm_));
}

double HybridOrientationField::RibbonDistance(const Eigen::Vector3f& p) const {
  float d;
  Sample(ribbon_distance_, 1, p, &d);
  return d;
}

double HybridOrientationField::SegmentDistance(const Eigen::Vector3f& p) const {
  float d;
  Sample(segment_distance_, 1, p, &d);
  return d;
}

bool HybridOrientationField::Contains(const Eigen::Vector3f& p) const {
  const Eigen::Vector3f u = (p - origin_) / static_cast<float>(voxel_mm_);
  return (u.array() >= 0).all() && (u.array() <= (size_.cast<float>().array() - 1)).all();
}

}  // namespace hairrig
