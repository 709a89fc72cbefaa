#include "core/mesh_bvh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace hairrig {
namespace {

constexpr uint32_t kMaxLeafTriangles = 4;
constexpr int kBins = 12;

struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  void Grow(const Eigen::Vector3d& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
  void Grow(const Bounds& b) { lo = lo.cwiseMin(b.lo), hi = hi.cwiseMax(b.hi); }
  double Area() const {
    if (!(hi.x() >= lo.x())) return 0;
    const Eigen::Vector3d d = hi - lo;
    return 2 * (d.x() * d.y() + d.y() * d.z() + d.z() * d.x());
  }
};

// Slab test of a ray against a float box; the entry distance in *t_enter.
bool HitsBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Eigen::Vector3d& origin,
             const Eigen::Vector3d& inv_dir, double t_min, double t_max, double* t_enter) {
  for (int k = 0; k < 3; ++k) {
    double t0 = (lo[k] - origin[k]) * inv_dir[k], t1 = (hi[k] - origin[k]) * inv_dir[k];
    if (t0 > t1) std::swap(t0, t1);
    t_min = std::max(t_min, t0);
    t_max = std::min(t_max, t1);
    if (t_min > t_max) return false;
  }
  *t_enter = t_min;
  return true;
}

}  // namespace

MeshBvh::MeshBvh(const TriangleMesh& mesh) {
  const auto n = static_cast<uint32_t>(mesh.num_triangles());
  if (n == 0) return;
  std::vector<Eigen::Vector3d> centroids(n);
  order_.resize(n);
  for (uint32_t t = 0; t < n; ++t) {
    order_[t] = t;
    centroids[t] = (mesh.Corner(t, 0) + mesh.Corner(t, 1) + mesh.Corner(t, 2)) / 3.0;
  }
  triangles_.resize(n);
  for (uint32_t t = 0; t < n; ++t) {
    triangles_[t] = {mesh.Corner(t, 0), mesh.Corner(t, 1) - mesh.Corner(t, 0),
                     mesh.Corner(t, 2) - mesh.Corner(t, 0)};
  }
  nodes_.reserve(2 * n);
  nodes_.emplace_back();
  Build(0, 0, n, centroids);
  // Triangles in leaf order, so a leaf reads a contiguous run.
  std::vector<Triangle> ordered(n);
  for (uint32_t i = 0; i < n; ++i) ordered[i] = triangles_[order_[i]];
  triangles_ = std::move(ordered);
}

// Fills `node` and its subtree over order_[begin, end); children take two
// consecutive slots appended to nodes_.
void MeshBvh::Build(uint32_t node, uint32_t begin, uint32_t end,
                    const std::vector<Eigen::Vector3d>& centroids) {
  Bounds box, centre_box;
  for (uint32_t i = begin; i < end; ++i) {
    const Triangle& t = triangles_[order_[i]];
    box.Grow(t.p0), box.Grow(t.p0 + t.e1), box.Grow(t.p0 + t.e2);
    centre_box.Grow(centroids[order_[i]]);
  }
  nodes_[node].lo = box.lo.cast<float>();
  nodes_[node].hi = box.hi.cast<float>();
  // Float bounds rounded outward so no triangle pokes out of its box.
  for (int k = 0; k < 3; ++k) {
    nodes_[node].lo[k] =
        std::nextafter(nodes_[node].lo[k], -std::numeric_limits<float>::infinity());
    nodes_[node].hi[k] = std::nextafter(nodes_[node].hi[k], std::numeric_limits<float>::infinity());
  }
  const uint32_t count = end - begin;
  const Eigen::Vector3d extent = centre_box.hi - centre_box.lo;
  int axis = 0;
  extent.maxCoeff(&axis);
  if (count <= kMaxLeafTriangles || !(extent[axis] > 0)) {
    nodes_[node].first = begin;
    nodes_[node].count = count;
    return;
  }
  // Binned surface-area heuristic along the widest centroid axis.
  std::array<Bounds, kBins> bins;
  std::array<uint32_t, kBins> bin_count{};
  const auto bin_of = [&](uint32_t tri) {
    const double f = (centroids[tri][axis] - centre_box.lo[axis]) / extent[axis];
    return std::min(kBins - 1, static_cast<int>(f * kBins));
  };
  for (uint32_t i = begin; i < end; ++i) {
    const int b = bin_of(order_[i]);
    const Triangle& t = triangles_[order_[i]];
    bins[static_cast<size_t>(b)].Grow(t.p0), bins[static_cast<size_t>(b)].Grow(t.p0 + t.e1);
    bins[static_cast<size_t>(b)].Grow(t.p0 + t.e2);
    ++bin_count[static_cast<size_t>(b)];
  }
  double best_cost = std::numeric_limits<double>::infinity();
  int best_split = kBins / 2;
  for (int split = 1; split < kBins; ++split) {
    Bounds left, right;
    uint32_t n_left = 0, n_right = 0;
    for (int b = 0; b < split; ++b)
      left.Grow(bins[static_cast<size_t>(b)]), n_left += bin_count[static_cast<size_t>(b)];
    for (int b = split; b < kBins; ++b)
      right.Grow(bins[static_cast<size_t>(b)]), n_right += bin_count[static_cast<size_t>(b)];
    if (n_left == 0 || n_right == 0) continue;
    const double cost = left.Area() * n_left + right.Area() * n_right;
    if (cost < best_cost) best_cost = cost, best_split = split;
  }
  auto* middle = std::partition(order_.data() + begin, order_.data() + end,
                                [&](uint32_t tri) { return bin_of(tri) < best_split; });
  auto mid = static_cast<uint32_t>(middle - order_.data());
  if (mid == begin || mid == end)
    mid = begin + count / 2;  // every centroid in one bin: split by count
  const auto left = static_cast<uint32_t>(nodes_.size());
  nodes_[node].first = left;
  nodes_[node].count = 0;
  nodes_.emplace_back();
  nodes_.emplace_back();
  Build(left, begin, mid, centroids);
  Build(left + 1, mid, end, centroids);
}

