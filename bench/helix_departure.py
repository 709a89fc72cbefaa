#!/usr/bin/env python3
"""How grown strands leave the seen strands they followed: the turn at the step where they leave,
and whether the strand still lies on the true hair in the steps after.

    /usr/bin/python3 bench/helix_departure.py GROUND_TRUTH_STRANDS.ply STRANDS.ply SEGMENTS.ply
        [--strands N] [--seed S]

GROUND_TRUTH_STRANDS.ply is a simulated capture's ground_truth/ground_truth_strands.ply;
STRANDS.ply and SEGMENTS.ply a reconstruction's strands.ply and its directed seen strands
(segments.ply), all hairrig strand PLYs (bench/strand_tips.py). For N strands drawn at random
(3000 by default), a vertex follows a seen strand where a segment vertex lies within 1 mm and the
segment's tangent within 20 deg of the strand's (either way along). Where a strand leaves after
following for 5 or more vertices, the script records the angle between its last two steps and, for
each of the next 12 vertices while it follows none, whether a true strand sample lies within 3 mm
with its tangent within 30 deg (directed: the evaluation's precision test at 3 mm, 30 deg).
Prints the departures, their median turn, and that share at each vertex after leaving.

Needs Debian's python3-numpy and python3-scipy.
"""
import argparse
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from seen_tip_truth import load, tangents  # noqa: E402

FOLLOW_MM, FOLLOW_DEG, MIN_RUN, AFTER = 1.0, 20.0, 5, 12
MATCH_MM, MATCH_DEG = 3.0, 30.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("truth")
    parser.add_argument("strands")
    parser.add_argument("segments")
    parser.add_argument("--strands", dest="count", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=5)
    args = parser.parse_args()
    truth_p, truth_o = load(args.truth)
    strand_p, strand_o = load(args.strands)
    seg_p, seg_o = load(args.segments)
    truth_t, strand_t, seg_t = (tangents(truth_p, truth_o), tangents(strand_p, strand_o),
                                tangents(seg_p, seg_o))
    truth_tree, seg_tree = cKDTree(truth_p), cKDTree(seg_p)
    cos_match, cos_follow = np.cos(np.radians(MATCH_DEG)), np.cos(np.radians(FOLLOW_DEG))
    rng = np.random.default_rng(args.seed)
    drawn = rng.choice(len(strand_o) - 1, min(args.count, len(strand_o) - 1), replace=False)
    turns, on_truth = [], [[] for _ in range(AFTER)]
    for s in drawn:
        a, b = strand_o[s], strand_o[s + 1]
        distance, nearest = seg_tree.query(strand_p[a:b])
        follows = (distance < FOLLOW_MM) & (
            np.abs(np.sum(seg_t[nearest] * strand_t[a:b], axis=1)) > cos_follow)
        run = 0
        for k in range(1, b - a):
            if follows[k]:
                run += 1
                continue
            if follows[k - 1] and run >= MIN_RUN:
                turn = np.clip(strand_t[a + k - 1] @ strand_t[a + k], -1, 1)
                turns.append(np.degrees(np.arccos(turn)))
                for j in range(AFTER):
                    if k + j >= b - a or follows[k + j]:
                        break
                    near = truth_tree.query_ball_point(strand_p[a + k + j], MATCH_MM)
                    on_truth[j].append(bool(near) and
                                       bool(np.any(truth_t[near] @ strand_t[a + k + j] >= cos_match)))
            run = 0
    if not turns:
        sys.exit("no strand follows a seen strand for %d vertices and leaves it" % MIN_RUN)
    print("departures: %d after following %d or more vertices; median turn at the departure "
          "%.1f deg" % (len(turns), MIN_RUN, np.median(turns)))
    print("vertices after leaving, departures still off every seen strand, share on a true strand "
          "(%.0f mm, %.0f deg):" % (MATCH_MM, MATCH_DEG))
    for j, hits in enumerate(on_truth):
        if hits:
            print("  %2d  %6d  %.3f" % (j + 1, len(hits), np.mean(hits)))


if __name__ == "__main__":
    main()
