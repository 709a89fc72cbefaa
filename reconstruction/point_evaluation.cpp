#include "reconstruction/point_evaluation.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <utility>

#include "core/parallel.h"

namespace hairrig {
namespace {

// Cells further than this many cell sizes from the origin are not kept (their keys must fit 63
// bits).
constexpr double kMaxCellIndex = 1 << 20;
// Query samples per ParallelFor item.
constexpr size_t kChunk = 1024;

// The thresholds as the inner loop compares them: squared distance and cosine.
struct Criteria {
  std::vector<float> max_d2;   // -1: never met
  std::vector<float> min_cos;  // of the unsigned or directed angle
  std::vector<char> usable;
  size_t num_usable = 0;
  double cell_mm = 1;
};

Criteria MakeCriteria(const std::vector<MatchThreshold>& thresholds) {
  Criteria c;
  double largest = 0;
  for (const MatchThreshold& t : thresholds) {
    const bool usable = std::isfinite(t.distance_mm) && t.distance_mm >= 0 && t.angle_deg >= 0;
    c.usable.push_back(usable ? 1 : 0);
    c.max_d2.push_back(usable ? static_cast<float>(t.distance_mm * t.distance_mm) : -1.f);
    // A small slack so that equal directions meet a 0 degree threshold despite rounding.
    const double cosine =
        t.angle_deg >= 180 ? -2.0 : std::cos(t.angle_deg * std::numbers::pi / 180) - 1e-6;
    c.min_cos.push_back(static_cast<float>(cosine));
    if (usable) {
      ++c.num_usable;
      largest = std::max(largest, t.distance_mm);
    }
  }
  c.cell_mm = largest > 0 ? largest : 1.0;
  return c;
}

// Integer cells of size cell_mm, keyed x fastest inside the bounding box of all kept samples grown
// by one cell on every side, so that a neighbour's key is the cell's key plus a fixed offset and
// never aliases another cell.
struct CellFrame {
  double cell_mm = 1;
  std::array<int64_t, 3> low{};           // smallest cell index minus one, per axis
  std::array<uint64_t, 3> size{1, 1, 1};  // cells per axis including the padding

