#!/usr/bin/python3
"""How far the segmentation's hair runs past the true hair's edge onto bare skin.

    /usr/bin/python3 bench/skin_edge_bleed.py CAPTURE [--every K]

CAPTURE is a simulated capture whose points stage has run (it holds ground_truth/views/ and
reconstruction/masks/). For every K-th view (default 3), the true bare skin (true label: head)
is split by its distance in pixels from the nearest true hair pixel (true label: hair), and for
each band the share that the segmentation (reconstruction/masks/NNN_*_label.png) labels hair is
printed. A segmentation whose hair reaches a few pixels past the hair's edge shows a high share
in the first bands only; skin taken for hair as a whole shows it in every band.

Needs Debian's python3-numpy and python3-opencv (hence /usr/bin/python3).
"""
import argparse
import glob
import os

import cv2
import numpy as np

BANDS_PX = [(0, 4), (4, 8), (8, 16), (16, 32), (32, None)]
HEAD, HAIR = 2, 3  # the labels' numbering (core/truth_maps.h)


def band_counts(true_label, label):
    """Per band: true skin pixels, and those the segmentation labels hair."""
    not_hair = (true_label != HAIR).astype(np.uint8)
    distance = cv2.distanceTransform(not_hair, cv2.DIST_L2, 5)
    skin = true_label == HEAD
    counts = []
    for low, high in BANDS_PX:
        band = skin & (distance >= low) & (distance < (high if high is not None else np.inf))
        counts.append((int(band.sum()), int((band & (label == HAIR)).sum())))
    return counts


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("capture")
    parser.add_argument("--every", type=int, default=3)
    args = parser.parse_args()
    masks = sorted(glob.glob(os.path.join(args.capture, "reconstruction", "masks", "*_label.png")))
    if not masks:
        raise SystemExit("skin_edge_bleed: no reconstruction/masks/*_label.png under %s "
                         "(run `hairrig reconstruct CAPTURE --stage points` first)" % args.capture)
    totals = [[0, 0] for _ in BANDS_PX]
    for path in masks[::args.every]:
        view = int(os.path.basename(path)[:3])
        truth_path = os.path.join(args.capture, "ground_truth", "views", "%03d_label.png" % view)
        true_label = cv2.imread(truth_path, cv2.IMREAD_UNCHANGED)
        label = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if true_label is None or label is None or true_label.shape != label.shape:
            raise SystemExit("skin_edge_bleed: cannot compare %s with %s" % (path, truth_path))
        for total, (skin, as_hair) in zip(totals, band_counts(true_label, label)):
            total[0] += skin
            total[1] += as_hair
    print("true bare skin by distance from the true hair: share labelled hair (pixels)")
    for (low, high), (skin, as_hair) in zip(BANDS_PX, totals):
        name = "%d-%d px" % (low, high) if high is not None else "%d px and more" % low
        print("  %-14s %.3f (%d)" % (name, as_hair / skin if skin else 0.0, skin))


if __name__ == "__main__":
    main()
