// Strands grown along a field converge: two roots' strands that meet follow
// the same field line from then on, one on top of the other (on the demo
// capture half the grown samples past 200 mm lie within 0.05 mm of another
// strand, against a median spacing of 0.37 mm between true strands). Such a
// strand adds no hair where it runs on top of another, only a second copy
// that splits a true strand's matches between the two.
//
// EndMergedStrands ends each strand where it has merged into an earlier one
// (in the set's order): where its vertices have run within `distance_mm` of
// the kept polylines of earlier strands for `run_mm` of arc length, it is cut
// at the start of that run. Deterministic; single-threaded (the order
// matters), a few seconds for 5 million vertices. Units mm, any frame.
#pragma once

#include <cstdint>

#include "core/status.h"
#include "core/strands.h"

namespace hairrig {

struct StrandMergeOptions {
  double distance_mm = 0.1;  // closer than this (in [0.01, 10]), a vertex lies on an earlier strand
  // ... for this long (arc length), the strand has merged. 0 (the default)
  // turns it off: on the demo capture it cut half the strands and brought the
  // median length to the truth's, but left consistency where it was and cost
  // 0.02 of precision (docs/accuracy.md, "Strands").
  double run_mm = 0;

  Status Check() const;
};

struct StrandMergeSummary {
  int64_t strands_ended = 0;     // cut where they merged
  int64_t strands_dropped = 0;   // merged from their root: fewer than 2 vertices left
  int64_t vertices_removed = 0;  // those of the dropped strands included
};

// `strands` with every merged strand cut (strands left with fewer than 2
// vertices dropped; colours are not kept). Returns the input unchanged
// when run_mm is 0.
StrandSet EndMergedStrands(const StrandSet& strands, const StrandMergeOptions& options,
                           StrandMergeSummary* summary = nullptr);

}  // namespace hairrig