  // False for a sample that is not finite or too far out.
  bool CellOf(const Eigen::Vector3f& p, std::array<int64_t, 3>* cell) const {
    for (int k = 0; k < 3; ++k) {
      const double s = std::floor(static_cast<double>(p[k]) / cell_mm);
      if (!(std::abs(s) <= kMaxCellIndex)) return false;
      (*cell)[static_cast<size_t>(k)] = static_cast<int64_t>(s);
    }
    return true;
  }
  uint64_t Key(const std::array<int64_t, 3>& c) const {
    return (static_cast<uint64_t>(c[2] - low[2]) * size[1] + static_cast<uint64_t>(c[1] - low[1])) *
               size[0] +
           static_cast<uint64_t>(c[0] - low[0]);
  }
  // Key difference of the neighbour (dx, dy, dz), two's complement.
  uint64_t Offset(int dx, int dy, int dz) const {
    const auto nx = static_cast<int64_t>(size[0]), nxy = static_cast<int64_t>(size[0] * size[1]);
    return static_cast<uint64_t>(dx + dy * nx + dz * nxy);
  }
};

bool Usable(const OrientedSample& s, const CellFrame& frame, std::array<int64_t, 3>* cell,
            Eigen::Vector3f* dir) {
  const float length = s.direction.norm();
  if (!(length > 0) || !std::isfinite(length) || !frame.CellOf(s.position_mm, cell)) return false;
  *dir = s.direction / length;
  return true;
}

CellFrame MakeFrame(const std::vector<OrientedSample>& a, const std::vector<OrientedSample>& b,
                    double cell_mm) {
  CellFrame frame;
  frame.cell_mm = cell_mm;
  std::array<int64_t, 3> lo{}, hi{}, cell{};
  bool any = false;
  Eigen::Vector3f dir;
  for (const auto* set : {&a, &b}) {
    for (const OrientedSample& s : *set) {
      if (!Usable(s, frame, &cell, &dir)) continue;
      for (size_t k = 0; k < 3; ++k) {
        lo[k] = any ? std::min(lo[k], cell[k]) : cell[k];
        hi[k] = any ? std::max(hi[k], cell[k]) : cell[k];
      }
      any = true;
    }
  }
  for (size_t k = 0; k < 3; ++k) {
    frame.low[k] = lo[k] - 1;
    frame.size[k] = static_cast<uint64_t>(hi[k] - lo[k]) + 3;
  }
  return frame;
}

struct KeyIndex {
  uint64_t key;
  size_t index;
};

// Stable LSD radix sort by key, 11 bits a pass, passes where every key has the same digit skipped.
void RadixSort(std::vector<KeyIndex>* items, uint64_t max_key) {
  constexpr unsigned kBits = 11;
  constexpr size_t kBuckets = size_t{1} << kBits;
  std::vector<KeyIndex> buffer(items->size());
  for (unsigned shift = 0; shift < 64 && (max_key >> shift) != 0; shift += kBits) {
    std::vector<size_t> start(kBuckets, 0);
    for (const KeyIndex& it : *items) ++start[(it.key >> shift) & (kBuckets - 1)];
    if (std::find(start.begin(), start.end(), items->size()) != start.end()) continue;
    size_t sum = 0;
    for (size_t& s : start) sum += std::exchange(s, sum);
    for (const KeyIndex& it : *items) buffer[start[(it.key >> shift) & (kBuckets - 1)]++] = it;
    items->swap(buffer);
  }
}

// One sample set sorted by cell.
struct Grid {
  std::vector<Eigen::Vector3f> position;   // kept samples in cell order
  std::vector<Eigen::Vector3f> direction;  // unit
  std::vector<uint64_t> cell_key;          // occupied cells, increasing
  std::vector<size_t>
      cell_begin;  // cell i holds [cell_begin[i], cell_begin[i + 1]); size cells + 1
  std::vector<size_t>
      source;  // with keep_source: each kept sample's index in the input, else empty
};

Grid BuildGrid(const std::vector<OrientedSample>& samples, const CellFrame& frame,
               bool keep_source) {
  Grid grid;
  std::vector<KeyIndex> items;
  items.reserve(samples.size());
  std::array<int64_t, 3> cell{};
  Eigen::Vector3f dir;
  uint64_t max_key = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (!Usable(samples[i], frame, &cell, &dir)) continue;
    items.push_back({frame.Key(cell), i});
    max_key = std::max(max_key, items.back().key);
  }
  RadixSort(&items, max_key);
  grid.position.resize(items.size());
  grid.direction.resize(items.size());
  if (keep_source) grid.source.resize(items.size());
  for (size_t k = 0; k < items.size(); ++k) {
    const OrientedSample& s = samples[items[k].index];
    grid.position[k] = s.position_mm;
    grid.direction[k] = s.direction.normalized();
    if (keep_source) grid.source[k] = items[k].index;
    if (k == 0 || items[k].key != items[k - 1].key) {
      grid.cell_key.push_back(items[k].key);
      grid.cell_begin.push_back(k);
    }
  }
  grid.cell_begin.push_back(items.size());
  return grid;
}

// First index >= from whose key is >= key (keys increasing): galloping, as the queries of a chunk
// come in order.
size_t SearchFrom(const std::vector<uint64_t>& keys, size_t from, uint64_t key) {
  size_t lo = from, step = 1;
  while (lo < keys.size() && keys[lo] < key) {
    const size_t probe = lo + step;
    if (probe >= keys.size() || keys[probe] >= key) {
      const auto end = keys.begin() + static_cast<std::ptrdiff_t>(std::min(probe, keys.size()));
      return static_cast<size_t>(
          std::lower_bound(keys.begin() + static_cast<std::ptrdiff_t>(lo) + 1, end, key) -
          keys.begin());
    }
    lo = probe + 1;
    step *= 2;
  }
  return lo;
}

// The occupied target cells around each query sample's cell, nearest first (the own cell, faces,
// edges, corners), for the query samples of a chunk (kChunk of them, in cell order) one after the
// other.
class TargetCells {
 public:
  struct Neighbour {
    size_t begin = 0, end = 0;    // target samples [begin, end)
    std::array<int, 3> offset{};  // cell offset from the query's cell
  };

