#!/usr/bin/env bash
# The simulation in glTF: frame nodes against morph targets
# (`hairrig export --animation-encoding nodes|morph`), on a default capture's
# head shake (31 frames; 500 strands a frame and the 300 guides), in one run:
#   - the bytes the animation adds to hair.glb (the export with the
#     simulation less the export without it) and the export's wall time;
#   - where Blender is installed, its own importer on each file: import time,
#     objects, actions and shape keys made, the scene's evaluation time per
#     frame as playback steps through it, and the animated strands' largest
#     move from frame 0 to the last frame (0: it does not play);
#   - three.js r111 (the console's) is not run on the morph file: its Line
#     has no morphTargetInfluences, so lines do not morph there (the console's
#     playback of frame nodes is measured by bench/console_viewer_bench.sh).
# Usage: bench/gltf_animation_bench.sh [CAPTURE] [--animation-strands N] [--json FILE]
#   CAPTURE: default the newest out/demo/capture-* whose simulation has guides/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hairrig="$root/build/cli/hairrig"
capture=""
json=""
strands=500
while [ $# -gt 0 ]; do
  case "$1" in
    --json) json="$2"; shift 2 ;;
    --animation-strands) strands="$2"; shift 2 ;;
    *) capture="$1"; shift ;;
  esac
done
source "$root/bench/demo_capture.sh"
capture=$(demo_capture gltf_animation_bench "$root" "$capture" simulation/head-shake/guides)
out="$root/out/gltf-animation-bench"
rm -rf "$out"
mkdir -p "$out"

seconds() { python3 -c 'import sys, time; print(time.time())'; }
"$hairrig" --log-level warning export "$capture" --out "$out/static.glb" --json > "$out/static.json"
for encoding in nodes morph; do
  start=$(seconds)
  "$hairrig" --log-level warning export "$capture" --simulation "$capture/simulation/head-shake" \
    --animation-strands "$strands" --animation-encoding "$encoding" --out "$out/$encoding.glb" \
    --json > "$out/$encoding.json"
  echo "$(seconds) - $start" | bc > "$out/$encoding.export_s"
  if command -v blender > /dev/null 2>&1; then
    if ! blender -b --factory-startup --python-exit-code 1 -P "$root/bench/blender_animation.py" \
      -- "$out/$encoding.glb" head-shake > "$out/$encoding.blender.log" 2>&1 ||
      ! grep '^{' "$out/$encoding.blender.log" > "$out/$encoding.blender.json"; then
      echo "gltf_animation_bench: Blender could not import $out/$encoding.glb:" >&2
      tail -n 15 "$out/$encoding.blender.log" >&2
      exit 1
    fi
  fi
done

python3 - "$out" "$capture" "$strands" "$json" <<'PY'
import json, os, sys
out, capture, strands, json_out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
static = json.load(open(f"{out}/static.json"))["full"]["bytes"]
result = {"capture": capture, "animation_strands": strands, "encodings": {}}
for encoding in ("nodes", "morph"):
    summary = json.load(open(f"{out}/{encoding}.json"))
    row = {"animation_bytes": summary["full"]["bytes"] - static,
           "file_bytes": summary["full"]["bytes"],
           "frames": summary["display"]["frames"], "guides": summary["guides"],
           "export_s": float(open(f"{out}/{encoding}.export_s").read())}
    blender = f"{out}/{encoding}.blender.json"
    row["blender"] = json.load(open(blender)) if os.path.exists(blender) else None
    result["encodings"][encoding] = row
    line = (f"{encoding:5s}: the animation adds {row['animation_bytes'] / 1e6:.2f} MB "
            f"({row['frames']} frames of {strands} strands and {row['guides']} guides); "
            f"export {row['export_s']:.2f} s")
    b = row["blender"]
    if b:
        line += (f"; Blender: import {b['import_s']:.2f} s, {b['objects']} objects, "
                 f"{b['actions']} actions, {b['shape_keys']} shape keys, "
                 f"{1e3 * b['frame_s']:.2f} ms a frame, largest move {1e3 * b['largest_move_m']:.0f} mm")
    else:
        line += "; Blender: SKIPPED (blender is absent: apt-get install blender python3-numpy)"
    print(line)
if json_out:
    json.dump(result, open(json_out, "w"), indent=1)
PY
