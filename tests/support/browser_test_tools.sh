# Sourced by the console's browser tests (tests/console_browser/run.sh,
# viewer_run.sh): exits 77 (skipped) with the reason when chromium, node or
# playwright-core (installed by scripts/install-deps --tests) is absent.
#   require_browser_test_tools DIR   (DIR: the folder with node_modules/)
require_browser_test_tools() {
  local dir="$1" need
  for need in /usr/bin/chromium "$(command -v node || echo node)"; do
    if [ ! -x "$need" ]; then
      echo "SKIPPED: $need is absent (scripts/install-deps --tests installs chromium and nodejs)"
      exit 77
    fi
  done
  if [ ! -d "$dir/node_modules/playwright-core" ]; then
    echo "SKIPPED: playwright-core is not installed in $dir (scripts/install-deps --tests runs npm ci there)"
    exit 77
  fi
}
