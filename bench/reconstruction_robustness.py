#!/usr/bin/env python3
"""The whole pipeline under the simulated rig's scene variations.

For every scene and variation (one at a time, or several joined by '+'): a
38-view capture of the simulated rig with the scene's `variations:` set,
calibrated as the rig does it (`hairrig capture --calibrate`), reconstructed
(`hairrig reconstruct`, with the options given after `--`) and scored against
the ground truth (`hairrig eval reconstruction --json`). One row per case:
hair mask IoU, orientation error, points P / visible R, strands P / visible R
/ all-strands R, F1 at (3 mm, 30 deg), consistency, median length, the
verdict, and the F1's loss against the scene's baseline (no variation).

    python3 bench/reconstruction_robustness.py --work DIR [--scenes default,curly_blond]
        [--variations none,photograph,defocus+iso1600] [--tag NAME] [--json OUT]
        [--hairrig build/cli/hairrig] [-- RECONSTRUCT OPTIONS...]

Captures are kept in DIR/<scene>/<variation>/capture and reused by later runs
(delete them to re-capture); each set of reconstruct options writes its own
copy of the capture's reconstruction, DIR/<scene>/<variation>/<tag>/, so two
option sets compare on the same images, and a tag's finished run with the
same options is reused. A case that fails is reported with
its error and the run goes on.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_VARIATIONS = ("none,iso1600,jpeg70,bayer,defocus,soft_lens,wb_warm,under_exposed,"
                      "over_exposed,second_panel_off,hard_light,soft_light,white_mannequin,"
                      "dark_skin,white_backdrop,blue_backdrop,fibre_sparkle,photograph,"
                      "defocus+iso1600+jpeg70")
PATH_KEYS = re.compile(r"^(\s*(?:mesh|file|box|head|scene):\s*)([^\s#][^\s#]*)(.*)$")


def absolutise_paths(text, base_dir):
    """Rewrites relative file values (mesh:, file:, box:, head:, scene:) as absolute."""
    lines = []
    for line in text.splitlines():
        m = PATH_KEYS.match(line)
        if m and not os.path.isabs(m.group(2)) and ("/" in m.group(2) or "." in m.group(2)):
            line = m.group(1) + os.path.normpath(os.path.join(base_dir, m.group(2))) + m.group(3)
        lines.append(line)
    return "\n".join(lines) + "\n"


def write_rig(case_dir, scene, variations):
    """A copy of etc/sim-rig.yaml whose scene is a copy of etc/scenes/SCENE.yaml with the variations."""
    scene_file = os.path.join(ROOT, "etc", "scenes", scene + ".yaml")
    with open(scene_file) as f:
        text = absolutise_paths(f.read(), os.path.dirname(scene_file))
    if re.search(r"^variations:", text, re.M):
        sys.exit(f"{scene_file} already has variations:; give a scene without them")
    if variations:
        text += "variations: [" + ", ".join(variations) + "]\n"
    os.makedirs(case_dir, exist_ok=True)
    case_scene = os.path.join(case_dir, "scene.yaml")
    with open(case_scene, "w") as f:
        f.write(text)
    rig_file = os.path.join(ROOT, "etc", "sim-rig.yaml")
    with open(rig_file) as f:
        rig = absolutise_paths(f.read(), os.path.dirname(rig_file))
    rig = re.sub(r"^(\s*scene:\s*)\S+", lambda m: m.group(1) + case_scene, rig, count=1, flags=re.M)
    # The bench measures the images, not the rig's timing: on a shared machine a path-traced
    # frame can take longer than the rig's own limit, so its copy waits up to 5 minutes.
    rig = re.sub(r"^(\s*frame_timeout_s:\s*)[0-9.]+", lambda m: m.group(1) + "300", rig,
                 count=1, flags=re.M)
    case_rig = os.path.join(case_dir, "rig.yaml")
    with open(case_rig, "w") as f:
        f.write(rig)
    return case_rig


def run(cmd, log):
    """Runs cmd with its output to log; returns (exit code, seconds)."""
    start = time.monotonic()
    with open(log, "a") as out:
        out.write("$ " + " ".join(cmd) + "\n")
        out.flush()
        code = subprocess.call(cmd, stdout=out, stderr=subprocess.STDOUT)
    return code, time.monotonic() - start


def at(table, distance_mm):
    """The row of an eval's P/R table at a distance."""
    for row in table:
        if abs(row["distance_mm"] - distance_mm) < 1e-6 and row["angle_deg"] < 89:
            return row
    raise KeyError(distance_mm)


def f1(p, r):
    return 2 * p * r / (p + r) if p + r > 0 else 0.0


