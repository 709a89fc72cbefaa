#!/usr/bin/env python3
"""The operator console under a connection flood, measured in one run.

Starts `hairrig serve` on the default simulated rig, then:
  1. measures the server's CPU over a window with no extra connections
     (the live view's renders included);
  2. opens IDLE connections that send nothing and SLOW ones that send a
     request's headers one byte a second (each opened again when the server
     closes it), and measures the server's CPU over the same window;
  3. under that load, presses the e-stop TRIES times (a new connection each,
     as a panicking operator's page would) and reads the state each time,
     timing each from the request's first byte to the whole response; the
     e-stop's response comes after the rig has acted (turntable stopped,
     lights off, a running capture stopped);
  4. under the same load, starts a capture and checks that it completes with
     every frame matching its journal record's SHA-256.

Usage (from the repository root, after scripts/build):
  python3 bench/console_load_bench.py [--hairrig build/cli/hairrig]
      [--idle 2000] [--slow 200] [--tries 20] [--window 10] [--json OUT]

Prints one line per figure and, with --json, writes them to OUT. Standard
library only. Exits 1 when the console cannot be started.
"""

import argparse
import collections
import hashlib
import json
import os
import re
import resource
import select
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid):
    """User + system CPU seconds of process `pid` (all its threads)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def cpu_share(pid, seconds):
    start = cpu_seconds(pid)
    time.sleep(seconds)
    return (cpu_seconds(pid) - start) / seconds


def request(port, method, path, body=None, headers=None, timeout=30.0):
    """(status or None, body text, seconds) of one request on a new connection."""
    start = time.monotonic()
    text = f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n"
    for name, value in (headers or {}).items():
        text += f"{name}: {value}\r\n"
    payload = b""
    if body is not None:
        payload = json.dumps(body).encode()
        text += f"Content-Type: application/json\r\nContent-Length: {len(payload)}\r\n"
    data = b""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
            s.settimeout(max(0.001, timeout - (time.monotonic() - start)))
            s.sendall(text.encode() + b"\r\n" + payload)
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                data += chunk
    except OSError:
        return None, "", time.monotonic() - start
    seconds = time.monotonic() - start
    head, _, rest = data.partition(b"\r\n\r\n")
    match = re.match(rb"HTTP/1\.[01] (\d{3})", head)
    return (int(match.group(1)) if match else None), rest.decode(errors="replace"), seconds


class Pressure:
    """IDLE silent connections and SLOW one-byte-a-second ones, refilled when closed."""

    def __init__(self, port, idle, slow):
        self.port, self.idle, self.slow = port, [None] * idle, [None] * slow
        self.reopened = 0
        self.failed_connects = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self):
        self._refill(self.idle)
        self._refill(self.slow)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        for s in self.idle + self.slow:
            if s is not None:
                s.close()

    def _closed(self, s):
        poller = select.poll()
        poller.register(s, select.POLLIN)
        if not poller.poll(0):
            return False
        try:
            return s.recv(1, socket.MSG_PEEK) == b""
        except OSError:
            return True

    def _refill(self, sockets):
        for i, s in enumerate(sockets):
            if s is not None and not self._closed(s):
                continue
            if s is not None:
                s.close()
                self.reopened += 1
            try:
                sockets[i] = socket.create_connection(("127.0.0.1", self.port), timeout=5)
            except OSError:
                sockets[i] = None
                self.failed_connects += 1

    def _run(self):
        header = b"POST /api/estop HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        tick = 0
        while not self._stop.wait(1.0):
            self._refill(self.idle)
            self._refill(self.slow)
            byte = header[tick % len(header):tick % len(header) + 1]
            for s in self.slow:
                if s is not None:
                    try:
                        s.send(byte)
                    except OSError:
                        pass
            tick += 1


def keep_log_tail(proc):
    """Reads the console's stderr to its end, keeping the last lines in proc.stderr_tail."""
    for line in proc.stderr:
        proc.stderr_tail.append(line.rstrip("\n")[:1000])


def start_console(hairrig, captures, extra=(), live_fps="1"):
    """(process, port) of `hairrig serve` on 127.0.0.1 with `extra` arguments; the last lines
    of its stderr are kept in process.stderr_tail. Exits when it does not start."""
    proc = subprocess.Popen([hairrig, "serve", "--listen", "127.0.0.1:0", "--captures", captures,
                             "--live-fps", live_fps, *extra], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, errors="replace")
    proc.stderr_tail = collections.deque(maxlen=200)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        proc.stderr_tail.append(line.rstrip("\n")[:1000])
        match = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
        if match:
            threading.Thread(target=keep_log_tail, args=(proc,), daemon=True).start()
            return proc, int(match.group(1))
    proc.kill()
    proc.wait()
    sys.exit("console_load_bench: the console did not start: " + " | ".join(proc.stderr_tail))


