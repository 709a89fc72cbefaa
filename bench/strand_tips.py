#!/usr/bin/env python3
"""Where strands end: lengths, drops and tip heights of strand files side by side.

    python3 bench/strand_tips.py STRANDS.ply [MORE.ply ...]

For each file (hairrig's strand PLY, core/strand_io.h: vertices x y z in mm,
then one ushort segment count per strand), prints the median length along the
strand, the median drop (root height minus tip height, z up), the median
length over the root-to-tip chord (1 for a straight strand, about 2 for
curls), the 10th / 50th / 90th percentile of the tips' height, and the median
length of the strands rooted in the top, middle and bottom third of the
roots' height span. Give a reconstruction's strands.ply and the capture's
ground_truth/ground_truth_strands.ply to see whether strands end where the
true ones do.
"""
import array
import math
import statistics
import sys


def read_binary_ply(path, required, what):
    """The file's bytes, its header and where the payload starts; exits naming the file and what
    it should be unless the header is binary little-endian and holds every line of required."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii", "replace")
    if "binary_little_endian" not in header or any(line not in header for line in required):
        sys.exit("%s: not %s" % (path, what))
    return data, header, end


def read_strands(path):
    data, header, end = read_binary_ply(path, ["property ushort nsegs"],
                                        "a hairrig strand PLY (binary, per-strand ushort nsegs)")
    vertices = int(header.split("element vertex ")[1].split()[0])
    strands = int(header.split("element strand ")[1].split()[0])
    xyz = array.array("f")
    xyz.frombytes(data[end:end + 12 * vertices])
    segments = array.array("H")
    segments.frombytes(data[end + 12 * vertices:end + 12 * vertices + 2 * strands])
    if sys.byteorder != "little":
        xyz.byteswap()
        segments.byteswap()
    return xyz, segments


def percentile(sorted_values, q):
    return sorted_values[min(len(sorted_values) - 1, int(q * len(sorted_values)))]


def describe(path):
    xyz, segments = read_strands(path)
    lengths, drops, ratios, tips, roots = [], [], [], [], []
    first = 0
    for count in segments:
        last = first + count  # count segments: count + 1 vertices
        length = 0.0
        for k in range(first, last):
            a, b = 3 * k, 3 * k + 3
            length += math.dist(xyz[a:a + 3], xyz[b:b + 3])
        root, tip = xyz[3 * first:3 * first + 3], xyz[3 * last:3 * last + 3]
        lengths.append(length)
        drops.append(root[2] - tip[2])
        ratios.append(length / max(math.dist(root, tip), 1.0))
        tips.append(tip[2])
        roots.append(root[2])
        first = last + 1
    tips.sort()
    print("%s: %d strands; length median %.0f mm, drop median %.0f mm, length / chord median %.2f, "
          "tip height p10 / p50 / p90 %.0f / %.0f / %.0f mm"
          % (path, len(segments), statistics.median(lengths), statistics.median(drops),
             statistics.median(ratios), percentile(tips, 0.1), percentile(tips, 0.5),
             percentile(tips, 0.9)))
    print("  length median by root height (top / middle / bottom third of %.0f..%.0f mm): %s mm"
          % (min(roots), max(roots), " / ".join(
              "%.0f" % statistics.median(third) if third else "-"
              for third in by_root_height_third(roots, lengths))))


def by_root_height_third(roots, values):
    """values split by their strand's root height: top, middle, bottom third of the span."""
    low, high = min(roots), max(roots)
    span = max(high - low, 1e-9)
    thirds = [[], [], []]
    for root, value in zip(roots, values):
        thirds[min(2, int(3 * (high - root) / span))].append(value)
    return thirds


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for name in sys.argv[1:]:
        describe(name)
