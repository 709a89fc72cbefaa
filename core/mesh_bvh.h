// Ray casting against a triangle mesh through a bounding-volume hierarchy
// (binned surface-area heuristic, at most 4 triangles per leaf). Built once,
// then const and safe to query from many threads. Units and frame are the
// mesh's; ray directions need not be unit length (t is in units of `dir`).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/triangle_mesh.h"

namespace hairrig {

struct MeshRayHit {
  double t = 0;           // origin + t * dir is the hit point
  uint32_t triangle = 0;  // index into the mesh's triangles
  double u = 0, v = 0;    // barycentric weights of corners 1 and 2
};

class MeshBvh {
 public:
  MeshBvh() = default;
  explicit MeshBvh(const TriangleMesh& mesh);

  // The nearest hit with t in (t_min, t_max), from either side of a triangle;
  // false if there is none.
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                 double t_max, MeshRayHit* hit) const;
  // Any hit with t in (t_min, t_max) (cheaper than Intersect: stops at the first).
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                double t_max) const;
  // Whether `p` lies inside the closed mesh (odd number of crossings along a fixed ray).
  bool Contains(const Eigen::Vector3d& p) const;

  size_t num_nodes() const { return nodes_.size(); }
  bool empty() const { return nodes_.empty(); }

 private:
  struct Node {
    Eigen::Vector3f lo, hi;
    uint32_t first = 0;  // leaf: first triangle in order_; inner: index of the left child
    uint32_t count = 0;  // leaf: number of triangles; inner: 0 (right child is left + 1)
  };
  struct Triangle {
    Eigen::Vector3d p0, e1, e2;
  };
  template <bool kAnyHit>
  bool Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                double t_max, MeshRayHit* hit) const;
  void Build(uint32_t node, uint32_t begin, uint32_t end,
             const std::vector<Eigen::Vector3d>& centroids);

  std::vector<Node> nodes_;
  std::vector<Triangle> triangles_;  // in leaf order
  std::vector<uint32_t> order_;      // leaf order -> mesh triangle index
};

}  // namespace hairrig
