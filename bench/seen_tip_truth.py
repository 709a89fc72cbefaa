#!/usr/bin/env python3
"""Whether the seen strands' tip ends lie where true strands end.

    /usr/bin/python3 bench/seen_tip_truth.py GROUND_TRUTH_STRANDS.ply SEGMENTS.ply
        [--window AHEAD_MM,LATERAL_MM,ANGLE_DEG] [--carry-on MM] [--min-length MM] [--probes N]
        [--points POINTS.ply [--points-ahead SHARE]]

GROUND_TRUTH_STRANDS.ply is a simulated capture's ground_truth/ground_truth_strands.ply;
SEGMENTS.ply the directed seen strands of its reconstruction
(reconstruction/strands/segments.ply). Both are hairrig strand PLYs (bench/strand_tips.py).

For a random sample of the seen strands at least --min-length long (0 by default; 40 mm is
SeenTipOptions::min_seen_length_mm) (--probes, 4000 by default), it looks at each one's tip
end and at its middle vertex. At each, the true strand samples within 2 mm whose tangent lies
within 30 deg of the seen strand's give how much of their true strand is left beyond them (the
median over those samples, mm along the strand). A tip end "at a true tip" has under 5 mm left.
The tips are split as reconstruction/seen_tips.h splits them: continued where another seen
strand has a vertex 1..AHEAD mm ahead along the tip's direction (the chord over its last three
steps), within LATERAL mm of that line, its tangent within ANGLE deg either way, and reaches
--carry-on mm or more ahead of the tip (9,2,45 and 12: the defaults of SeenTipOptions; 0 lets
any vertex in the window continue the tip). With --points (the reconstruction's points.ply) a
tip the oriented points run on past counts as continued too: 2-12 mm ahead, within 3 mm of its
line and 30 deg of its direction, at least --points-ahead (0.08, SeenTipOptions'
points_ahead_max_share) times as many points as as far behind it. Prints, for the uncontinued tips, the continued ones and the
middles, the share at a true tip and the share with more than 30 mm left.

Needs Debian's python3-numpy and python3-scipy.
"""
import argparse
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from strand_tips import read_strands  # noqa: E402


def load(path):
    """Vertices (n x 3, mm) and the offsets of each strand's first vertex (strands + 1)."""
    xyz, segments = read_strands(path)
    points = np.frombuffer(xyz, dtype=np.float32).reshape(-1, 3).astype(np.float64)
    counts = np.asarray(segments, dtype=np.int64) + 1
    return points, np.concatenate([[0], np.cumsum(counts)])


def unit(v):
    return v / (np.linalg.norm(v, axis=-1, keepdims=True) + 1e-12)


def tangents(points, offsets):
    """Forward differences, the last vertex of each strand taking its backward one."""
    t = np.zeros_like(points)
    t[:-1] = points[1:] - points[:-1]
    last = offsets[1:] - 1
    t[last] = points[last] - points[last - 1]
    return unit(t)


def remaining_length(points, offsets):
    """Arc length from each vertex to its strand's last vertex."""
    strand = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    step = np.append(np.linalg.norm(np.diff(points, axis=0), axis=1), 0.0)
    step[offsets[1:] - 1] = 0.0  # no step across strands
    to_end = np.cumsum(step[::-1])[::-1]
    return to_end - to_end[offsets[1:][strand] - 1]


class Truth:
    def __init__(self, path):
        self.points, offsets = load(path)
        self.tangents = tangents(self.points, offsets)
        self.left = remaining_length(self.points, offsets)
        self.tree = cKDTree(self.points)

    def left_at(self, places, directions):
        """Median true length left at each place (nan where no aligned true sample is near)."""
        out = np.full(len(places), np.nan)
        for k, near in enumerate(self.tree.query_ball_point(places, 2.0)):
            aligned = [j for j in near if abs(self.tangents[j] @ directions[k]) > np.cos(np.radians(30))]
            if aligned:
                out[k] = np.median(self.left[aligned])
        return out


def continued(seen, offsets, tree, owner, seen_tangents, k, tip, direction, window, carry_on):
    ahead_max, lateral, angle = window
    middle = tip + 0.5 * (1 + ahead_max) * direction
    for j in tree.query_ball_point(middle, np.hypot(0.5 * (ahead_max - 1), lateral)):
        if owner[j] == k:
            continue
        v = seen[j] - tip
        ahead = v @ direction
        if (1 <= ahead <= ahead_max and np.linalg.norm(v - ahead * direction) <= lateral
                and abs(seen_tangents[j] @ direction) >= np.cos(np.radians(angle))):
            other = seen[offsets[owner[j]]:offsets[owner[j] + 1]]
            if carry_on <= 0 or np.max((other - tip) @ direction) >= carry_on:
                return True
    return False


