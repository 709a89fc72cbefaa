#!/usr/bin/env python3
"""How well the oriented points' directions follow the true strands, and how far off the hair's
local axis both lie.

    python3 bench/point_directions.py POINTS.ply TRUE_STRANDS.ply [--sample N] [--axis-radius MM]

POINTS.ply is a reconstruction's points.ply (hairrig's oriented points: x y z, unit direction as
nx ny nz, confidence, views); TRUE_STRANDS.ply the capture's ground_truth/ground_truth_strands.ply.
For N points drawn at random (seeded) within 2 mm of a true strand sample, prints the median angle
between the point's direction and the nearest true sample's tangent, and the median angle off the
local axis (the mean root-to-tip tangent of the true samples within the axis radius) of the points'
directions and of the nearest true tangents. On curls the two off-axis figures tell whether the
points see the helix's slant or only the ringlet's run. Needs numpy and scipy.
"""
import argparse
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from strand_tips import read_binary_ply, read_strands  # noqa: E402


def read_points(path):
    """(n, 6) float32: position (mm) and unit direction of every point."""
    data, header, end = read_binary_ply(
        path, ["property float confidence", "property list uchar ushort views"],
        "a hairrig points PLY (x y z nx ny nz confidence, a views list)")
    count = int(header.split("element vertex ")[1].split()[0])
    out = np.empty((count, 6), np.float32)
    offset = end
    for i in range(count):  # each vertex: 7 floats, then a uchar count of ushort views
        out[i] = np.frombuffer(data, np.float32, 6, offset)
        offset += 28
        offset += 1 + 2 * data[offset]
    return out


def true_tangents(path):
    """Midpoints and unit root-to-tip tangents of every true strand's edges."""
    xyz, segments = read_strands(path)
    vertices = np.frombuffer(xyz, np.float32).reshape(-1, 3)
    mids, tangents, first = [], [], 0
    for count in segments:
        strand = vertices[first:first + count + 1]
        first += count + 1
        edges = np.diff(strand, axis=0)
        edges /= np.maximum(np.linalg.norm(edges, axis=1, keepdims=True), 1e-9)
        mids.append((strand[1:] + strand[:-1]) / 2)
        tangents.append(edges)
    return np.concatenate(mids), np.concatenate(tangents)


def angle_deg(a, b):
    """Unsigned angle between rows of unit vectors a and b."""
    return np.degrees(np.arccos(np.clip(np.abs(np.sum(a * b, axis=1)), 0, 1)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("points")
    parser.add_argument("truth")
    parser.add_argument("--sample", type=int, default=20000)
    parser.add_argument("--axis-radius", type=float, default=15.0)
    args = parser.parse_args()
    points = read_points(args.points)
    mids, tangents = true_tangents(args.truth)
    tree = cKDTree(mids)
    distance, nearest = tree.query(points[:, :3])
    near = np.nonzero(distance < 2.0)[0]
    pick = np.random.default_rng(1).choice(near, min(args.sample, len(near)), replace=False)
    directions, truth = points[pick, 3:6], tangents[nearest[pick]]
    # The axis from every 8th true sample: the mean tangent needs no more.
    coarse = cKDTree(mids[::8])
    axes = np.zeros_like(directions)
    for k, neighbours in enumerate(coarse.query_ball_point(points[pick, :3], args.axis_radius)):
        mean = tangents[::8][neighbours].sum(axis=0)
        axes[k] = mean / max(np.linalg.norm(mean), 1e-9)
    has_axis = np.linalg.norm(axes, axis=1) > 0.5  # a point with no true sample near has none
    print("%s: %d points, %.1f %% within 2 mm of a true strand; %d of those drawn"
          % (args.points, len(points), 100.0 * len(near) / len(points), len(pick)))
    print("  direction against the nearest true tangent: median %.1f deg, 75th percentile %.1f deg"
          % (np.median(angle_deg(directions, truth)),
             np.percentile(angle_deg(directions, truth), 75)))
    print("  off the local axis (true tangents within %.0f mm): points median %.1f deg, "
          "nearest true tangents %.1f deg" % (args.axis_radius,
                                             np.median(angle_deg(directions[has_axis],
                                                                 axes[has_axis])),
                                             np.median(angle_deg(truth[has_axis],
                                                                 axes[has_axis]))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
