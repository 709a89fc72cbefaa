#!/usr/bin/env python3
"""Where the strands of a curly capture lose against the truth: the strand stage run on its
inputs one at a time replaced by the truth, each stage's ceiling in one run.

    python3 bench/strand_ceilings.py CAPTURE --curl RADIUS_MM,PITCH_MM,HANDEDNESS
        [--strand-bench build/bench/hairrig_strand_bench] [--json OUT]

CAPTURE is a simulated capture whose points exist (`hairrig reconstruct CAPTURE --stage points`);
--curl is the simulated wig's curl (the scene's curl_radius_mm and curl_pitch_mm; +1 for
right-handed, as the simulated rig winds its curls). The strand bench runs the Bao & Qi method
six times, each into CAPTURE/bench-strands-bao-qi-ceiling-NAME/ (a run whose output is there,
made by the same strand bench with the same flags, is read again, not repeated):

  capture           the capture's points, the curl estimated from them (what `reconstruct` does)
  estimate everywhere  the capture's points, the estimate's curl given everywhere: every strand
                    winds wherever it leaves the seen strands, one way round (the estimate's
                    region and the arcs' local handedness left out)
  true curl         the capture's points, the true curl in place of the estimate
  true directions   the capture's points with the true strands' directions, the curl estimated
  true points       points from the true visible surface (as many), the curl estimated
  true points+curl  both: the strand stage's own ceiling

and prints each one's all-strands precision, recall and F1 at (3 mm, 30 deg), directed, the curl
it grew on, the median length and the share of samples over the true bare skin. A row's gain over
the first is what that input costs the strands. --json writes the rows for bench/docs_figures.py.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CASES = [
    ("capture", []),
    ("estimate everywhere", ["--curl-oracle", "ESTIMATE"]),
    ("true curl", ["--curl-oracle", "TRUTH"]),
    ("true directions", ["--points", "true-directions"]),
    ("true points", ["--points", "truth"]),
    ("true points+curl", ["--points", "truth", "--curl-oracle", "TRUTH"]),
]

SCORE = re.compile(r"^\s+\(3 mm, 30 deg\): precision [\d.]+ \(([\d.]+)\), visible-surface recall "
                   r"[\d.]+ \([\d.]+\), all-strands recall [\d.]+ \(([\d.]+)\)", re.M)
CURL = re.compile(r"^\s+curls: (.*)$", re.M)
LENGTH = re.compile(r"reconstructed lengths: mean [\d.]+ mm, p10 [\d.]+, median ([\d.]+)")
SKIN = re.compile(r"in front of the true bare skin: ([\d.]+) %")


def parse(output):
    """The figures of one strand-bench run's output; SystemExit when a line is missing."""
    found = {name: pattern.search(output) for name, pattern in
             (("score", SCORE), ("curl", CURL), ("length", LENGTH), ("skin", SKIN))}
    missing = [name for name, match in found.items() if match is None and name != "curl"]
    if missing:
        raise SystemExit("strand_ceilings: the strand bench printed no %s line"
                         % ", ".join(missing))
    precision, recall = float(found["score"].group(1)), float(found["score"].group(2))
    curl = found["curl"].group(1) if found["curl"] else None
    return {
        "precision": precision,
        "recall": recall,
        "f1": 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0,
        "curl": re.split(r", (?:from|given)", curl)[0] if curl else "none",
        "curl_flag": curl_flag(curl) if curl else None,
        "median_length_mm": float(found["length"].group(1)),
        "over_skin_percent": float(found["skin"].group(1)),
    }


def curl_flag(curl_line):
    """--curl-oracle's value for a curl as the strand bench prints it, or None for no curl."""
    shape = re.match(r"radius ([\d.]+) mm, pitch ([\d.]+) mm, (right|left)-handed", curl_line)
    if shape is None:
        return None
    return "%s,%s,%s" % (shape.group(1), shape.group(2), "1" if shape.group(3) == "right" else "-1")


def run_case(strand_bench, capture, suffix, flags):
    """The strand bench's output for these flags: read from the case's folder where the same
    strand bench (path and modification time) finished a run with the same flags, else run."""
    saved = os.path.join(capture, "bench-strands-bao-qi" + suffix, "bench_output.json")
    made_by = "%s %d" % (os.path.abspath(strand_bench), os.stat(strand_bench).st_mtime_ns)
    if os.path.exists(saved):
        with open(saved) as f:
            done = json.load(f)
        if done["flags"] == flags and done.get("made_by") == made_by:
            return done["output"], done["seconds"]
    cmd = [strand_bench, capture, "--methods", "bao-qi", "--out-suffix", suffix] + flags
    start = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.stderr.write(done.stdout + done.stderr)
        raise SystemExit("strand_ceilings: %s exited %d" % (" ".join(cmd), done.returncode))
    seconds = time.monotonic() - start
    with open(saved, "w") as f:
        json.dump({"flags": flags, "made_by": made_by, "output": done.stdout, "seconds": seconds},
                  f)
    return done.stdout, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("capture")
    parser.add_argument("--curl", required=True, help="RADIUS_MM,PITCH_MM,HANDEDNESS")
    parser.add_argument("--strand-bench", default=os.path.join(ROOT, "build", "bench",
                                                               "hairrig_strand_bench"))
    parser.add_argument("--json")
    args = parser.parse_args()
    if not re.fullmatch(r"[\d.]+,[\d.]+,[+-]?1", args.curl):
        raise SystemExit("strand_ceilings: --curl wants RADIUS_MM,PITCH_MM,HANDEDNESS "
                         "(e.g. 6,20,1)")
    if not os.path.isfile(os.path.join(args.capture, "reconstruction", "points.ply")):
        raise SystemExit("strand_ceilings: %s has no reconstruction/points.ply (run `hairrig "
                         "reconstruct %s --stage points` first)" % (args.capture, args.capture))
    rows = []
    for name, extra in CASES:
        curls = {"TRUTH": args.curl, "ESTIMATE": rows[0]["curl_flag"] if rows else None}
        if "ESTIMATE" in extra and curls["ESTIMATE"] is None:
            print("%-17s skipped: the capture's points show no curl" % name, flush=True)
            continue
        flags = [curls.get(flag, flag) for flag in extra]
        suffix = "-ceiling-" + name.replace(" ", "-").replace("+", "-and-")
        output, seconds = run_case(args.strand_bench, args.capture, suffix, flags)
        row = {"case": name, "flags": " ".join(flags), "seconds": seconds}
        row.update(parse(output))
        rows.append(row)
        print("%-17s P %.3f  R %.3f  F1 %.3f (%+.3f)  median %5.1f mm  over skin %.2f %%  curl: %s"
              % (name, row["precision"], row["recall"], row["f1"], row["f1"] - rows[0]["f1"],
                 row["median_length_mm"], row["over_skin_percent"], row["curl"]), flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"capture": os.path.basename(os.path.normpath(args.capture)),
                       "true_curl": args.curl, "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