  TargetCells(const Grid& queries, const Grid& targets, const CellFrame& frame)
      : queries_(queries), targets_(targets), frame_(frame) {}

  // Calls visit(q) for every query sample q of `chunk`, in order, with the neighbours of q's cell
  // current.
  template <typename Visit>
  void ForEachQuery(size_t chunk, Visit&& visit) {
    const size_t begin = chunk * kChunk, end = std::min(queries_.position.size(), begin + kChunk);
    const std::vector<size_t>& starts = queries_.cell_begin;
    size_t cell = static_cast<size_t>(std::upper_bound(starts.begin(), starts.end(), begin) -
                                      starts.begin() - 1);
    cursors_.fill(0);
    EnterCell(cell);
    for (size_t q = begin; q < end; ++q) {
      while (starts[cell + 1] <= q) EnterCell(++cell);
      visit(q);
    }
  }

  int size() const { return num_neighbours_; }
  const Neighbour& operator[](int n) const { return neighbours_[static_cast<size_t>(n)]; }

 private:
  void EnterCell(size_t cell) {
    const uint64_t key = queries_.cell_key[cell];
    const std::vector<uint64_t>& keys = targets_.cell_key;
    num_neighbours_ = 0;
    size_t row = 0;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy, ++row) {
        const uint64_t first = key + frame_.Offset(-1, dy, dz);
        size_t j = cursors_[row] = SearchFrom(keys, cursors_[row], first);
        for (; j < keys.size() && keys[j] <= first + 2; ++j) {
          Neighbour& n = neighbours_[static_cast<size_t>(num_neighbours_++)];
          n.begin = targets_.cell_begin[j];
          n.end = targets_.cell_begin[j + 1];
          n.offset = {static_cast<int>(keys[j] - first) - 1, dy, dz};
        }
      }
    }
    const auto rank = [](const Neighbour& n) {
      return std::abs(n.offset[0]) + std::abs(n.offset[1]) + std::abs(n.offset[2]);
    };
    std::sort(neighbours_.begin(), neighbours_.begin() + num_neighbours_,
              [&](const Neighbour& a, const Neighbour& b) { return rank(a) < rank(b); });
  }

  const Grid& queries_;
  const Grid& targets_;
  const CellFrame& frame_;
  std::array<size_t, 9> cursors_{};
  std::array<Neighbour, 27> neighbours_{};
  int num_neighbours_ = 0;
};

// Squared distances from a point to the faces of its cell, below and above per axis: BoxDistance2
// is a lower bound of the squared distance from the point to anything in a neighbour cell.
class CellFaces {
 public:
  CellFaces(const Eigen::Vector3f& p, double cell_mm) {
    for (size_t k = 0; k < 3; ++k) {
      const double s = static_cast<double>(p[static_cast<int>(k)]) / cell_mm;
      const double u = (s - std::floor(s)) * cell_mm;
      below_[k] = u * u;
      above_[k] = (cell_mm - u) * (cell_mm - u);
    }
  }
  double BoxDistance2(const std::array<int, 3>& offset) const {
    double box2 = 0;
    for (size_t k = 0; k < 3; ++k)
      box2 += offset[k] < 0 ? below_[k] : offset[k] > 0 ? above_[k] : 0.0;
    return box2;
  }
  // False when the cell at `offset` lies beyond `reach2` (a squared distance), with a margin for
  // rounding.
  bool CanReach(const std::array<int, 3>& offset, float reach2) const {
    return BoxDistance2(offset) <= static_cast<double>(reach2) * (1 + 1e-6) + 1e-9;
  }

 private:
  std::array<double, 3> below_{}, above_{};
};

