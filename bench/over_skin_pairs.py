#!/usr/bin/python3
"""Where a reconstruction's strands lie in front of the true bare skin, and what the
segmentation called those pixels.

    /usr/bin/python3 bench/over_skin_pairs.py CAPTURE STRANDS.data [--step K]

CAPTURE is a simulated capture that has been reconstructed (it holds ground_truth/ and
reconstruction/masks/); STRANDS.data is a strand file in the USC-HairSalon format that hairrig
writes beside strands.ply, in the reconstruction's object frame (the turntable's, which the
calibration makes the true one to within a fraction of a millimetre). Every K-th strand sample
(default 4) is projected into every true camera; a (sample, view) pair counts when the sample is
in the image and not more than 3 mm behind the true depth there, and lies in front of the true
bare skin when the true label is the head with under 2 % hair coverage (as `hairrig eval
reconstruction`, without its hairline test). Prints the share of such pairs, what the
segmentation's own label says at them (skin, hair, backdrop), how far inside its hair they lie,
how far they lie from their strand's tip, and the share per view.

Needs Debian's python3-numpy and python3-opencv (hence /usr/bin/python3).
"""
import json
import os
import sys

import cv2
import numpy as np

BARE_ALPHA = 0.02
DEPTH_TOLERANCE_MM = 3.0
LABELS = {0: "backdrop", 1: "box", 2: "skin", 3: "hair"}


def read_strands_data(path):
    """Vertices (N x 3), each vertex's index along its strand and the strand's vertex count."""
    raw = open(path, "rb").read()
    count = int(np.frombuffer(raw, np.int32, 1, 0)[0])
    offset, points, index, length = 4, [], [], []
    for _ in range(count):
        n = int(np.frombuffer(raw, np.int32, 1, offset)[0])
        offset += 4
        points.append(np.frombuffer(raw, np.float32, 3 * n, offset).reshape(n, 3))
        offset += 12 * n
        index.append(np.arange(n))
        length.append(np.full(n, n))
    return np.concatenate(points).astype(np.float64), np.concatenate(index), np.concatenate(length)


def matrix(transform):
    return np.array(transform["matrix_3x4"])


def project(view, points):
    """Pixel (rounded) and depth of `points` (turntable frame, mm) in a true view."""
    k = view["intrinsics"]
    cam_from_world, world_from_turntable = matrix(view["cam_from_world"]), matrix(
        view["world_from_turntable"])
    rotation = cam_from_world[:, :3] @ world_from_turntable[:, :3]
    translation = cam_from_world[:, :3] @ world_from_turntable[:, 3] + cam_from_world[:, 3]
    in_camera = points @ rotation.T + translation
    camera = np.array([[k["fx_px"], 0, k["cx_px"]], [0, k["fy_px"], k["cy_px"]], [0, 0, 1]])
    distortion = np.array([k["k1"], k["k2"], k["p1"], k["p2"], k["k3"]])
    pixels, _ = cv2.projectPoints(in_camera.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), camera,
                                  distortion)
    pixels = np.round(pixels.reshape(-1, 2)).astype(int)
    inside = ((in_camera[:, 2] > 0) & (pixels[:, 0] >= 0) & (pixels[:, 1] >= 0) &
              (pixels[:, 0] < k["width_px"]) & (pixels[:, 1] < k["height_px"]))
    return pixels[:, 0], pixels[:, 1], in_camera[:, 2], inside


def read_png(path):
    image = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if image is None:
        sys.exit(f"{path}: cannot be read")
    return image


def own_label(masks_dir, view):
    names = [f for f in os.listdir(masks_dir) if f.startswith(f"{view:03d}_") and
             f.endswith("_label.png")]
    return read_png(os.path.join(masks_dir, names[0])) if names else None


def histogram_line(values, edges):
    counts, _ = np.histogram(values, bins=edges)
    total = max(1, len(values))
    return "  ".join(f"{int(a)}-{int(b) if b < 1e8 else 'inf'}: {100 * c / total:.1f} %"
                     for a, b, c in zip(edges[:-1], edges[1:], counts))


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    capture, strands_file = sys.argv[1], sys.argv[2]
    step = int(sys.argv[4]) if len(sys.argv) > 4 and sys.argv[3] == "--step" else 4
    truth = json.load(open(os.path.join(capture, "ground_truth", "ground_truth.json")))
    views_dir = os.path.join(capture, "ground_truth", "views")
    masks_dir = os.path.join(capture, "reconstruction", "masks")
    points, index, length = read_strands_data(strands_file)
    points, from_tip = points[::step], (length - 1 - index)[::step]
    pairs = over_skin = 0
    labels_at, inside_hair_px, tip_mm, per_view = [], [], [], []
    for view in truth["views"]:
        v = view["view"]
        x, y, depth, inside = project(view, points)
        true_depth = read_png(os.path.join(views_dir, f"{v:03d}_depth.png")) / 20.0
        true_label = read_png(os.path.join(views_dir, f"{v:03d}_label.png"))
        alpha = read_png(os.path.join(views_dir, f"{v:03d}_alpha.png")) / 65535.0
        ids = np.nonzero(inside)[0]
        d = true_depth[y[ids], x[ids]]
        ids = ids[(d == 0) | (depth[ids] <= d + DEPTH_TOLERANCE_MM)]
        xs, ys = x[ids], y[ids]
        bare = (true_label[ys, xs] == 2) & (alpha[ys, xs] < BARE_ALPHA)
        pairs += len(ids)
        over_skin += int(bare.sum())
        per_view.append((v, 100 * bare.sum() / max(1, len(ids))))
        tip_mm.append(from_tip[ids[bare]])
        label = own_label(masks_dir, v)
        if label is None:
            continue
        labels_at.append(label[ys[bare], xs[bare]])
        inside_hair = cv2.distanceTransform((label == 3).astype(np.uint8), cv2.DIST_L2, 3)
        on_hair = label[ys[bare], xs[bare]] == 3
        inside_hair_px.append(inside_hair[ys[bare], xs[bare]][on_hair])
    print(f"{len(points)} samples (every {step}th), {pairs} (sample, view) pairs seen: "
          f"{100 * over_skin / max(1, pairs):.2f} % in front of the true bare skin")
    if labels_at:
        labels_at = np.concatenate(labels_at)
        print("  the segmentation's label there: " + "  ".join(
            f"{name} {100 * np.mean(labels_at == code):.1f} %" for code, name in LABELS.items()))
        print("  of those it calls hair, px inside its hair's edge: " +
              histogram_line(np.concatenate(inside_hair_px), [0, 2, 4, 8, 16, 32, 1e9]))
    print("  vertices from the strand's tip: " +
          histogram_line(np.concatenate(tip_mm), [0, 10, 20, 40, 80, 160, 1e9]))
    print("  per view: " + " ".join(f"{v}:{share:.1f}" for v, share in per_view))


if __name__ == "__main__":
    main()
