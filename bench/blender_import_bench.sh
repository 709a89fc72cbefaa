#!/usr/bin/env bash
# A hairrig glTF in Blender: Blender's own importer reads the file, the
# strands (a mesh of edges) are converted to curves, and the splines are
# counted against the reconstruction's strands (every one in hair.glb, every
# k-th in hair.display.glb). Converting the full file's 4.8 million points to
# curves takes Blender about 6 minutes on one core.
# Usage: bench/blender_import_bench.sh [CAPTURE] (default: the newest out/demo/capture-*)
# Prints "SKIPPED: ..." and exits 0 where Blender is absent (Debian package blender).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hairrig="$root/build/cli/hairrig"
if ! command -v blender >/dev/null 2>&1; then
  echo "SKIPPED: blender is absent (apt-get install blender python3-numpy: Debian 12 has 3.4)"
  exit 0
fi
source "$root/bench/demo_capture.sh"
capture=$(demo_capture blender_import_bench "$root" "${1:-}" reconstruction/strands/strands.ply)
out="$root/out/blender-bench"
rm -rf "$out"
mkdir -p "$out"
sim=()
if [ -d "$capture/simulation/head-shake/frames" ]; then sim=(--simulation "$capture/simulation/head-shake"); fi
"$hairrig" --log-level warning export "$capture" "${sim[@]}" --out "$out/hair.glb" --json > "$out/export.json"
for level in hair hair.display; do
  if ! blender -b --factory-startup --python-exit-code 1 -P "$root/bench/blender_import.py" -- \
    "$out/$level.glb" > "$out/$level.log" 2>&1 || ! grep '^{' "$out/$level.log" > "$out/$level.json"; then
    echo "blender_import_bench: Blender could not import $out/$level.glb:" >&2
    tail -n 15 "$out/$level.log" >&2
    exit 1
  fi
done
python3 - "$out" "$capture" <<'PY'
import json, sys
out = sys.argv[1]
capture = sys.argv[2]
n = json.load(open(f"{capture}/reconstruction/strands/summary.json"))["strands"]["count"]
stride = -(-n // 2000)  # the display copy keeps every stride-th strand (--display-strands 2000)
for level, expected in (("hair", n), ("hair.display", -(-n // stride))):
    b = json.load(open(f"{out}/{level}.json"))
    verdict = "as written" if b["splines"] == expected else f"EXPECTED {expected:,}"
    print(f"{level}.glb: {b['splines']:,} curves in Blender ({verdict}; {b['spline_points']:,} points), "
          f"strands {b['size_m'][0]:.3f} x {b['size_m'][1]:.3f} x {b['size_m'][2]:.3f} m, "
          f"z {b['z_m'][0]:.3f} .. {b['z_m'][1]:.3f} m, head {'yes' if b['head'] else 'no'}, "
          f"{b['actions']} action(s) ending at frame {max((r[1] for r in b['frame_range']), default=0):.1f} "
          f"(Blender's 24 fps); import {b['import_s']:.1f} s, "
          f"to curves {b['convert_s']:.1f} s")
PY
