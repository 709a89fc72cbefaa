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
for need in /usr/bin/chromium "$(command -v node || echo node)"; do
  if [ ! -x "$need" ]; then
    echo "SKIPPED: $need is absent (scripts/install-deps installs chromium and nodejs)"
    exit 77
  fi
done
if [ ! -d "$here/node_modules/playwright-core" ]; then
  echo "SKIPPED: playwright-core is not installed in $here (scripts/install-deps runs npm ci there)"
  exit 77
fi
rm -rf "$out"
mkdir -p "$out/captures" "$out/screenshots"
log="$out/serve.log"
"$hairrig" serve --config "$here/rig.yaml" --listen 127.0.0.1:0 --captures "$out/captures" 2>"$log" &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true' EXIT
url=""
for _ in $(seq 1 600); do
  url=$(sed -n 's/.*the console is at \(http[^ ]*\).*/\1/p' "$log" | head -n 1)
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { echo "hairrig serve ended:"; cat "$log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "hairrig serve did not start within 60 s:"; cat "$log"; exit 1; }
echo "console at $url"
status=0
node "$here/console_browser.mjs" "$url" "$out/screenshots" || status=$?
if [ "$status" -ne 0 ]; then
  echo "--- hairrig serve's log ---"
  tail -n 50 "$log"
fi
exit "$status"
