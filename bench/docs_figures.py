#!/usr/bin/env python3
"""The tables of docs/ that come from a bench's JSON output, generated from it.

A bench run is recorded once, with the commit, date and command that made it:

  python3 bench/console_load_bench.py --json /tmp/load.json
  python3 bench/docs_figures.py record console_load /tmp/load.json \\
      "python3 bench/console_load_bench.py --json OUT"

which writes docs/figures/console_load.json. A table in docs/*.md that shows it
sits between two markers,

  <!-- figures: console_load -->
  ...
  <!-- end figures -->

and `python3 bench/docs_figures.py` rewrites every such table from its record,
so a figure in docs/ cannot drift from the bench output it quotes.
`--check` rewrites nothing and exits 1 naming each table that differs from its
record (tests/docs_figures runs it).
"""

import argparse
import datetime
import json
import os
import re
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIGURES = os.path.join(ROOT, "docs", "figures")
BLOCK = re.compile(r"(<!-- figures: (\w+) -->\n)(.*?)(<!-- end figures -->)", re.S)


def provenance(record):
    return "`%s` %s" % (record["commit"], record["date"])


def console_load_table(record):
    r = record["result"]
    estop = sorted(r["estop_ms"])
    state = sorted(r["state_ms"])
    cap = r["capture"]
    rows = [
        ("connections held: idle / slow-header", "%d / %d" % (r["idle"], r["slow"])),
        ("e-stops acted on", "%d of %d" % (r["estop_answered"], r["tries"])),
        ("e-stop latency, median / max",
         "%.1f ms / %.1f ms" % (statistics.median(estop), estop[-1])),
        ("state read, median / max", "%.1f ms / %.1f ms" % (statistics.median(state), state[-1])),
        ("console CPU with its live view at %g frame/s, load held / no load" % r.get("live_fps", 1),
         "%.1f %% / %.1f %% of a core" % (100 * r["cpu_under_load"], 100 * r["cpu_no_load"])),
    ]
    if cap.get("started"):
        rows.append(("a capture started under the load",
                     "%d of %d frames verified" % (cap["frames_verified"], cap["frames"])))
    lines = ["| what | figure | commit, date |", "| --- | --- | --- |"]
    lines += ["| %s | %s | %s |" % (what, figure, provenance(record)) for what, figure in rows]
    return lines


def hostile_campaign_table(record):
    r = record["result"]
    names = {"crash": "crashes", "hang": "hangs", "clean": "clean errors"}
    columns = [names.get(c, c) for c in r["columns"]]
    lines = ["| " + " | ".join(columns) + " |", "| " + " | ".join("---" for _ in columns) + " |"]
    for row in r["table"]:
        lines.append("| " + " | ".join(str(x) for x in row) + " |")
    lines.append("")
    lines.append("Mode `%s`, seed %s, %.0f s; %s." % (r["mode"], r["seed"], r["runtime_s"],
                                                        provenance(record)))
    return lines


def console_viewer_table(record):
    r = record["result"]
    full, display = r["export_full"], r["export_display"]
    export_s, first, fps = sorted(r["export_s"]), sorted(r["first_frame_ms"]), sorted(r["orbit_fps"])
    rows = [
        ("`hairrig export` of %s strands with %d simulated frames, median (runs)"
         % ("{:,}".format(r["strands"]), display["frames"]),
         "%.2f s (%s)" % (statistics.median(export_s), ", ".join("%.2f" % s for s in export_s))),
        ("files written: every strand / display copy",
         "%.1f MB / %.1f MB (%s vertices)" % (full["bytes"] / 1e6, display["bytes"] / 1e6,
                                              "{:,}".format(display["vertices"]))),
        ("3D view, Open to the model's first frame, median (runs)",
         "%.0f ms (%s)" % (statistics.median(first), ", ".join("%.0f" % x for x in first))),
        ("3D view while orbiting as a drag draws it (1,000 strands through every 2nd point), median (runs)",
         "%.1f frames/s (%s)" % (statistics.median(fps), ", ".join("%.1f" % x for x in fps))),
        ("3D view while orbiting with every display strand drawn, median of runs",
         "%.1f frames/s" % statistics.median(r["orbit_fps_full_detail"])),
        ("95th-percentile frame interval while orbiting, median of runs",
         "%.0f ms" % statistics.median(r["orbit_interval_ms_p95"])),
    ]
    if r.get("play_fps"):
        play = sorted(r["play_fps"])
        rows.append(("3D view playing the simulation, median (runs)",
                     "%.1f frames/s (%s)" % (statistics.median(play),
                                             ", ".join("%.1f" % x for x in play))))
    lines = ["| what | figure | commit, date |", "| --- | --- | --- |"]
    lines += ["| %s | %s | %s |" % (what, figure, provenance(record)) for what, figure in rows]
    return lines


