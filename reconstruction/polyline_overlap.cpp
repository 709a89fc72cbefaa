#include "reconstruction/polyline_overlap.h"

#include <algorithm>
#include <limits>
#include <memory>

#include "core/parallel.h"
#include "reconstruction/point_grid.h"

namespace hairrig {

namespace {

// Per other owner that an owner overlaps: how many of its queried vertices
// have that owner within reach, and the vote of their tangents.
struct OverlapTally {
  uint32_t other = 0;
  int overlapped = 0, votes = 0;
};

// Tallies one owner's overlaps at a time. Per-owner marks (which query,
// which tally last saw that owner) make every lookup O(1); one per thread.
class OverlapTallier {
 public:
  OverlapTallier(const PolylineVertexTable& table, const PointGrid& grid,
                 const std::vector<uint32_t>& owner_by_slot, double overlap_mm, int stride)
      : table_(table),
        grid_(grid),
        owner_by_slot_(owner_by_slot),
        overlap_mm_(overlap_mm),
        stride_(static_cast<uint32_t>(stride)) {
    const size_t n = table.owners();
    query_mark_.assign(n, kNone);
    query_slot_.assign(n, 0);
    tally_mark_.assign(n, kNone);
    tally_slot_.assign(n, 0);
  }

  std::vector<OverlapTally> Tally(uint32_t s) {
    std::vector<OverlapTally> tallies;
    for (uint32_t v = table_.first[s]; v < table_.first[s + 1]; v += stride_) {
      NearestOthers(s, v);
      for (const Near& n : nearest_) {
        if (tally_mark_[n.owner] != s) {
          tally_mark_[n.owner] = s;
          tally_slot_[n.owner] = static_cast<uint32_t>(tallies.size());
          tallies.push_back({n.owner, 0, 0});
        }
        OverlapTally& t = tallies[tally_slot_[n.owner]];
        ++t.overlapped;
        t.votes += table_.tangents[v].dot(table_.tangents[n.vertex]) >= 0 ? 1 : -1;
      }
    }
    std::sort(tallies.begin(), tallies.end(),
              [](const OverlapTally& a, const OverlapTally& b) { return a.other < b.other; });
    return tallies;
  }

 private:
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  struct Near {
    uint32_t owner, vertex;
    double d2;
  };

  // nearest_: per other owner within reach of vertex v, its nearest vertex
  // (while visiting, its grid slot).
  void NearestOthers(uint32_t s, uint32_t v) {
    nearest_.clear();
    ++query_id_;
    grid_.ForEachSlotWithin(table_.positions[v], overlap_mm_, [&](uint32_t slot, double d2) {
      const uint32_t other = owner_by_slot_[slot];
      if (other == s) return;
      if (query_mark_[other] != query_id_) {
        query_mark_[other] = query_id_;
        query_slot_[other] = static_cast<uint32_t>(nearest_.size());
        nearest_.push_back({other, slot, d2});
      } else if (d2 < nearest_[query_slot_[other]].d2) {
        nearest_[query_slot_[other]].vertex = slot;
        nearest_[query_slot_[other]].d2 = d2;
      }
    });
    for (Near& n : nearest_) n.vertex = grid_.order()[n.vertex];
  }

  const PolylineVertexTable& table_;
  const PointGrid& grid_;
  const std::vector<uint32_t>& owner_by_slot_;  // table_.owner in the grid's slot order
  double overlap_mm_;
  uint32_t stride_;
  std::vector<uint32_t> query_mark_, query_slot_, tally_mark_, tally_slot_;
  std::vector<Near> nearest_;
  uint32_t query_id_ = 0;
};

}  // namespace

Eigen::Vector3f PolylineTangent(const std::vector<Eigen::Vector3f>& p, size_t i) {
  const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, p.size() - 1);
  const Eigen::Vector3f d = p[b] - p[a];
  return d.norm() > 0 ? Eigen::Vector3f(d.normalized()) : Eigen::Vector3f::Zero();
}