def summarise(evaluation, verdict):
    points, strands = evaluation["points"], evaluation["strands"]
    p2 = at(points["visible_surface"], 2.0)
    s2 = at(strands["visible_surface"]["directed"], 2.0)
    s3 = at(strands["all_strands"]["directed"], 3.0)
    return {
        "mask_iou": evaluation["masks"]["iou_median"],
        "orientation_median_deg": evaluation["orientation"]["median_deg"],
        "points": points["count"],
        "points_precision_2mm": p2["precision"],
        "points_visible_recall_2mm": p2["recall"],
        "strands_precision_2mm": s2["precision"],
        "strands_visible_recall_2mm": s2["recall"],
        "strands_all_recall_3mm": s3["recall"],
        "strands_f1_3mm": f1(s3["precision"], s3["recall"]),
        "consistency": strands["consistency"]["mean"],
        "median_length_mm": strands["lengths_mm"]["reconstructed"]["median"],
        "truth_median_length_mm": strands["lengths_mm"]["truth"]["median"],
        # Absent in evaluations made before `eval reconstruction` measured it.
        "over_true_skin_share": strands.get("over_true_skin_share"),
        "verdict": verdict.get("verdict", "?"),
        "reasons": verdict.get("reasons", []),
    }


def capture(hairrig, case_dir, scene, variations, log):
    """The case's calibrated capture, made once."""
    cap = os.path.join(case_dir, "capture")
    if os.path.exists(os.path.join(cap, "calibration", "calibration.json")):
        return cap, 0.0
    if os.path.exists(cap):
        shutil.rmtree(cap)
    rig = write_rig(case_dir, scene, variations)
    code, seconds = run([hairrig, "capture", "--config", rig, "--out", cap, "--calibrate"], log)
    if code not in (0, 3) or not os.path.exists(os.path.join(cap, "calibration", "calibration.json")):
        raise RuntimeError(f"capture/calibrate exited {code} (see {log})")
    return cap, seconds


def reconstruct(hairrig, cap, out, options, log):
    """Reconstructs a copy of the capture (its files hard-linked: the stages refuse symbolic
    links out of a capture folder) into out; a finished run with the same options is reused."""
    done_file = os.path.join(out, "bench_run.json")
    if os.path.exists(done_file):
        with open(done_file) as f:
            done = json.load(f)
        if done["options"] == options:
            return done["evaluation"], done["verdict"], done["seconds"]
    if os.path.exists(out):
        shutil.rmtree(out)
    shutil.copytree(cap, out, copy_function=os.link,
                    ignore=lambda d, names: ["reconstruction"] if d == cap else [])
    code, seconds = run([hairrig, "reconstruct", out] + options, log)
    if code not in (0, 3):
        raise RuntimeError(f"reconstruct exited {code} (see {log})")
    with open(os.path.join(out, "reconstruction", "verdict.json")) as f:
        verdict = json.load(f)
    evaluation_file = os.path.join(out, "evaluation.json")
    with open(evaluation_file, "w") as f:
        code = subprocess.call([hairrig, "eval", "reconstruction", out, "--json"], stdout=f,
                               stderr=open(log, "a"))
    if code != 0:
        raise RuntimeError(f"eval reconstruction exited {code} (see {log})")
    with open(evaluation_file) as f:
        evaluation = json.load(f)
    with open(done_file, "w") as f:
        json.dump({"options": options, "evaluation": evaluation, "verdict": verdict,
                   "seconds": seconds}, f)
    return evaluation, verdict, seconds


def main():
    argv = sys.argv[1:]
    options = []
    if "--" in argv:
        options = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--work", required=True)
    parser.add_argument("--scenes", default="default,curly_blond")
    parser.add_argument("--variations", default=DEFAULT_VARIATIONS)
    parser.add_argument("--tag", default="default-options")
    parser.add_argument("--hairrig", default=os.path.join(ROOT, "build", "cli", "hairrig"))
    parser.add_argument("--json", help="write the rows here")
    args = parser.parse_args(argv)
    if not os.access(args.hairrig, os.X_OK):
        sys.exit(f"{args.hairrig} is not an executable: build it first (scripts/build)")
    rows = []
    for scene in args.scenes.split(","):
        baseline_f1 = None
        for variation in args.variations.split(","):
            names = [] if variation == "none" else variation.split("+")
            case_dir = os.path.join(os.path.abspath(args.work), scene, variation)
            os.makedirs(case_dir, exist_ok=True)
            log = os.path.join(case_dir, "log.txt")
            row = {"scene": scene, "variation": variation, "tag": args.tag, "options": options}
            try:
                cap, capture_s = capture(args.hairrig, case_dir, scene, names, log)
                out = os.path.join(case_dir, args.tag)
                evaluation, verdict, reconstruct_s = reconstruct(args.hairrig, cap, out, options, log)
                row.update(summarise(evaluation, verdict))
                row.update({"capture_s": capture_s, "reconstruct_s": reconstruct_s})
                if variation == "none":
                    baseline_f1 = row["strands_f1_3mm"]
                if baseline_f1:
                    row["f1_loss"] = 1 - row["strands_f1_3mm"] / baseline_f1
            except (RuntimeError, OSError, KeyError, ValueError) as e:
                row["error"] = str(e)
            rows.append(row)
            print(json.dumps(row), flush=True)
            if args.json:
                with open(args.json, "w") as f:
                    json.dump({"rows": rows, "options": options, "tag": args.tag}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
