# Sourced by the benches that measure a demo capture (console_viewer_bench.sh,
# blender_import_bench.sh):
#   demo_capture BENCH ROOT CAPTURE NEEDS
# prints CAPTURE, or when it is empty the newest ROOT/out/demo/capture-* that
# holds the path NEEDS (relative to the capture); fails naming BENCH and what
# to do when there is none.
demo_capture() {
  local bench="$1" root="$2" capture="$3" needs="$4"
  if [ -z "$capture" ]; then
    capture=$(ls -d "$root"/out/demo/capture-*/"$needs" 2>/dev/null | sort | tail -n 1 || true)
    capture="${capture%/"$needs"}"
  fi
  if [ -z "$capture" ] || [ ! -e "$capture/$needs" ]; then
    echo "$bench: no capture with $needs: run scripts/demo first, or give CAPTURE" >&2
    return 2
  fi
  echo "$capture"
}
