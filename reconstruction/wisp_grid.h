// Geometry shared by ribbons and wisps as grids of vertices
// (isocurves[j][i], j across, i along; every isocurve the same length; mm):
// points at fractional width, a spatial index over many grids' vertices, and
// projection onto a grid near one of its vertices. The wisps' steps
// (wisps.cpp, wisp_attachment.cpp, wisp_synthesis.cpp) use them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "reconstruction/point_grid.h"

namespace hairrig {

using Isocurves = std::vector<std::vector<Eigen::Vector3f>>;

// R^w_i: vertex i of the isocurve at width w (clamped to [0, W]), linear
// between the neighbouring isocurves.
Eigen::Vector3f IsocurvePoint(const Isocurves& grid, double w, int i);

// The vertices of several grids in one PointGrid, each knowing its grid and
// (j, i). The grids must outlive the index.
class GridVertexIndex {
 public:
  struct Owner {
    uint32_t grid;
    uint32_t j, i;
  };

  GridVertexIndex(const std::vector<const Isocurves*>& grids, double cell_mm);

  const PointGrid& points() const { return *grid_; }
  const Owner& owner(uint32_t vertex) const { return owners_[vertex]; }

 private:
  std::vector<Eigen::Vector3f> positions_;
  std::vector<Owner> owners_;
  std::unique_ptr<PointGrid> grid_;
};

// p projected onto the grid's triangles around vertex (j, i) (the four quads
// sharing it, each split along its (j, i)-(j+1, i+1) diagonal; the edges
// next to it for a grid of one isocurve).
struct GridProjection {
  float w = 0, l = 0;  // parameters of the closest point
  float distance_mm = 0;
  Eigen::Vector3f along = Eigen::Vector3f::Zero();  // unit direction of increasing l there
};
GridProjection ProjectNearVertex(const Isocurves& grid, int j, int i, const Eigen::Vector3f& p);

}  // namespace hairrig
