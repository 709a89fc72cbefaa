#include "reconstruction/strand_merging.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "reconstruction/point_segment_distance.h"

namespace hairrig {

namespace {

// The kept pieces (segments between consecutive vertices) of the strands
// processed so far, filed under the cell of their midpoint. Cells are
// 2 (distance + longest half piece) wide, so a piece within the distance of
// p has its midpoint in the 2 x 2 x 2 cells around p. Open addressing; each
// cell heads a list of pieces.
class PieceGrid {
 public:
  PieceGrid(size_t pieces, double distance_mm, double longest_piece_mm)
      : cell_mm_(2 * (distance_mm + 0.5 * longest_piece_mm)),
        distance2_(static_cast<float>(distance_mm * distance_mm)) {
    size_t capacity = 1024;
    int bits = 10;
    while (capacity < 2 * pieces) capacity *= 2, ++bits;
    shift_ = 64 - bits;
    keys_.assign(capacity, kEmpty);
    heads_.assign(capacity, kNone);
    next_.reserve(pieces);
    ends_.reserve(pieces);
  }

  void Insert(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const size_t id = ends_.size();
    ends_.push_back({a, b});
    const size_t slot = Slot(Key(Cell(0.5f * (a + b), 0, 0, 0)));
    next_.push_back(heads_[slot]);
    heads_[slot] = id;
  }

  bool AnyWithin(const Eigen::Vector3f& p) const {
    // The lower corner of the 2 x 2 x 2 block: the cell of p - half a cell.
    const Eigen::Vector3f corner = p.array() - static_cast<float>(0.5 * cell_mm_);
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const size_t slot = Find(Key(Cell(corner, dx, dy, dz)));
          if (slot == kNoSlot) continue;
          for (size_t v = heads_[slot]; v != kNone; v = next_[v])
            if (PointSegmentDistance2(p, ends_[v][0], ends_[v][1]) < distance2_) return true;
        }
    return false;
  }

 private:
  static constexpr int64_t kEmpty = INT64_MIN;
  static constexpr size_t kNone = SIZE_MAX;
  static constexpr size_t kNoSlot = SIZE_MAX;

  Eigen::Vector3i Cell(const Eigen::Vector3f& p, int dx, int dy, int dz) const {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / cell_mm_)) + dx,
                           static_cast<int>(std::floor(p.y() / cell_mm_)) + dy,
                           static_cast<int>(std::floor(p.z() / cell_mm_)) + dz);
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    // 21 bits per axis (cells further apart share keys; distances are checked).
    const auto part = [](int v) { return static_cast<int64_t>(v & 0x1fffff); };
    return part(c.x()) | (part(c.y()) << 21) | (part(c.z()) << 42);
  }
  // Fibonacci hashing: the product's top bits depend on every bit of the key.
  size_t Hash(int64_t key) const {
    return static_cast<size_t>((static_cast<uint64_t>(key) * 0x9e3779b97f4a7c15ULL) >> shift_);
  }
  // The slot holding `key`, claimed if new.
  size_t Slot(int64_t key) {
    size_t s = Hash(key);
    while (keys_[s] != kEmpty && keys_[s] != key) s = (s + 1) & (keys_.size() - 1);
    keys_[s] = key;
    return s;
  }
  size_t Find(int64_t key) const {
    for (size_t s = Hash(key);; s = (s + 1) & (keys_.size() - 1)) {
      if (keys_[s] == key) return s;
      if (keys_[s] == kEmpty) return kNoSlot;
    }
  }

  double cell_mm_;
  float distance2_;
  int shift_ = 54;
  std::vector<int64_t> keys_;
  std::vector<size_t> heads_, next_;
  std::vector<std::array<Eigen::Vector3f, 2>> ends_;
};

// How many leading vertices of `strand` to keep: up to the start of the first
// run of at least run_mm (arc length) on earlier strands.
size_t KeptVertices(const Eigen::Vector3f* strand, size_t count, const PieceGrid& grid,
                    double run_mm) {
  bool in_run = false;
  double run = 0;
  size_t run_start = 0;
  for (size_t i = 0; i < count; ++i) {
    if (!grid.AnyWithin(strand[i])) {
      in_run = false;
      continue;
    }
    if (!in_run) {
      in_run = true;
      run = 0;
      run_start = i;
      continue;
    }
    run += (strand[i] - strand[i - 1]).norm();
    if (run >= run_mm) return run_start + 1;
  }
  return count;
}

double LongestPiece(const StrandSet& strands, const std::vector<size_t>& offsets) {
  double longest = 0;
  for (size_t k = 0; k + 1 < offsets.size(); ++k)
    for (size_t i = offsets[k] + 1; i < offsets[k + 1]; ++i)
      longest = std::max(longest, double((strands.points_mm[i] - strands.points_mm[i - 1]).norm()));
  return longest;
}

}  // namespace

Status StrandMergeOptions::Check() const {
  if (!(distance_mm >= 0.01 && distance_mm <= 10))
    return InvalidArgument("strand merge distance_mm must lie in [0.01, 10]");
  if (!(run_mm >= 0)) return InvalidArgument("strand merge run_mm must be non-negative (0 = off)");
  return Status::Ok();
}

StrandSet EndMergedStrands(const StrandSet& strands, const StrandMergeOptions& options,
                           StrandMergeSummary* summary) {
  StrandMergeSummary s;
  if (options.run_mm <= 0) {
    if (summary != nullptr) *summary = s;
    return strands;
  }
  const std::vector<size_t> offsets = strands.Offsets();
  PieceGrid grid(strands.num_points(), options.distance_mm, LongestPiece(strands, offsets));
  StrandSet out;
  for (size_t k = 0; k < strands.num_strands(); ++k) {
    const Eigen::Vector3f* first = strands.points_mm.data() + offsets[k];
    const size_t count = offsets[k + 1] - offsets[k];
    const size_t kept = KeptVertices(first, count, grid, options.run_mm);
    if (kept < 2) {
      ++s.strands_dropped;
      s.vertices_removed += static_cast<int64_t>(count);
      continue;
    }
    if (kept < count) ++s.strands_ended;
    s.vertices_removed += static_cast<int64_t>(count - kept);
    for (size_t i = 1; i < kept; ++i) grid.Insert(first[i - 1], first[i]);
    out.AddStrand(std::vector<Eigen::Vector3f>(first, first + kept));
  }
  if (summary != nullptr) *summary = s;
  return out;
}

}  // namespace hairrig