template <bool kAnyHit>
bool MeshBvh::Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                       double t_max, MeshRayHit* hit) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inv_dir(1.0 / dir.x(), 1.0 / dir.y(), 1.0 / dir.z());
  std::array<uint32_t, 64> stack;
  size_t top = 0;
  stack[top++] = 0;
  bool found = false;
  double t_enter = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!HitsBox(n.lo, n.hi, origin, inv_dir, t_min, t_max, &t_enter)) continue;
    if (n.count == 0) {
      // Visit the nearer child first: push it last.
      double t_left = 0, t_right = 0;
      const bool hit_left =
          HitsBox(nodes_[n.first].lo, nodes_[n.first].hi, origin, inv_dir, t_min, t_max, &t_left);
      const bool hit_right = HitsBox(nodes_[n.first + 1].lo, nodes_[n.first + 1].hi, origin,
                                     inv_dir, t_min, t_max, &t_right);
      if (hit_left && hit_right && top + 2 <= stack.size()) {
        const bool left_first = t_left <= t_right;
        stack[top++] = left_first ? n.first + 1 : n.first;
        stack[top++] = left_first ? n.first : n.first + 1;
      } else if (hit_left && top < stack.size()) {
        stack[top++] = n.first;
      } else if (hit_right && top < stack.size()) {
        stack[top++] = n.first + 1;
      }
      continue;
    }
    for (uint32_t i = n.first; i < n.first + n.count; ++i) {
      // Moeller-Trumbore, both sides.
      const Triangle& tri = triangles_[i];
      const Eigen::Vector3d p = dir.cross(tri.e2);
      const double det = tri.e1.dot(p);
      if (std::abs(det) < 1e-300) continue;
      const double inv_det = 1.0 / det;
      const Eigen::Vector3d s = origin - tri.p0;
      const double u = s.dot(p) * inv_det;
      if (u < 0 || u > 1) continue;
      const Eigen::Vector3d q = s.cross(tri.e1);
      const double v = dir.dot(q) * inv_det;
      if (v < 0 || u + v > 1) continue;
      const double t = tri.e2.dot(q) * inv_det;
      if (t <= t_min || t >= t_max) continue;
      if (kAnyHit) return true;
      t_max = t;
      found = true;
      hit->t = t;
      hit->triangle = order_[i];
      hit->u = u;
      hit->v = v;
    }
  }
  return found;
}

bool MeshBvh::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                        double t_max, MeshRayHit* hit) const {
  return Traverse<false>(origin, dir, t_min, t_max, hit);
}

bool MeshBvh::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                       double t_max) const {
  return Traverse<true>(origin, dir, t_min, t_max, nullptr);
}

bool MeshBvh::Contains(const Eigen::Vector3d& p) const {
  // An irrational-looking direction, so the ray does not graze edges of axis-aligned tessellations.
  const Eigen::Vector3d dir = Eigen::Vector3d(0.5377, 0.7318, 0.4187).normalized();
  int crossings = 0;
  double t = 0;
  MeshRayHit hit;
  while (crossings < 1000 && Intersect(p, dir, t, std::numeric_limits<double>::infinity(), &hit)) {
    ++crossings;
    t = hit.t + 1e-9;
  }
  return crossings % 2 == 1;
}

}  // namespace hairrig
