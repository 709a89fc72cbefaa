#include "reconstruction/strand_merging.h"

#include <Eigen/Core>
#include <cmath>
#include <vector>

namespace hairrig {

namespace {

// The kept vertices of the strands processed so far, in cells of twice the
// merge distance: a point's neighbours within the distance lie in the 2 x 2 x 2
// cells around it. Open addressing; each cell heads a list of vertices.
class VertexGrid {
 public:
  VertexGrid(size_t vertices, double distance_mm)
      : cell_mm_(2 * distance_mm), distance2_(distance_mm * distance_mm) {
    size_t capacity = 1024;
    while (capacity < 2 * vertices) capacity *= 2;
    keys_.assign(capacity, kEmpty);
    heads_.assign(capacity, kNone);
    next_.reserve(vertices);
    points_.reserve(vertices);
  }

  void Insert(const Eigen::Vector3f& p) {
    const uint32_t id = static_cast<uint32_t>(points_.size());
    points_.push_back(p);
    const size_t slot = Slot(Key(Cell(p, 0, 0, 0)));
    next_.push_back(heads_[slot]);
    heads_[slot] = id;
  }

  bool AnyWithin(const Eigen::Vector3f& p) const {
    // The lower corner of the 2 x 2 x 2 block: the cell of p - distance.
    const Eigen::Vector3f corner = p.array() - static_cast<float>(0.5 * cell_mm_);
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int64_t key = Key(Cell(corner, dx, dy, dz));
          const size_t slot = Find(key);
          if (slot == kNoSlot) continue;
          for (uint32_t v = heads_[slot]; v != kNone; v = next_[v])
            if ((points_[v] - p).squaredNorm() < distance2_) return true;
        }
    return false;
  }

 private:
  static constexpr int64_t kEmpty = INT64_MIN;
  static constexpr uint32_t kNone = UINT32_MAX;
  static constexpr size_t kNoSlot = SIZE_MAX;

  Eigen::Vector3i Cell(const Eigen::Vector3f& p, int dx, int dy, int dz) const {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / cell_mm_)) + dx,
                           static_cast<int>(std::floor(p.y() / cell_mm_)) + dy,
                           static_cast<int>(std::floor(p.z() / cell_mm_)) + dz);
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    // 21 bits per axis: +-1 million cells, +-200 m at 0.2 mm.
    const auto part = [](int v) { return static_cast<int64_t>(v & 0x1fffff); };
    return part(c.x()) | (part(c.y()) << 21) | (part(c.z()) << 42);
  }
  size_t Hash(int64_t key) const {
    return static_cast<size_t>((static_cast<uint64_t>(key) * 0x9e3779b97f4a7c15ULL) >> 7) &
           (keys_.size() - 1);
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

  double cell_mm_, distance2_;
  std::vector<int64_t> keys_;
  std::vector<uint32_t> heads_, next_;
  std::vector<Eigen::Vector3f> points_;
};

// How many leading vertices of `strand` to keep: up to the start of the first
// run of at least run_mm on earlier strands.
size_t KeptVertices(const Eigen::Vector3f* strand, size_t count, const VertexGrid& grid,
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

}  // namespace

Status StrandMergeOptions::Check() const {
  if (!(distance_mm > 0)) return InvalidArgument("strand merge distance_mm must be positive");
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
  VertexGrid grid(strands.num_points(), options.distance_mm);
  const std::vector<size_t> offsets = strands.Offsets();
  StrandSet out;
  for (size_t k = 0; k < strands.num_strands(); ++k) {
    const Eigen::Vector3f* first = strands.points_mm.data() + offsets[k];
    const size_t count = offsets[k + 1] - offsets[k];
    const size_t kept = KeptVertices(first, count, grid, options.run_mm);
    s.vertices_removed += static_cast<int64_t>(count - kept);
    if (kept < count) ++(kept < 2 ? s.strands_dropped : s.strands_ended);
    if (kept < 2) continue;
    std::vector<Eigen::Vector3f> strand(first, first + kept);
    for (const Eigen::Vector3f& p : strand) grid.Insert(p);
    out.AddStrand(strand);
  }
  if (summary != nullptr) *summary = s;
  return out;
}

}  // namespace hairrig
