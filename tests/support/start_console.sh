# Sourced by tests/console_browser/run.sh and bench/console_bench.sh:
#   start_console LOG HAIRRIG serve-arguments...
# starts `hairrig serve --listen 127.0.0.1:0 ...` in the background with its
# messages in LOG, sets console_pid and console_url once it serves, stops it
# when the calling script exits, and fails (status 1, with the log) when it
# ends or does not serve within 60 s.
start_console() {
  local log="$1" hairrig="$2"
  shift 2
  # The log exists before the loop reads it: the background job opens it
  # only once it runs.
  : >"$log"
  "$hairrig" serve --listen 127.0.0.1:0 "$@" 2>>"$log" >/dev/null &
  console_pid=$!
  trap 'kill "$console_pid" 2>/dev/null || true; wait "$console_pid" 2>/dev/null || true' EXIT
  console_url=""
  for _ in $(seq 1 600); do
    console_url=$(sed -n 's/.*the console is at \(http[^ ]*\).*/\1/p' "$log" | head -n 1)
    [ -n "$console_url" ] && return 0
    kill -0 "$console_pid" 2>/dev/null || { echo "hairrig serve ended:"; cat "$log"; return 1; }
    sleep 0.1
  done
  echo "hairrig serve did not start within 60 s:"
  cat "$log"
  return 1
}

# Stops the console start_console started.
stop_console() {
  kill "$console_pid" 2>/dev/null || true
  wait "$console_pid" 2>/dev/null || true
}
