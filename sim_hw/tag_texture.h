// AprilTag bit patterns for the renderer, taken from libapriltag's own family
// tables (so the simulated tags are exactly what the detector decodes).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// A tag as a square grid of cells, row 0 at the top as printed, including the
// outer white border: for tag36h11, 10 x 10 cells whose inner 8 x 8 are the
// black border and the data bits. cells[row * width + col] is true for white.
struct TagPattern {
  int width = 0;
  std::vector<bool> white;
  bool IsWhite(int col, int row) const { return white[static_cast<size_t>(row * width + col)]; }
};

// NotFound for an id the family does not have; InvalidArgument for a family
// other than tag36h11.
Result<TagPattern> MakeTagPattern(const std::string& family, int id);

}  // namespace hairrig