def frames_verified(capture):
    """(frames whose bytes match their journal record, frames recorded)."""
    good = total = 0
    with open(os.path.join(capture, "journal.jsonl")) as f:
        for line in f:
            record = json.loads(line)
            if record.get("event") != "frame_stored":
                continue
            total += 1
            try:
                with open(os.path.join(capture, record["file"]), "rb") as frame:
                    good += hashlib.sha256(frame.read()).hexdigest() == record["sha256"]
            except OSError:
                pass
    return good, total


def run_capture(port, lease, captures):
    status, body, _ = request(port, "POST", "/api/captures",
                              {"subject": "under load", "calibrate": False},
                              {"X-Hairrig-Lease": lease})
    if status != 202:
        return {"started": False, "error": body}
    capture_id = json.loads(body)["id"]
    start = time.monotonic()
    busy = "capturing"
    while busy != "idle" and time.monotonic() - start < 900:
        time.sleep(1)
        request(port, "POST", "/api/control/heartbeat", {}, {"X-Hairrig-Lease": lease})
        status, body, _ = request(port, "GET", "/api/state")
        if status == 200:
            busy = json.loads(body)["busy"]
    good, total = frames_verified(os.path.join(captures, capture_id))
    return {"started": True, "wall_s": time.monotonic() - start, "frames": total,
            "frames_verified": good}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hairrig", default="build/cli/hairrig")
    parser.add_argument("--idle", type=int, default=2000)
    parser.add_argument("--slow", type=int, default=200)
    parser.add_argument("--tries", type=int, default=20)
    parser.add_argument("--window", type=float, default=10.0)
    parser.add_argument("--timeout", type=float, default=30.0, help="per request, seconds")
    parser.add_argument("--live-fps", default="1",
                        help="the console's live view (its renders are most of its CPU)")
    parser.add_argument("--skip-capture", action="store_true")
    parser.add_argument("--json")
    args = parser.parse_args()

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    wanted = args.idle + args.slow + 256
    if soft < wanted:
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(wanted, hard), hard))
    captures = tempfile.mkdtemp(prefix="console_load_")
    proc, port = start_console(args.hairrig, captures, live_fps=args.live_fps)
    result = {"idle": args.idle, "slow": args.slow, "live_fps": float(args.live_fps)}
    try:
        time.sleep(2)
        result["cpu_no_load"] = cpu_share(proc.pid, args.window)
        status, body, _ = request(port, "POST", "/api/control", {"client": "bench"})
        lease = json.loads(body)["lease"]
        with Pressure(port, args.idle, args.slow) as pressure:
            time.sleep(2)
            result["cpu_under_load"] = cpu_share(proc.pid, args.window)
            estop, state, answered = [], [], 0
            for _ in range(args.tries):
                status, body, seconds = request(port, "POST", "/api/estop", {"client": "bench"},
                                                timeout=args.timeout)
                active = status == 200 and json.loads(body)["estop"]["active"]
                answered += bool(active)
                estop.append(seconds if active else float("inf"))
                status, _, seconds = request(port, "GET", "/api/state", timeout=args.timeout)
                state.append(seconds if status == 200 else float("inf"))
                request(port, "POST", "/api/estop/release", {}, {"X-Hairrig-Lease": lease},
                        timeout=args.timeout)
                request(port, "POST", "/api/control/heartbeat", {}, {"X-Hairrig-Lease": lease},
                        timeout=args.timeout)
            result.update(estop_answered=answered, tries=args.tries,
                          estop_ms=[round(s * 1000, 1) for s in estop],
                          state_ms=[round(s * 1000, 1) for s in state])
            result["capture"] = ({"started": False, "error": "--skip-capture"} if args.skip_capture
                                 else run_capture(port, lease, captures))
            result["reopened_connections"] = pressure.reopened
            result["failed_connects"] = pressure.failed_connects
    finally:
        proc.terminate()
        proc.wait(timeout=60)
        shutil.rmtree(captures, ignore_errors=True)

    ms = sorted(result["estop_ms"])
    st = sorted(result["state_ms"])
    print(f"load: {args.idle} idle + {args.slow} slow-header connections held "
          f"({result['reopened_connections']} reopened after the server closed them)")
    print(f"e-stop acted on: {result['estop_answered']} of {args.tries}; "
          f"median {statistics.median(ms):.1f} ms, max {ms[-1]:.1f} ms")
    print(f"state read: median {statistics.median(st):.1f} ms, max {st[-1]:.1f} ms")
    print(f"server CPU: {100 * result['cpu_no_load']:.1f} % of a core without the load, "
          f"{100 * result['cpu_under_load']:.1f} % with it ({args.window:.0f} s windows)")
    cap = result["capture"]
    if cap.get("started"):
        print(f"capture under load: {cap['frames_verified']} of {cap['frames']} frames verified "
              f"in {cap['wall_s']:.1f} s")
    else:
        print(f"capture under load: not started: {cap.get('error')}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