// Counts, per threshold, the query samples that have a target sample within it; one per thread.
class Matcher {
 public:
  Matcher(const Grid& queries, const Grid& targets, const CellFrame& frame,
          const Criteria& criteria, bool directed, std::vector<int64_t>* counts)
      : queries_(queries),
        targets_(targets),
        frame_(frame),
        cells_(queries, targets, frame),
        criteria_(criteria),
        directed_(directed),
        counts_(counts),
        met_(criteria.usable.size(), 0) {}

  void operator()(size_t chunk) {
    cells_.ForEachQuery(chunk, [this](size_t q) { Match(q); });
  }

 private:
  void Match(size_t q) {
    const Eigen::Vector3f p = queries_.position[q], d = queries_.direction[q];
    std::fill(met_.begin(), met_.end(), 0);
    size_t unmet = criteria_.num_usable;
    float reach2 = NeededReach2();
    const CellFaces faces(p, frame_.cell_mm);
    for (int n = 0; n < cells_.size() && unmet > 0; ++n) {
      const TargetCells::Neighbour& nb = cells_[n];
      if (!faces.CanReach(nb.offset, reach2)) continue;
      for (size_t j = nb.begin; j < nb.end; ++j) {
        const float d2 = (targets_.position[j] - p).squaredNorm();
        if (d2 > reach2) continue;
        float c = targets_.direction[j].dot(d);
        if (!directed_) c = std::fabs(c);
        bool changed = false;
        for (size_t t = 0; t < met_.size(); ++t) {
          if (!met_[t] && d2 <= criteria_.max_d2[t] && c >= criteria_.min_cos[t]) {
            met_[t] = 1;
            --unmet;
            changed = true;
          }
        }
        if (!changed) continue;
        if (unmet == 0) break;
        reach2 = NeededReach2();
      }
    }
    for (size_t t = 0; t < met_.size(); ++t) (*counts_)[t] += met_[t];
  }

  // The largest distance of the thresholds not met yet, squared.
  float NeededReach2() const {
    float r2 = 0;
    for (size_t t = 0; t < met_.size(); ++t) {
      if (criteria_.usable[t] && !met_[t]) r2 = std::max(r2, criteria_.max_d2[t]);
    }
    return r2;
  }

  const Grid& queries_;
  const Grid& targets_;
  const CellFrame& frame_;
  TargetCells cells_;
  const Criteria& criteria_;
  bool directed_;
  std::vector<int64_t>* counts_;
  std::vector<char> met_;
};

// For each query sample, the input index of the nearest target sample within one threshold (ties:
// the lower index), -1 when none; one per thread. The grids keep their sources.
class NearestFinder {
 public:
  NearestFinder(const Grid& queries, const Grid& targets, const CellFrame& frame, float max_d2,
                float min_cos, bool directed, std::vector<int64_t>* nearest)
      : queries_(queries),
        targets_(targets),
        frame_(frame),
        cells_(queries, targets, frame),
        max_d2_(max_d2),
        min_cos_(min_cos),
        directed_(directed),
        nearest_(nearest) {}

  void operator()(size_t chunk) {
    cells_.ForEachQuery(chunk, [this](size_t q) { Find(q); });
  }

 private:
  void Find(size_t q) {
    const Eigen::Vector3f p = queries_.position[q], d = queries_.direction[q];
    const CellFaces faces(p, frame_.cell_mm);
    float best2 = max_d2_;
    int64_t best = -1;
    for (int n = 0; n < cells_.size(); ++n) {
      const TargetCells::Neighbour& nb = cells_[n];
      if (!faces.CanReach(nb.offset, best2)) continue;
      for (size_t j = nb.begin; j < nb.end; ++j) {
        const float d2 = (targets_.position[j] - p).squaredNorm();
        if (d2 > best2) continue;
        float c = targets_.direction[j].dot(d);
        if (!directed_) c = std::fabs(c);
        if (c < min_cos_) continue;
        const auto source = static_cast<int64_t>(targets_.source[j]);
        if (best < 0 || d2 < best2 || source < best) {
          best = source;
          best2 = d2;
        }
      }
    }
    (*nearest_)[queries_.source[q]] = best;  // each query sample is one thread's
  }

