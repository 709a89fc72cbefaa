#!/usr/bin/env bash
# ctest tests/console_browser: the operator console in Debian's chromium,
# driven by playwright-core (console_browser.mjs) against `hairrig serve` on
# the default simulated rig at a quarter of real time (rig.yaml). Screenshots of each step go to $1/screenshots/.
# Exit 77 (skipped) with the reason when chromium, node or the npm package
# (installed by scripts/install-deps) is absent.
set -euo pipefail
hairrig="$1"
out="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/../support/browser_test_tools.sh"
require_browser_test_tools "$here"
rm -rf "$out"
mkdir -p "$out/captures" "$out/screenshots"
log="$out/serve.log"
source "$here/../support/start_console.sh"
start_console "$log" "$hairrig" --config "$here/rig.yaml" --captures "$out/captures"
url="$console_url"
echo "console at $url"
status=0
node "$here/console_browser.mjs" "$url" "$out/screenshots" || status=$?
if [ "$status" -ne 0 ]; then
  echo "--- hairrig serve's log ---"
  tail -n 50 "$log"
fi
exit "$status"
