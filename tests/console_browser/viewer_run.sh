#!/usr/bin/env bash
# ctest tests/console_viewer: the console's 3D view in Debian's chromium. A
# capture of the batch tests' rig (tests/data/batch_rig.yaml: 16 views, 4,000
# strands) is calibrated and reconstructed, fitted, simulated for 10 frames
# and exported (`hairrig export --simulation`) through the command line; then
# viewer.mjs opens it in the console. Screenshots go to $2/screenshots/.
# Exit 77 (skipped) with the reason when chromium, node or playwright-core
# (installed by scripts/install-deps --tests) is absent.
set -euo pipefail
hairrig="$1"
out="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
source "$here/../support/browser_test_tools.sh"
require_browser_test_tools "$here"
rm -rf "$out"
mkdir -p "$out/captures" "$out/screenshots"
capture="$out/captures/wig-viewer"
rig="$root/tests/data/batch_rig.yaml"
quiet=(--log-level warning)
"$hairrig" "${quiet[@]}" capture --config "$rig" --out "$out/captures" --subject wig-viewer \
  --calibrate --reconstruct
"$hairrig" "${quiet[@]}" fit "$capture/reconstruction/strands/strands.ply" --guides 60 \
  --out "$capture/simulation/model.json"
"$hairrig" "${quiet[@]}" simulate "$capture/simulation/model.json" \
  --out "$capture/simulation/head-shake" --scenario head-shake --seconds 0.3 --fps 30 \
  --preview-every 0
"$hairrig" "${quiet[@]}" export "$capture" --simulation "$capture/simulation/head-shake"

log="$out/serve.log"
source "$here/../support/start_console.sh"
start_console "$log" "$hairrig" --config "$rig" --captures "$out/captures"
echo "console at $console_url"
status=0
node "$here/viewer.mjs" "$console_url" "$out/screenshots" wig-viewer || status=$?
if [ "$status" -ne 0 ]; then
  echo "--- hairrig serve's log ---"
  tail -n 50 "$log"
fi
exit "$status"
