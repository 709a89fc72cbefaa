#!/usr/bin/env bash
# The operator console's costs on the default simulated rig, measured in one run:
#   - a capture's wall time through the console (page open, events streaming,
#     thumbnails) against the same capture by `hairrig capture`, alternating
#     RUNS times each (ratio of medians);
#   - how long a stored view takes to appear in the page (frame_stored's time
#     in the journal to the thumbnail loaded in chromium);
#   - the live view's frames per second per camera between captures.
# Usage: bench/console_bench.sh [RUNS]   (from the repository root, after scripts/test;
# needs chromium and tests/console_browser/node_modules, which scripts/install-deps installs)
set -euo pipefail
runs="${1:-3}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hairrig="$root/build/cli/hairrig"
out="$root/out/console-bench"
source "$root/tests/support/start_console.sh"
rm -rf "$out"
mkdir -p "$out"
for i in $(seq 1 "$runs"); do
  "$hairrig" capture --out "$out/cli-$i" --json > "$out/cli-$i.json" 2>/dev/null || true
  start_console "$out/serve-$i.log" "$hairrig" --captures "$out/console-$i"
  node "$root/bench/console_bench.mjs" "$console_url" "$out/console-$i" > "$out/console-$i.json"
  stop_console
done
python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
cli = [json.load(open(f"{out}/cli-{i}.json"))["wall_s"] for i in range(1, runs + 1)]
con = [json.load(open(f"{out}/console-{i}.json")) for i in range(1, runs + 1)]
walls = [c["wall_s"] for c in con]
lat = sorted(x for c in con for x in c["view_latency_ms"])
fps = [f for c in con for f in c["live_fps"].values()]
print(f"capture wall time: CLI median {statistics.median(cli):.2f} s {cli}, "
      f"console median {statistics.median(walls):.2f} s {walls}")
print(f"console / CLI: {statistics.median(walls) / statistics.median(cli):.3f}")
print(f"stored view to thumbnail in the page: median {statistics.median(lat):.0f} ms, "
      f"90th {lat[int(0.9 * (len(lat) - 1))]:.0f} ms, max {lat[-1]:.0f} ms over {len(lat)} views")
print(f"live view between captures: {min(fps):.2f} - {max(fps):.2f} frames/s per camera")
PY