def gltf_animation_table(record):
    r = record["result"]
    lines = ["| encoding | the animation adds | export | Blender: import, objects, actions, "
             "shape keys | Blender: evaluation a frame, largest move | commit, date |",
             "| --- | --- | --- | --- | --- | --- |"]
    for encoding, e in r["encodings"].items():
        b = e["blender"]
        made = ("%.2f s, %d, %d, %d" % (b["import_s"], b["objects"], b["actions"], b["shape_keys"])
                if b else "not run (no Blender)")
        played = "%.2f ms, %.0f mm" % (1e3 * b["frame_s"], 1e3 * b["largest_move_m"]) if b else ""
        lines.append("| %s | %.2f MB | %.2f s | %s | %s | %s |"
                     % (encoding, e["animation_bytes"] / 1e6, e["export_s"], made, played,
                        provenance(record)))
    first = next(iter(r["encodings"].values()))
    lines += ["", "%d frames of %s strands and %d guides." % (
        first["frames"], "{:,}".format(r["animation_strands"]), first["guides"])]
    return lines


def reconstruction_robustness_table(record):
    r = record["result"]
    lines = ["| scene | variation | hair IoU | orientation median | points P / visible R (2 mm) "
             "| strands P / visible R (2 mm) | strands all R (3 mm) | strands F1 (3 mm, 30 deg), "
             "loss | consistency | median length (truth) | over bare skin | verdict |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for row in r["rows"]:
        if "error" in row:
            lines.append("| %s | %s | failed: %s |  |  |  |  |  |  |  |  |  |"
                         % (row["scene"], row["variation"], row["error"]))
            continue
        loss = row.get("f1_loss")
        skin = row.get("over_true_skin_share")
        lines.append(
            "| %s | %s | %.2f | %.1f deg | %.2f / %.2f | %.2f / %.2f | %.2f | %.3f, %s | %.2f "
            "| %.0f (%.0f) mm | %s | %s |"
            % (row["scene"], row["variation"].replace("+", " + "), row["mask_iou"],
               row["orientation_median_deg"], row["points_precision_2mm"],
               row["points_visible_recall_2mm"], row["strands_precision_2mm"],
               row["strands_visible_recall_2mm"], row["strands_all_recall_3mm"],
               row["strands_f1_3mm"],
               "baseline" if row["variation"] == "none" else
               "-" if loss is None else "%+.0f %%" % (-100 * loss),
               row["consistency"], row["median_length_mm"], row["truth_median_length_mm"],
               "-" if skin is None else "%.1f %%" % (100 * skin), row["verdict"]))
    options = " ".join(r.get("options", [])) or "none (the defaults)"
    lines += ["", "Reconstruction options: %s. Measured at %s." % (options, provenance(record))]
    return lines


def google_benchmark_times(record):
    """{benchmark name: [real time of each repetition]} from Google Benchmark's JSON output."""
    times = {}
    for b in record["result"]["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        name = b.get("run_name", b["name"]).replace("/real_time", "")
        times.setdefault(name, []).append(b["real_time"] / {"ms": 1e3, "us": 1e6, "ns": 1e9,
                                                            "s": 1.0}[b["time_unit"]])
    return times


RENDER_SUBJECTS = [
    ("BM_RenderView/0/2", "default scene: 40,000-strand wig"),
    ("BM_RenderView/0/1", "the same on one thread"),
    ("BM_RenderView/3/2", "the same style with 50,000 strands"),
    ("BM_RenderView/1/2", "curly_blond: 50,000 strands, 78 points per strand, the densest"),
    ("BM_RenderView/2/2", "the former subject: an ellipsoid under 10,000 unshadowed strands"),
    ("BM_RenderNoHair/0/2", "the default view without its hair"),
]


MODBUS_EXCHANGES = [
    ("BM_ModbusStatusRead/0", "round trip of one status read (17 registers), TCP loopback"),
    ("BM_ModbusStatusRead/1",
     "the same over a pseudo-terminal, which does not pace bytes at the baud rate"),
    ("BM_ModbusWriteMoveParameters/0", "writing a move's parameters (6 registers), TCP loopback"),
    ("BM_ModbusWriteMoveParameters/1", "the same over a pseudo-terminal"),
]


def google_benchmark_table(record, rows, what, unit):
    """One row per (benchmark, label) present: the median and each repetition, in `unit`."""
    times = google_benchmark_times(record)
    scale = {"s": 1.0, "ms": 1e3, "us": 1e6}[unit]
    lines = ["| %s (benchmark) | median (repetitions) | commit, date |" % what, "| --- | --- | --- |"]
    for name, label in rows:
        if name not in times:
            raise SystemExit("docs_figures: the record has no benchmark %s (run every one the "
                             "table lists)" % name)
        t = sorted(x * scale for x in times[name])
        digits = 2 if unit == "s" else 0
        lines.append("| %s (`%s`) | %.*f %s (%s) | %s |"
                     % (label, name, digits, statistics.median(t), unit,
                        ", ".join("%.*f" % (digits, x) for x in t), provenance(record)))
    return lines, times


def render_view_table(record):
    lines, times = google_benchmark_table(record, RENDER_SUBJECTS, "subject, time per view", "s")
    wig, old = times.get("BM_RenderView/0/2"), times.get("BM_RenderView/2/2")
    if wig and old:
        lines += ["", "In the same run, the default wig costs %.1f times the former subject."
                  % (statistics.median(wig) / statistics.median(old))]
    return lines


def modbus_table(record):
    return google_benchmark_table(record, MODBUS_EXCHANGES, "exchange", "us")[0]


def strand_ceilings_table(record):
    r = record["result"]
    lines = ["| %s: the strand stage's input | P / all-strands R at (3 mm, 30 deg), directed | F1 "
             "(gain) | curl grown on | median length | over bare skin |" % r["capture"],
             "| --- | --- | --- | --- | --- | --- |"]
    base = r["rows"][0]["f1"]
    for row in r["rows"]:
        lines.append("| %s | %.3f / %.3f | %.3f (%+.3f) | %s | %.0f mm | %.2f %% |" % (
            row["case"], row["precision"], row["recall"], row["f1"], row["f1"] - base, row["curl"],
            row["median_length_mm"], row["over_skin_percent"]))
    lines += ["", "The true curl: %s (radius mm, pitch mm, handedness). %s." % (
        r["true_curl"], provenance(record))]
    return lines


RENDERERS = {"console_load": console_load_table, "hostile_campaign": hostile_campaign_table,
             "console_viewer": console_viewer_table, "gltf_animation": gltf_animation_table,
             "reconstruction_robustness": reconstruction_robustness_table,
             "reconstruction_robustness_now": reconstruction_robustness_table,
             "reconstruction_robustness_luo_filter": reconstruction_robustness_table,
             "reconstruction_robustness_curly_blond": reconstruction_robustness_table,
             "reconstruction_robustness_grain": reconstruction_robustness_table,
             "reconstruction_robustness_dark_neck": reconstruction_robustness_table,
             "reconstruction_robustness_curly_rest": reconstruction_robustness_table,
             "reconstruction_robustness_four_more": reconstruction_robustness_table,
             "reconstruction_robustness_cover": reconstruction_robustness_table,
             "reconstruction_robustness_default_cover": reconstruction_robustness_table,
             "reconstruction_robustness_outline": reconstruction_robustness_table,
             "reconstruction_robustness_streamline": reconstruction_robustness_table,
             "reconstruction_robustness_curls": reconstruction_robustness_table,
             "reconstruction_robustness_curls_both_ways": reconstruction_robustness_table,
             "reconstruction_robustness_curls_all": reconstruction_robustness_table,
             "reconstruction_robustness_default_curls": reconstruction_robustness_table,
             "reconstruction_robustness_curls_light": reconstruction_robustness_table,
             "reconstruction_robustness_curls_exposure": reconstruction_robustness_table,
             "reconstruction_robustness_curls_bend": reconstruction_robustness_table,
             "reconstruction_robustness_curls_whole_hair": reconstruction_robustness_table,
             "reconstruction_robustness_curls_helix_fit": reconstruction_robustness_table,
             "reconstruction_robustness_curls_free_space": reconstruction_robustness_table,
             "reconstruction_robustness_curls_less_bias": reconstruction_robustness_table,
             "strand_ceilings_curly_blond": strand_ceilings_table,
             "render_view": render_view_table, "modbus": modbus_table}


def load_record(name):
    path = os.path.join(FIGURES, name + ".json")
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit("docs_figures: %s: %s (record it with `docs_figures.py record`)" % (path, e))


def render(name):
    if name not in RENDERERS:
        raise SystemExit("docs_figures: no renderer '%s' (known: %s)" % (name, ", ".join(RENDERERS)))
    record = load_record(name)
    lines = RENDERERS[name](record)
    lines += ["", "Recorded with `%s`." % record["command"], ""]
    return "\n".join(lines) + "\n"


def update(check):
    differing = []
    docs = os.path.join(ROOT, "docs")
    for file in sorted(os.listdir(docs)):
        if not file.endswith(".md"):
            continue
        path = os.path.join(docs, file)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        new = BLOCK.sub(lambda m: m.group(1) + render(m.group(2)) + m.group(4), text)
        for m in BLOCK.finditer(text):
            if m.group(3) != render(m.group(2)):
                differing.append("docs/%s: the '%s' table" % (file, m.group(2)))
        if new != text and not check:
            with open(path, "w", encoding="utf-8") as f:
                f.write(new)
    return differing


def record(name, result_path, command):
    with open(result_path, encoding="utf-8") as f:
        result = json.load(f)
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True, check=True).stdout.strip()
    os.makedirs(FIGURES, exist_ok=True)
    out = os.path.join(FIGURES, name + ".json")
    with open(out, "w", encoding="utf-8") as f:
        json.dump({"command": command, "commit": commit,
                   "date": datetime.date.today().isoformat(), "result": result}, f, indent=1)
        f.write("\n")
    print(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 when a table differs")
    sub = parser.add_subparsers(dest="action")
    rec = sub.add_parser("record", help="store a bench's JSON output as docs/figures/NAME.json")
    rec.add_argument("name", choices=sorted(RENDERERS))
    rec.add_argument("result")
    rec.add_argument("command", help="the command that made the output, as a reader would type it")
    args = parser.parse_args()
    if args.action == "record":
        record(args.name, args.result, args.command)
        return 0
    differing = update(args.check)
    if args.check and differing:
        print("docs_figures: out of date with docs/figures/ (run python3 bench/docs_figures.py):")
        for d in differing:
            print("  " + d)
        return 1
    print("docs_figures: %s" % ("every table matches its record" if args.check else "tables written"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