  const Grid& queries_;
  const Grid& targets_;
  const CellFrame& frame_;
  TargetCells cells_;
  float max_d2_, min_cos_;
  bool directed_;
  std::vector<int64_t>* nearest_;
};

std::vector<int64_t> CountMatched(const Grid& queries, const Grid& targets, const CellFrame& frame,
                                  const Criteria& criteria, bool directed, int threads) {
  const size_t num_threads = static_cast<size_t>(std::max(1, threads));
  std::vector<std::vector<int64_t>> counts(num_threads,
                                           std::vector<int64_t>(criteria.usable.size(), 0));
  if (criteria.num_usable > 0 && !targets.position.empty()) {
    std::atomic<size_t> next_slot{0};
    ParallelFor((queries.position.size() + kChunk - 1) / kChunk, threads, [&] {
      return Matcher(queries, targets, frame, criteria, directed, &counts[next_slot++]);
    });
  }
  std::vector<int64_t> total(criteria.usable.size(), 0);
  for (const auto& c : counts) {
    for (size_t t = 0; t < total.size(); ++t) total[t] += c[t];
  }
  return total;
}

void SampleStrand(const Eigen::Vector3f* points, size_t count, double step_mm,
                  std::vector<OrientedSample>* out) {
  const bool densify = step_mm > 0 && std::isfinite(step_mm);
  Eigen::Vector3f last_dir = Eigen::Vector3f::Zero();
  for (size_t i = 0; i + 1 < count; ++i) {
    const Eigen::Vector3f segment = points[i + 1] - points[i];
    const float length = segment.norm();
    if (!(length > 0) || !std::isfinite(length)) continue;
    last_dir = segment / length;
    const size_t pieces =
        densify ? std::max<size_t>(
                      1, static_cast<size_t>(std::ceil(static_cast<double>(length) / step_mm)))
                : 1;
    for (size_t k = 0; k < pieces; ++k) {
      const float f = static_cast<float>(k) / static_cast<float>(pieces);
      out->push_back({points[i] + f * segment, last_dir});
    }
  }
  if (count > 0 && last_dir != Eigen::Vector3f::Zero() && points[count - 1].allFinite()) {
    out->push_back({points[count - 1], last_dir});
  }
}

double F1(double precision, double recall) {
  return precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0;
}

}  // namespace

std::vector<MatchThreshold> DefaultMatchThresholds() {
  return {{1, 10}, {2, 20}, {3, 30}, {4, 40}, {4, 90}};
}

std::vector<MatchScore> MatchSamples(const std::vector<OrientedSample>& estimate,
                                     const std::vector<OrientedSample>& truth,
                                     const std::vector<MatchThreshold>& thresholds,
                                     const SampleMatchOptions& options) {
  const Criteria criteria = MakeCriteria(thresholds);
  const CellFrame frame = MakeFrame(estimate, truth, criteria.cell_mm);
  Grid estimate_grid, truth_grid;
  ParallelFor(2, options.threads, [&] {
    return [&](size_t i) {
      (i == 0 ? estimate_grid : truth_grid) =
          BuildGrid(i == 0 ? estimate : truth, frame, /*keep_source=*/false);
    };
  });
  const std::vector<int64_t> matched_estimate =
      CountMatched(estimate_grid, truth_grid, frame, criteria, options.directed, options.threads);
  const std::vector<int64_t> matched_truth =
      CountMatched(truth_grid, estimate_grid, frame, criteria, options.directed, options.threads);
  std::vector<MatchScore> scores(thresholds.size());
  for (size_t t = 0; t < thresholds.size(); ++t) {
    MatchScore& s = scores[t];
    s.threshold = thresholds[t];
    s.matched_estimate = matched_estimate[t];
    s.matched_truth = matched_truth[t];
    s.precision = estimate.empty() ? 0
                                   : static_cast<double>(s.matched_estimate) /
                                         static_cast<double>(estimate.size());
    s.recall = truth.empty()
                   ? 0
                   : static_cast<double>(s.matched_truth) / static_cast<double>(truth.size());
    s.f1 = F1(s.precision, s.recall);
  }
  return scores;
}