void PolylineVertexTable::Append(const std::vector<Eigen::Vector3f>& polyline) {
  const uint32_t o = static_cast<uint32_t>(first.size()) - 1;
  for (size_t k = 0; k < polyline.size(); ++k) {
    positions.push_back(polyline[k]);
    tangents.push_back(PolylineTangent(polyline, k));
    owner.push_back(o);
  }
}

PolylineVertexTable TabulatePolylines(
    const std::vector<const std::vector<Eigen::Vector3f>*>& polylines) {
  PolylineVertexTable table;
  for (const std::vector<Eigen::Vector3f>* polyline : polylines) {
    table.StartOwner();
    table.Append(*polyline);
  }
  table.Close();
  return table;
}

std::vector<OwnerOverlap> FindOwnerOverlaps(const PolylineVertexTable& table, double overlap_mm,
                                            int stride, int threads) {
  const size_t n = table.owners();
  const PointGrid grid(table.positions, overlap_mm);
  std::vector<std::vector<OverlapTally>> seen(n);
  std::vector<uint32_t> owner_by_slot(grid.order().size());
  for (size_t k = 0; k < owner_by_slot.size(); ++k) owner_by_slot[k] = table.owner[grid.order()[k]];
  ParallelFor(n, threads, [&] {
    auto tallier = std::make_shared<OverlapTallier>(table, grid, owner_by_slot, overlap_mm, stride);
    return [&seen, tallier](size_t s) { seen[s] = tallier->Tally(static_cast<uint32_t>(s)); };
  });
  const auto queried = [&](uint32_t s) {
    return (table.vertices(s) + static_cast<uint32_t>(stride) - 1) / static_cast<uint32_t>(stride);
  };
  const auto by_other = [](const OverlapTally& t, uint32_t other) { return t.other < other; };
  std::vector<OwnerOverlap> overlaps;
  for (uint32_t s = 0; s < n; ++s) {
    for (const OverlapTally& tally : seen[s]) {
      if (tally.other < s)
        continue;  // each pair once, from its lower index; the other side's count joins it
      OwnerOverlap overlap{s, tally.other, tally.overlapped, tally.votes, 0.0};
      const auto& back_list = seen[tally.other];
      const auto back = std::lower_bound(back_list.begin(), back_list.end(), s, by_other);
      if (back != back_list.end() && back->other == s) {
        overlap.overlapped += back->overlapped, overlap.votes += back->votes;
      }
      overlap.share = static_cast<double>(overlap.overlapped) /
                      static_cast<double>(queried(s) + queried(tally.other));
      overlaps.push_back(overlap);
    }
  }
  return overlaps;
}

void KeepStrongestOverlaps(size_t owners, int keep, std::vector<OwnerOverlap>* overlaps) {
  // Each owner's overlaps, as indices into *overlaps, in compressed rows.
  std::vector<uint32_t> row(owners + 1, 0);
  for (const OwnerOverlap& v : *overlaps) ++row[v.a + 1], ++row[v.b + 1];
  for (size_t s = 0; s < owners; ++s) row[s + 1] += row[s];
  std::vector<uint32_t> index(row.back());
  std::vector<uint32_t> fill(row.begin(), row.end() - 1);
  for (uint32_t i = 0; i < overlaps->size(); ++i) {
    index[fill[(*overlaps)[i].a]++] = i;
    index[fill[(*overlaps)[i].b]++] = i;
  }
  std::vector<uint8_t> kept(overlaps->size(), 0);
  const auto stronger = [&](uint32_t x, uint32_t y) {
    const double sx = (*overlaps)[x].share, sy = (*overlaps)[y].share;
    return sx != sy ? sx > sy : x < y;
  };
  for (size_t s = 0; s < owners; ++s) {
    const auto begin = index.begin() + row[s], end = index.begin() + row[s + 1];
    const auto last = end - begin > keep ? begin + keep : end;
    if (last != end) std::nth_element(begin, last, end, stronger);
    for (auto it = begin; it != last; ++it) kept[*it] = 1;
  }
  size_t out = 0;
  for (size_t i = 0; i < overlaps->size(); ++i) {
    if (kept[i]) (*overlaps)[out++] = (*overlaps)[i];
  }
  overlaps->resize(out);
}

}  // namespace hairrig
