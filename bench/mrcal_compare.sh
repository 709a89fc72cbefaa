#!/usr/bin/env bash
# ChArUco intrinsics side by side with mrcal (Debian package `mrcal`) on the
# same corners: `hairrig sim charuco` renders a camera's board images with
# ground truth, `hairrig calibrate-intrinsics` solves them and writes its
# corners as mrcal's corners cache, mrcal-calibrate-cameras solves the same
# corners (LENSMODEL_OPENCV4: k1 k2 p1 p2, as ours with k3 held), and both are
# compared with the truth. Run from the repository root after building:
#   bench/mrcal_compare.sh [VIEWS] [SERIAL]
# mrcal is not a build dependency; install it with `apt-get install mrcal` (its
# Python module is the system one, so /usr/bin/python3 runs the comparison).
set -euo pipefail
views="${1:-25}"
serial="${2:-SIM-CAM-UPPER}"
hairrig="${HAIRRIG:-build/cli/hairrig}"
if ! command -v mrcal-calibrate-cameras >/dev/null; then
  echo "mrcal_compare: mrcal is not installed (apt-get install mrcal)" >&2
  exit 2
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$hairrig" sim charuco --out "$work" --camera "$serial" --views "$views" >/dev/null
dir="$work/$serial"
start=$(date +%s.%N)
"$hairrig" calibrate-intrinsics "$dir" --board etc/charuco-board.yaml --serial "$serial" \
  --mrcal-corners "$work/corners.vnl" >/dev/null
ours_s=$(echo "$(date +%s.%N) - $start" | bc)
read -r squares_x squares_y square_mm < <(python3 -c "
import re
text = open('etc/charuco-board.yaml').read()
sx, sy = re.search(r'squares:\s*\[(\d+),\s*(\d+)\]', text).groups()
print(int(sx), int(sy), re.search(r'square_mm:\s*([0-9.]+)', text).group(1))")
focal=$(python3 -c "import json; print(json.load(open('$dir/ground_truth.json'))['intrinsics']['fx_px'])")
start=$(date +%s.%N)
(cd "$dir" && mrcal-calibrate-cameras --corners-cache "$work/corners.vnl" --lensmodel LENSMODEL_OPENCV4 \
  --focal "$focal" --object-spacing "$square_mm" --object-width-n $((squares_x - 1)) \
  --object-height-n $((squares_y - 1)) --outdir "$work" 'view_*.png' >"$work/mrcal.log" 2>&1) ||
  { cat "$work/mrcal.log" >&2; exit 1; }
mrcal_s=$(echo "$(date +%s.%N) - $start" | bc)
/usr/bin/python3 - "$dir" "$work/camera-0.cameramodel" "$ours_s" "$mrcal_s" <<'PY'
import json, sys
import mrcal
truth = json.load(open(sys.argv[1] + "/ground_truth.json"))["intrinsics"]
ours = json.load(open(sys.argv[1] + "/intrinsics.json"))
ours_k, ours_sd = ours["intrinsics"], ours["intrinsics_stddev"]
_, mrcal_k = mrcal.cameramodel(sys.argv[2]).intrinsics()
names = ["fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2"]
print(f"# {len(ours['images'])} images, {ours['images_used']} used; ours {float(sys.argv[3]):.2f} s "
      f"(detection + solve), mrcal {float(sys.argv[4]):.2f} s (solve on our corners)")
print(f"{'param':8} {'truth':>12} {'ours':>12} {'ours_err':>10} {'ours_sd':>9} {'mrcal':>12} {'mrcal_err':>10}")
for i, name in enumerate(names):
    t, o, m = truth[name], ours_k[name], float(mrcal_k[i])
    print(f"{name:8} {t:12.6f} {o:12.6f} {o - t:+10.4g} {ours_sd[name]:9.3g} {m:12.6f} {m - t:+10.4g}")
def pp(k): return ((k[0] - truth["cx_px"]) ** 2 + (k[1] - truth["cy_px"]) ** 2) ** 0.5
def focal(k): return 100 * max(abs(k[0] / truth["fx_px"] - 1), abs(k[1] / truth["fy_px"] - 1))
print(f"focal error: ours {focal([ours_k['fx_px'], ours_k['fy_px']]):.4f} %, "
      f"mrcal {focal([float(mrcal_k[0]), float(mrcal_k[1])]):.4f} %")
print(f"principal point error: ours {pp([ours_k['cx_px'], ours_k['cy_px']]):.3f} px, "
      f"mrcal {pp([float(mrcal_k[2]), float(mrcal_k[3])]):.3f} px")
PY