SubsetMatchScores MatchSamplesAndSubset(const std::vector<OrientedSample>& estimate,
                                        const std::vector<OrientedSample>& truth,
                                        const std::vector<uint8_t>& truth_in_subset,
                                        const std::vector<MatchThreshold>& thresholds,
                                        const SampleMatchOptions& options) {
  SubsetMatchScores out;
  out.all = MatchSamples(estimate, truth, thresholds, options);
  if (truth_in_subset.size() != truth.size()) return out;
  std::vector<OrientedSample> subset;
  for (size_t i = 0; i < truth.size(); ++i)
    if (truth_in_subset[i] != 0) subset.push_back(truth[i]);
  out.subset_size = static_cast<int64_t>(subset.size());
  out.subset = MatchSamples(estimate, subset, thresholds, options);
  // An estimate sample is right when it lies on any true strand, seen or not.
  for (size_t t = 0; t < out.subset.size(); ++t) {
    MatchScore& s = out.subset[t];
    s.matched_estimate = out.all[t].matched_estimate;
    s.precision = out.all[t].precision;
    s.f1 = F1(s.precision, s.recall);
  }
  return out;
}

std::vector<int64_t> NearestMatches(const std::vector<OrientedSample>& estimate,
                                    const std::vector<OrientedSample>& truth,
                                    const MatchThreshold& threshold,
                                    const SampleMatchOptions& options) {
  std::vector<int64_t> nearest(truth.size(), -1);
  const Criteria criteria = MakeCriteria({threshold});
  if (criteria.num_usable == 0 || estimate.empty() || truth.empty()) return nearest;
  const CellFrame frame = MakeFrame(estimate, truth, criteria.cell_mm);
  Grid estimate_grid, truth_grid;
  ParallelFor(2, options.threads, [&] {
    return [&](size_t i) {
      (i == 0 ? estimate_grid : truth_grid) =
          BuildGrid(i == 0 ? estimate : truth, frame, /*keep_source=*/true);
    };
  });
  if (estimate_grid.position.empty()) return nearest;
  ParallelFor((truth_grid.position.size() + kChunk - 1) / kChunk, options.threads, [&] {
    return NearestFinder(truth_grid, estimate_grid, frame, criteria.max_d2[0], criteria.min_cos[0],
                         options.directed, &nearest);
  });
  return nearest;
}

nlohmann::json ScoresToJson(const std::vector<MatchScore>& scores) {
  nlohmann::json out = nlohmann::json::array();
  for (const MatchScore& s : scores) {
    out.push_back({{"distance_mm", s.threshold.distance_mm},
                   {"angle_deg", s.threshold.angle_deg},
                   {"precision", s.precision},
                   {"recall", s.recall},
                   {"f1", s.f1}});
  }
  return out;
}

std::vector<OrientedSample> SampleStrands(const std::vector<std::vector<Eigen::Vector3f>>& strands,
                                          double step_mm) {
  std::vector<OrientedSample> samples;
  for (const auto& strand : strands) SampleStrand(strand.data(), strand.size(), step_mm, &samples);
  return samples;
}

std::vector<OrientedSample> SampleStrands(const StrandSet& strands, double step_mm) {
  return SampleStrands(strands, step_mm, nullptr);
}

std::vector<OrientedSample> SampleStrands(const StrandSet& strands, double step_mm,
                                          std::vector<uint32_t>* sample_strand) {
  std::vector<OrientedSample> samples;
  if (sample_strand != nullptr) sample_strand->clear();
  size_t first = 0;
  for (size_t k = 0; k < strands.point_counts.size(); ++k) {
    const uint32_t count = strands.point_counts[k];
    if (count > strands.points_mm.size() - first)
      break;  // counts inconsistent with the points (see StrandSet::Check)
    SampleStrand(strands.points_mm.data() + first, count, step_mm, &samples);
    if (sample_strand != nullptr) sample_strand->resize(samples.size(), static_cast<uint32_t>(k));
    first += count;
  }
  return samples;
}

}  // namespace hairrig
