#!/usr/bin/env bash
# The glTF export and the console's 3D view on a default capture (20,000
# strands, 31 simulated frames: what scripts/demo writes), measured in one run:
#   - `hairrig export CAPTURE --simulation CAPTURE/simulation/head-shake`,
#     RUNS times (every strand, the head and the animation, plus the display
#     copy), wall time each;
#   - the 3D view in headless chromium (software WebGL, no GPU), RUNS times:
#     time from "Open" in the archive to the first frame of the model, and the
#     frames per second while the camera orbits for 5 s (chromium's own
#     requestAnimationFrame timing), as a drag draws it (every k-th strand
#     while the camera moves) and with every strand drawn, and while the
#     simulation plays for 5 s.
# Usage: bench/console_viewer_bench.sh [CAPTURE] [RUNS] [--json FILE]
#   CAPTURE: default the newest out/demo/capture-* with a simulation.
# Needs chromium and tests/console_browser/node_modules (scripts/install-deps --tests).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hairrig="$root/build/cli/hairrig"
capture=""
runs=3
json=""
while [ $# -gt 0 ]; do
  case "$1" in
    --json) json="$2"; shift 2 ;;
    *) if [ -z "$capture" ] && [ -d "$1" ]; then capture="$1"; else runs="$1"; fi; shift ;;
  esac
done
source "$root/bench/demo_capture.sh"
capture=$(demo_capture console_viewer_bench "$root" "$capture" simulation/head-shake/frames)
out="$root/out/console-viewer-bench"
rm -rf "$out"
mkdir -p "$out/screenshots"

export_s=()
for i in $(seq 1 "$runs"); do
  start=$(date +%s.%N)
  "$hairrig" --log-level warning export "$capture" --simulation "$capture/simulation/head-shake" \
    --out "$out/hair.glb" --json > "$out/export-$i.json"
  export_s+=("$(echo "$(date +%s.%N) - $start" | bc)")
done

source "$root/tests/support/start_console.sh"
start_console "$out/serve.log" "$hairrig" --captures "$(dirname "$capture")"
for i in $(seq 1 "$runs"); do
  node "$root/bench/console_viewer_bench.mjs" "$console_url" "$(basename "$capture")" \
    "$out/screenshots/run-$i" > "$out/view-$i.json"
done
stop_console

python3 - "$out" "$runs" "$capture" "${json:-}" "${export_s[@]}" <<'PY'
import json, statistics, sys
out, runs, capture, json_out = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
export_s = [float(x) for x in sys.argv[5:]]
summary = json.load(open(f"{out}/export-1.json"))
views = [json.load(open(f"{out}/view-{i}.json")) for i in range(1, runs + 1)]
result = {
    "capture": capture,
    "export_s": export_s,
    "export_full": summary["full"],
    "export_display": summary["display"],
    "first_frame_ms": [v["first_frame_ms"] for v in views],
    "orbit_fps": [v["orbit_fps"] for v in views],
    "orbit_fps_full_detail": [v["orbit_fps_full_detail"] for v in views],
    "play_fps": [v["play_fps"] for v in views if v["play_fps"] is not None],
    "software_renderer": all(v["software_renderer"] for v in views),
    "orbit_interval_ms_p95": [v["interval_ms_p95"] for v in views],
    "display_vertices": summary["display"]["vertices"],
    "strands": json.load(open(f"{capture}/reconstruction/strands/summary.json"))["strands"]["count"],
}
full, display = summary["full"], summary["display"]
print(f"export of {result['strands']:,} strands ({display['frames']} animation frames): "
      f"median {statistics.median(export_s):.2f} s {['%.2f' % s for s in export_s]}; "
      f"hair.glb {full['bytes'] / 1e6:.1f} MB, hair.display.glb {display['bytes'] / 1e6:.1f} MB "
      f"({display['vertices']:,} vertices)")
print(f"3D view, Open to first frame: median {statistics.median(result['first_frame_ms']):.0f} ms "
      f"{[round(x) for x in result['first_frame_ms']]}")
print(f"3D view while orbiting: median {statistics.median(result['orbit_fps']):.1f} frames/s "
      f"{[round(x, 1) for x in result['orbit_fps']]}, 95th-percentile frame interval "
      f"{statistics.median(result['orbit_interval_ms_p95']):.1f} ms; every strand drawn: "
      f"{statistics.median(result['orbit_fps_full_detail']):.1f} frames/s "
      f"(software WebGL: {result['software_renderer']})")
if result["play_fps"]:
    print(f"3D view playing the simulation: median {statistics.median(result['play_fps']):.1f} "
          f"frames/s {[round(x, 1) for x in result['play_fps']]}")
if json_out:
    json.dump(result, open(json_out, "w"), indent=1)
PY