class PointsRunOn:
    """SeenTipOptions::points_ahead_max_share: whether the oriented points run on past a tip."""

    def __init__(self, path, share):
        from point_directions import read_points
        points = read_points(path).astype(np.float64)
        self.positions, self.directions = points[:, :3], points[:, 3:6]
        self.tree = cKDTree(self.positions)
        self.share = share

    def count(self, tip, direction, gap=2.0, length=10.0, lateral=3.0, angle=30.0):
        centre = tip + (gap + 0.5 * length) * direction
        near = np.asarray(self.tree.query_ball_point(centre, np.hypot(0.5 * length, lateral)), int)
        if len(near) == 0:
            return 0
        v = self.positions[near] - tip
        along = v @ direction
        off = np.linalg.norm(v - np.outer(along, direction), axis=1)
        aligned = np.abs(self.directions[near] @ direction) >= np.cos(np.radians(angle))
        return int(np.sum((along >= gap) & (along <= gap + length) & (off <= lateral) & aligned))

    def __call__(self, tip, direction):
        ahead = self.count(tip, direction)
        return ahead > 0 and ahead >= self.share * self.count(tip, -direction)


def report(label, left):
    known = left[~np.isnan(left)]
    if len(known) == 0:
        print(f"{label}: no true strand near")
        return
    print(f"{label}: {len(left)}, {len(known)} with a true strand near; at a true tip (< 5 mm left) "
          f"{np.mean(known < 5):.3f}, more than 30 mm left {np.mean(known > 30):.3f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("truth")
    parser.add_argument("segments")
    parser.add_argument("--window", default="9,2,45")
    parser.add_argument("--carry-on", type=float, default=12.0)
    parser.add_argument("--min-length", type=float, default=0.0)
    parser.add_argument("--probes", type=int, default=4000)
    parser.add_argument("--points", help="the reconstruction's points.ply: also leave out the tips "
                        "the oriented points run on past")
    parser.add_argument("--points-ahead", type=float, default=0.08)
    args = parser.parse_args()
    window = tuple(float(v) for v in args.window.split(","))
    if len(window) != 3:
        sys.exit("--window: expected AHEAD_MM,LATERAL_MM,ANGLE_DEG")
    truth = Truth(args.truth)
    seen, offsets = load(args.segments)
    owner = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    seen_tangents = tangents(seen, offsets)
    last = offsets[1:] - 1
    back = np.minimum(3, last - offsets[:-1])
    tips, tip_directions = seen[last], unit(seen[last] - seen[last - back])
    middle = offsets[:-1] + (offsets[1:] - offsets[:-1]) // 2
    rng = np.random.default_rng(0)
    steps = np.append(np.linalg.norm(np.diff(seen, axis=0), axis=1), 0.0)
    steps[last] = 0.0
    lengths = np.add.reduceat(steps, offsets[:-1])
    candidates = np.flatnonzero(lengths >= args.min_length)
    probes = rng.choice(candidates, min(args.probes, len(candidates)), replace=False)
    tree = cKDTree(seen)
    is_continued = np.array([continued(seen, offsets, tree, owner, seen_tangents, k, tips[k],
                                       tip_directions[k], window, args.carry_on) for k in probes])
    if args.points and args.points_ahead > 0:
        run_on = PointsRunOn(args.points, args.points_ahead)
        is_continued |= np.array([run_on(tips[k], tip_directions[k]) for k in probes])
    left_tip = truth.left_at(tips[probes], tip_directions[probes])
    left_middle = truth.left_at(seen[middle[probes]], seen_tangents[middle[probes]])
    print(f"{len(last)} seen strands, {len(candidates)} at least {args.min_length:g} mm long, {len(probes)} looked at; window {args.window}, carry-on {args.carry_on:g} mm: "
          f"{np.mean(~is_continued):.3f} of the tips not continued")
    report("tips not continued", left_tip[~is_continued])
    report("tips continued", left_tip[is_continued])
    report("middles", left_middle)


if __name__ == "__main__":
    main()
