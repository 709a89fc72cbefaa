#!/usr/bin/env python3
"""Hostile-input campaign against the built `hairrig` command line.

Feeds the CLI seeded, deterministic hostile input in ten categories and
counts per category how each run ended:

  crash    killed by a signal, an exit code >= 128, or "terminate called" /
           a sanitizer report in the output
  hang     still running when the per-run timeout expired (the process group
           is killed)
  silent   a silent success: exit 0 where an error was due, a success whose
           result is damaged (invalid manifest, a frame that is not what its
           record vouches for, a replayed frame that is not the recorded one,
           a "good" calibration from a damaged frame, non-finite numbers
           written, a damaged frame used by a later stage without being named
           in its summary's left_out), any file changed or created outside
           the places the command may write (the capture or its output
           folder), or, for COLMAP input, a file outside the model and images
           folders read (its access time moves)
  clean    exit 1 with "hairrig: error: <message>" (not an internal error)
  handled  a correct outcome that is not an error: exit 0 on input that is
           valid or that the command repairs (resume re-shooting a damaged
           frame), exit 3 where the run is rightly incomplete (replay of a
           recording with a damaged frame), a failed calibration verdict (3)
           for a prior that belongs to another camera, a stage that completes
           with the damaged frames named as left out; each is checked
  other    anything else: another exit code, "internal error (please report
           it)" (an exception that reached main), a message that prints the
           content of a file the input names, a correct refusal without the
           "hairrig: error:" form

Categories (as in the hostile-input issue): journal frame records, dataset
files (capture.json, manifest.json, temporaries, frames/, journal, rig.yaml
snapshot), rig config files, calibration priors and inputs, strand files,
helix models, path escapes; COLMAP input (`reconstruct --colmap MODEL
--images DIR` on the calibration's COLMAP export of the capture, edited:
names leaving the images folder, special files, hostile PNG and JPEG
headers, repeated ids and names, non-finite or out-of-range numbers, short
lines, missing files and folders); stage inputs (`reconstruct`, `stage
reconstruct`, `calibrate`, `stage calibrate` and `eval reconstruction` on a
calibrated or reconstructed copy whose frames, frames/ folder,
calibration.json or ground truth are damaged); console load (`hairrig serve`
on 127.0.0.1 under a connection flood and malformed requests, with
bench/console_load_bench.py's helpers). For the console a case is clean when
the request is refused with a 4xx status or by closing the connection,
handled when the console serves it as it should (the e-stop acted on within
1 s), silent when it accepts what must be refused or serves a file outside
its captures, hang when it stops answering /api/state or the e-stop within
10 s, crash when the process dies.

One capture of the small test rig (tests/data/small_rig.yaml with absolute
paths and the calibration section of etc/sim-rig.yaml added, so that
`calibrate` runs on it) is recorded at the start, and a calibrated copy of it
kept; every variant works on its own copy. Variants marked slow (a stage that
runs the whole reconstruction) are left out of --quick unless they are core.
Run from the repository root:

  python3 bench/hostile_campaign.py [--hairrig build/cli/hairrig] [--quick]
      [--seed N] [--json OUT] [--timeout S] [--only TEXT] [--keep]

Prints the table and every case that is not clean or handled (category,
variant, command, exit code, first line of output); `--only TEXT` runs the
variants whose "category/variant" contains TEXT, `--keep` keeps the work
folder of every such case. Standard library only. Always exits 0.
"""

import argparse
import copy
import hashlib
import json
import math
import os
import random
import re
import resource
import select
import shutil
import signal
import socket
import stat
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from dataclasses import dataclass
from typing import Callable, List, Optional

OUTCOMES = ["crash", "hang", "silent", "clean", "handled", "other"]
NOT_CLEAN = {"crash", "hang", "silent", "other"}
OUTPUT_LIMIT = 2 << 20  # bytes of a run's output kept for the checks

ERROR = frozenset()          # an error is due
SUCCESS = frozenset({0})     # the input is valid or the command repairs it
INCOMPLETE = frozenset({3})  # the run ends incomplete (replay of a damaged view)
EITHER = frozenset({0, 3})


# ---------------------------------------------------------------------------
# Running one command


@dataclass
class RunResult:
    code: Optional[int]
    output: str
    hung: bool
    seconds: float


def run_command(argv, timeout, cwd):
    """Runs argv in its own process group; on timeout the group is killed."""
    with tempfile.TemporaryFile() as log:
        start = time.monotonic()
        proc = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                cwd=cwd, start_new_session=True)
        hung = False
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            hung = True
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        seconds = time.monotonic() - start
        log.seek(0)
        output = log.read(OUTPUT_LIMIT).decode("utf-8", "replace")
    return RunResult(None if hung else proc.returncode, output, hung, seconds)


SUMMARY_KEYS = ["status", "verdict", "views_solved", "views_completed", "missing_views", "reasons"]


def first_line(output):
    """The error line, a JSON summary's telling fields, or the first line."""
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    for line in lines:
        if "hairrig: error" in line or "terminate called" in line:
            return line[:240]
    summary = parse_last_json(output)
    if isinstance(summary, dict):
        return json.dumps({k: summary[k] for k in SUMMARY_KEYS if k in summary})[:240]
    return lines[0][:240] if lines else ""


# ---------------------------------------------------------------------------
# File-system state: what a run may not change


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def entry_state(path):
    """Type and content of one entry, never opening anything but a regular file."""
    st = os.lstat(path)
    if stat.S_ISLNK(st.st_mode):
        return ("link", os.readlink(path))
    if stat.S_ISREG(st.st_mode):
        return ("file", st.st_size, sha256_file(path), st.st_ino)
    if stat.S_ISDIR(st.st_mode):
        return ("dir",)
    return ("special", stat.S_IFMT(st.st_mode))


def tree_state(root, exclude=()):
    """{relative path: state} of a tree (symlinks not followed); {} when absent."""
    if not os.path.lexists(root):
        return {}
    state = {".": entry_state(root)}
    if state["."][0] != "dir":
        return state
    for here, dirs, files in os.walk(root):
        rel_here = os.path.relpath(here, root)
        dirs[:] = [d for d in dirs if os.path.normpath(os.path.join(rel_here, d)) not in exclude]
        for name in dirs + files:
            rel = os.path.normpath(os.path.join(rel_here, name))
            if rel not in exclude:
                state[rel] = entry_state(os.path.join(here, name))
    return state


def tree_changes(before, after):
    changed = [p for p in before if after.get(p) != before[p]]
    added = [p for p in after if p not in before]
    return changed + added


def listing(path):
    try:
        return set(os.listdir(path))
    except OSError:
        return set()


def bait_file(path):
    """Sets the file's access time an hour before its modification time, so that a read moves
    it (relatime updates it then); {path: that access time}."""
    st = os.lstat(path)
    atime = st.st_mtime_ns - 3600 * 10**9
    os.utime(path, ns=(atime, st.st_mtime_ns))
    return {path: atime}


def bait_reads(folder):
    """bait_file on every regular file under `folder` (symlinks not followed)."""
    baits = {}
    for here, _, files in os.walk(folder):
        for name in files:
            path = os.path.join(here, name)
            if stat.S_ISREG(os.lstat(path).st_mode):
                baits.update(bait_file(path))
    return baits


def baits_read(baits):
    """The baited files whose access time moved: something read them."""
    read = []
    for path, atime in baits.items():
        try:
            if os.lstat(path).st_atime_ns != atime:
                read.append(path)
        except OSError:
            pass
    return read


def access_times_recorded(folder):
    """Whether reading a file in `folder` moves its access time (not on a noatime mount)."""
    probe = os.path.join(folder, "atime_probe")
    write_bytes(probe, b"x")
    try:
        baits = bait_file(probe)
        with open(probe, "rb") as f:
            f.read()
        return bool(baits_read(baits))
    finally:
        os.remove(probe)


# ---------------------------------------------------------------------------
# Datasets: what a success must leave behind


def load_json_file(path):
    """The parsed file, or None; NaN/Infinity tokens are refused."""
    def refuse(token):
        raise ValueError(token)
    try:
        st = os.lstat(path)
        if not stat.S_ISREG(st.st_mode):
            return None
        with open(path, "rb") as f:
            return json.loads(f.read().decode("utf-8"), parse_constant=refuse)
    except (OSError, ValueError):
        return None


def frame_file_problem(cap, record, genuine, planned_serials):
    """Why a manifest frame entry does not hold the frame it names, or None."""
    view = record.get("view")
    if not isinstance(view, int) or view not in planned_serials:
        return "manifest frame with view %r" % (view,)
    if record.get("serial") != planned_serials[view]:
        return "view %d holds serial %r, planned %r" % (view, record.get("serial"), planned_serials[view])
    name = record.get("file")
    if not isinstance(name, str) or not name.startswith("frames/%03d_" % view) or "/" in name[7:]:
        return "view %d names file %r" % (view, name)
    path = os.path.join(cap, name)
    if not os.path.lexists(path) or not stat.S_ISREG(os.lstat(path).st_mode):
        return "view %d: %s is not a regular file" % (view, name)
    actual = sha256_file(path)
    if actual != record.get("sha256"):
        return "view %d: %s does not match its SHA-256" % (view, name)
    if record.get("bytes") != os.path.getsize(path):
        return "view %d: the manifest gives %r bytes, %s has %d" % (view, record.get("bytes"), name,
                                                                    os.path.getsize(path))
    for other, sha in genuine.items():
        if sha == actual and other != view:
            return "view %d holds the frame of view %d" % (view, other)
    return None


def dataset_problem(cap, genuine, planned_serials):
    """Why a capture that a command reported complete is not, or None."""
    manifest = load_json_file(os.path.join(cap, "manifest.json"))
    if not isinstance(manifest, dict) or not isinstance(manifest.get("frames"), list):
        return "manifest.json is not a valid manifest"
    views = [f.get("view") if isinstance(f, dict) else None for f in manifest["frames"]]
    if sorted(v for v in views if isinstance(v, int)) != sorted(planned_serials) or len(views) != len(planned_serials):
        return "manifest views %s, planned %d views" % (compact_list(views), len(planned_serials))
    if manifest.get("status") != "complete" or manifest.get("views_completed") != len(planned_serials):
        return "manifest status %r, %r views completed" % (manifest.get("status"), manifest.get("views_completed"))
    for record in manifest["frames"]:
        problem = frame_file_problem(cap, record, genuine, planned_serials)
        if problem:
            return problem
    number = 0
    try:
        with open(os.path.join(cap, "journal.jsonl"), "rb") as f:
            for number, line in enumerate(f.read().decode("utf-8").splitlines(), 1):
                if line.strip():
                    json.loads(line)
    except (OSError, ValueError):
        return "journal.jsonl line %d is not JSON after the run" % number
    return None


def replay_problem(out, genuine, planned_serials, complete):
    """Why a replay's output is wrong: a served frame that is not the recorded one."""
    manifest = load_json_file(os.path.join(out, "manifest.json"))
    if not isinstance(manifest, dict) or not isinstance(manifest.get("frames"), list):
        return "replay output has no valid manifest.json"
    for record in manifest["frames"]:
        if not isinstance(record, dict):
            return "replay manifest holds %r" % (record,)
        view = record.get("view")
        path = os.path.join(out, str(record.get("file")))
        if view not in genuine or not os.path.isfile(path) or sha256_file(path) != genuine[view]:
            return "replay served view %r with a frame that is not the one recorded for it" % (view,)
    if complete and len(manifest["frames"]) != len(planned_serials):
        return "replay complete with %d of %d views" % (len(manifest["frames"]), len(planned_serials))
    return None


def compact_list(values):
    text = str(values)
    return text if len(text) < 80 else text[:77] + "..."


def hair_points_finite(path):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 128 or data[:4] != b"HAIR":
        return False
    strands, points, flags = struct.unpack_from("<III", data, 4)
    offset = 128 + (2 * strands if flags & 1 else 0)
    if len(data) < offset + 12 * points:
        return False
    values = struct.unpack_from("<%df" % (3 * points), data, offset)
    return all(math.isfinite(v) for v in values)


def all_finite(value):
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, list):
        return all(all_finite(v) for v in value)
    if isinstance(value, dict):
        return all(all_finite(v) for v in value.values())
    return True


# ---------------------------------------------------------------------------
# Variants


@dataclass
class Probe:
    label: str
    argv: Callable[["RunContext"], List[str]]
    accept: frozenset = ERROR
    check: Optional[Callable[["RunContext", RunResult], Optional[str]]] = None  # why an accepted exit is wrong
    protect_capture: bool = False  # the capture folder must not change (except calibration/)
    log_level: str = "error"       # "warning" where a warning could print a file's content
    timeout: Optional[float] = None  # seconds, at least --timeout (a stage that runs long)


@dataclass
class Variant:
    category: str
    name: str
    prepare: Callable[["RunContext"], None]
    probes: List[Probe]
    core: bool = False          # always part of --quick
    leak_strict: bool = False   # the input names a file: none of its lines may be printed
    mutated: bool = False       # a random mutation: an error and a success are both right
    guard_reads: bool = False   # reading a file in the run's outside/ folder is a silent success
    slow: bool = False          # runs a whole stage: left out of --quick unless core
    # Instead of a command: a case against the running console, (session) -> (outcome, reason, observed).
    attack: Optional[Callable[["ConsoleSession"], tuple]] = None


@dataclass
class RunContext:
    campaign: "Campaign"
    dir: str

    @property
    def cap(self):
        return os.path.join(self.dir, "cap")

    @property
    def out(self):
        return os.path.join(self.dir, "out")

    @property
    def outside(self):
        return os.path.join(self.dir, "outside")

    def path(self, *parts):
        return os.path.join(self.dir, *parts)


# ---------------------------------------------------------------------------
# Generic mutators (seeded)


HOSTILE_JSON_VALUES = [None, True, 0, -1, 2.5, -2.5, 1e308, -1e308, 4294967296, 2**63 - 1, 2**64 - 1, -2**63,
                       "", "x", "NaN", "../../etc/passwd", "a" * 1000, [], {}, [1, 2, 3], {"a": 1}]
BYTE_TOKENS = [b"NaN", b"-1", b"1e999", b"-0", b"99999999999999999999999", b'""', b"null", b"[", b"{", b"]",
               b"}", b",", b"\n", b'"\\u0000"', b"../../", b"\xff\xfe"]


def json_pointers(value, here=()):
    yield here
    if isinstance(value, dict):
        for key, child in value.items():
            yield from json_pointers(child, here + (key,))
    elif isinstance(value, list):
        for index, child in enumerate(value):
            yield from json_pointers(child, here + (index,))


def with_field(document, path, value):
    """A deep copy of `document` with the field at `path` set to `value` (DELETE removes it)."""
    doc = json.loads(json.dumps(document))
    parent = json_get(doc, path[:-1])
    if value is DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return doc


def json_get(value, pointer):
    for key in pointer:
        value = value[key]
    return value


def mutate_json(doc, rng):
    """One structural mutation: a hostile value, a removal, a grown array, one level deeper."""
    doc = json.loads(json.dumps(doc))
    pointers = list(json_pointers(doc))
    target = pointers[rng.randrange(len(pointers))]
    op = rng.randrange(4)
    if not target:
        return [doc] if op == 3 else doc
    parent, key = json_get(doc, target[:-1]), target[-1]
    if op == 0:
        parent[key] = rng.choice(HOSTILE_JSON_VALUES)
    elif op == 1:
        del parent[key]
    elif op == 2:
        node = parent[key]
        parent[key] = node + [node[0]] * 2000 if isinstance(node, list) and node else [node, node]
    else:
        parent[key] = [parent[key]]
    return doc


def mutate_bytes(data, rng):
    """One byte-level mutation: truncation, bit flips, a token, a cut, a repeat, digits grown to 9s."""
    data = bytearray(data)
    at = rng.randrange(len(data) + 1)
    op = rng.randrange(6)
    if op == 0:
        del data[at:]
    elif op == 1:
        for _ in range(1 + rng.randrange(8)):
            if data:
                data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    elif op == 2:
        data[at:at] = rng.choice(BYTE_TOKENS)
    elif op == 3:
        del data[at:at + rng.randrange(16)]
    elif op == 4:
        start = rng.randrange(len(data) + 1)
        data[at:at] = data[start:start + rng.randrange(64)]
    else:
        for i in range(at, min(len(data), at + 12)):
            if chr(data[i]).isdigit():
                data[i] = ord("9")
    return bytes(data)


def mutate_json_text(doc, rng):
    op = rng.randrange(3)
    if op == 0:
        return mutate_bytes(json.dumps(doc, indent=1).encode(), rng)
    if op == 1:
        return json.dumps(mutate_json(doc, rng), indent=1).encode()
    return mutate_bytes(json.dumps(mutate_json(doc, rng), indent=1).encode(), rng)


BINARY_COUNTS = [0, 1, 65535, 65536, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFE, 0xFFFFFFFF]


def mutate_binary(data, rng):
    """Byte mutations, a huge or empty count in one of the first eight words, or a NaN/inf float."""
    op = rng.randrange(3)
    if op == 0 or len(data) < 4:
        return mutate_bytes(data, rng)
    data = bytearray(data)
    if op == 1:
        word = rng.randrange(min(len(data) // 4, 8))
        struct.pack_into("<I", data, 4 * word, rng.choice(BINARY_COUNTS))
    else:
        struct.pack_into("<f", data, rng.randrange(len(data) - 3), rng.choice([float("nan"), float("inf")]))
    return bytes(data)


# ---------------------------------------------------------------------------
# Writing inputs


def write_bytes(path, data):
    with open(path, "wb") as f:
        f.write(data)


def write_text(path, text):
    write_bytes(path, text.encode("utf-8"))


def write_json(path, doc):
    write_text(path, json.dumps(doc, indent=1))


def replace_with(path, kind, target=None):
    """Replaces `path` by a folder, a FIFO, a symlink to `target`, or removes it."""
    if os.path.isdir(path) and not os.path.islink(path):
        shutil.rmtree(path)
    elif os.path.lexists(path):
        os.remove(path)
    if kind == "dir":
        os.makedirs(os.path.join(path, "inner"))
        write_text(os.path.join(path, "inner", "x"), "x")
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "symlink":
        os.symlink(target, path)
    elif kind != "missing":
        raise ValueError(kind)


def special_file(ctx, kind, name):
    """A path in the run folder that is a FIFO, a folder, or a symlink to a device/system file."""
    path = ctx.path(name)
    targets = {"dev_zero": "/dev/zero", "dev_urandom": "/dev/urandom", "dev_null": "/dev/null",
               "etc_passwd": "/etc/passwd", "secret": os.path.join(ctx.outside, "secret.txt")}
    if kind in targets:
        os.symlink(targets[kind], path)
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "dir":
        os.makedirs(os.path.join(path, "inner"))
    elif kind == "loop":
        os.symlink(path, path)
    elif kind == "empty":
        write_bytes(path, b"")
    elif kind != "missing":
        raise ValueError(kind)
    return path


SPECIAL_KINDS = ["dev_zero", "dev_urandom", "fifo", "dir", "empty", "etc_passwd", "missing"]


# ---------------------------------------------------------------------------
# Strand files


def synthetic_strands(count=40, points=20, seed=1):
    rng = random.Random(seed)
    strands = []
    for s in range(count):
        a = 2 * math.pi * s / count
        x0, y0, z0 = 90 * math.cos(a), 90 * math.sin(a), 330 + 60 * rng.random()
        strands.append([(x0 + 3 * math.sin(0.7 * k + s), y0 + 3 * math.cos(0.7 * k + s), z0 - 5 * k)
                        for k in range(points)])
    return strands


def encode_hair(strands):
    points = [p for s in strands for p in s]
    header = struct.pack("<4sIIIIff3f88s", b"HAIR", len(strands), len(points), 3, 0, 1.0, 0.0, 1.0, 1.0, 1.0,
                         b"hostile campaign")
    body = b"".join(struct.pack("<H", len(s) - 1) for s in strands)
    return header + body + b"".join(struct.pack("<3f", *p) for p in points)


def encode_data(strands):
    out = [struct.pack("<i", len(strands))]
    for s in strands:
        out.append(struct.pack("<i", len(s)))
        out.extend(struct.pack("<3f", *p) for p in s)
    return b"".join(out)


def ply_header(strands, ascii_body, vertex_count=None, extra=""):
    points = sum(len(s) for s in strands)
    edges = points - len(strands)
    return ("ply\nformat %s 1.0\n%selement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element strand %d\nproperty ushort nsegs\nelement edge %d\nproperty int vertex1\n"
            "property int vertex2\nend_header\n" % ("ascii" if ascii_body else "binary_little_endian", extra,
                                                    points if vertex_count is None else vertex_count,
                                                    len(strands), edges))


def ply_edges(strands):
    edges, first = [], 0
    for s in strands:
        edges.extend((first + k, first + k + 1) for k in range(len(s) - 1))
        first += len(s)
    return edges


def encode_ply(strands, ascii_body, coordinate=None, extra=""):
    """A strand PLY; `coordinate` (text) replaces the x of the first point."""
    header = ply_header(strands, ascii_body, extra=extra).encode()
    points = [p for s in strands for p in s]
    if ascii_body:
        lines = ["%.9g %.9g %.9g" % p for p in points]
        if coordinate is not None:
            lines[0] = "%s %.9g %.9g" % (coordinate, points[0][1], points[0][2])
        lines += [str(len(s) - 1) for s in strands] + ["%d %d" % e for e in ply_edges(strands)]
        return header + ("\n".join(lines) + "\n").encode()
    body = b"".join(struct.pack("<3f", *p) for p in points)
    body += b"".join(struct.pack("<H", len(s) - 1) for s in strands)
    body += b"".join(struct.pack("<ii", *e) for e in ply_edges(strands))
    return header + body


# ---------------------------------------------------------------------------
# The campaign


class Campaign:
    def __init__(self, args):
        self.args = args
        self.hairrig = os.path.abspath(args.hairrig)
        self.repo = os.getcwd()
        self.root = tempfile.mkdtemp(prefix="hairrig_hostile_")
        self.runs_dir = os.path.join(self.root, "runs")
        self.kept_dir = os.path.join(self.root, "kept")
        self.master = os.path.join(self.root, "recorded")
        self.global_outside = os.path.join(self.root, "outside")
        self.results = []
        self.controls = []
        self.run_counter = 0
        self.console = None           # the ConsoleSession of the console cases, once started
        self.atime_works = False      # reads outside can be seen (setup checks it)
        self.reconstructed = None     # the reconstructed copy for `eval`, or why it failed
        secret_rng = random.Random(args.seed)
        tag = "%08x" % secret_rng.getrandbits(32)
        self.secret_lines = ["HAIRRIG-SENTINEL-%02d-%s please do not print me" % (k, tag) for k in range(20)]
        try:
            with open("/etc/passwd", encoding="utf-8", errors="replace") as f:
                self.passwd_lines = [line.strip() for line in f if len(line.strip()) >= 10]
        except OSError:
            self.passwd_lines = []

    # ----- setup ----------------------------------------------------------

    def base_config_text(self):
        """tests/data/small_rig.yaml with absolute paths and a calibration section."""
        with open(os.path.join(self.repo, "tests/data/small_rig.yaml"), encoding="utf-8") as f:
            text = f.read()
        scene = os.path.join(self.repo, "tests/data/small_scene.yaml")
        if "scene: small_scene.yaml" not in text:
            raise RuntimeError("tests/data/small_rig.yaml no longer names small_scene.yaml")
        text = text.replace("scene: small_scene.yaml", "scene: " + scene)
        return text + ("calibration:\n  box: %s\n  box_height_mm: 600\n  box_yaw_deg: 10\n"
                       % os.path.join(self.repo, "etc/calib-box.yaml"))

    def hairrig_argv(self, args, log_level="error"):
        return [self.hairrig, "--log-level", log_level] + args

    def setup_step(self, what, args, timeout=300):
        result = run_command(self.hairrig_argv(args), timeout, self.repo)
        if result.code != 0:
            raise RuntimeError("%s failed (exit %s): %s" % (what, result.code, result.output[-2000:]))
        return result

    def setup(self):
        os.makedirs(self.runs_dir)
        os.makedirs(self.global_outside)
        self.atime_works = access_times_recorded(self.root)
        self.fill_outside(self.global_outside)
        self.base_config = os.path.join(self.root, "base_rig.yaml")
        write_text(self.base_config, self.base_config_text())
        self.setup_step("recording the capture", ["capture", "--config", self.base_config, "--out", self.master])
        manifest = load_json_file(os.path.join(self.master, "manifest.json"))
        self.genuine = {f["view"]: f["sha256"] for f in manifest["frames"]}
        self.planned_serials = {f["view"]: f["serial"] for f in manifest["frames"]}
        self.frame_files = {f["view"]: f["file"] for f in manifest["frames"]}
        self.frame_bytes = {f["view"]: f["bytes"] for f in manifest["frames"]}
        with open(os.path.join(self.master, "journal.jsonl"), encoding="utf-8") as f:
            self.journal_lines = f.read().splitlines()
        self.setup_priors()
        self.setup_strands()
        self.master_state = tree_state(self.master)

    def setup_priors(self):
        """Intrinsics files per camera from one calibration of a copy of the capture, which is
        kept (self.calibrated) for the stages after calibration."""
        calibrated = self.calibrated = os.path.join(self.root, "calibrated")
        shutil.copytree(self.master, calibrated, symlinks=True)
        self.setup_step("calibrating a copy", ["calibrate", calibrated])
        stored = self.calibration = load_json_file(os.path.join(calibrated, "calibration", "calibration.json"))
        self.priors = {}
        for camera in stored["cameras"]:
            self.priors[camera["name"]] = {
                "format": "hairrig-intrinsics", "version": 1, "serial": camera["serial"],
                "board": os.path.join(self.repo, "etc/charuco-board.yaml"),
                "intrinsics": camera["intrinsics"], "intrinsics_stddev": camera["intrinsics_stddev"],
                "rms_px": 0.2, "images_used": 20, "images": []}

    def setup_strands(self):
        self.strands = synthetic_strands()
        self.strand_files = {".hair": encode_hair(self.strands), ".data": encode_data(self.strands),
                             ".ply": encode_ply(self.strands, False), "ascii.ply": encode_ply(self.strands, True)}
        source = os.path.join(self.root, "strands.data")
        write_bytes(source, self.strand_files[".data"])
        model = os.path.join(self.root, "model.json")
        self.setup_step("fitting the model", ["fit", source, "--out", model, "--guides", "4", "--fixed-n", "6",
                                              "--target-error", "0"])
        self.model = load_json_file(model)

    def fill_outside(self, folder):
        """Files outside the capture that nothing may change or print."""
        os.makedirs(folder, exist_ok=True)
        write_text(os.path.join(folder, "secret.txt"), "\n".join(self.secret_lines) + "\n")
        write_text(os.path.join(folder, "secret.yaml"), "".join("key%d: %s\n" % (k, line)
                                                                for k, line in enumerate(self.secret_lines)))

    # ----- running variants -----------------------------------------------

    def new_context(self):
        self.run_counter += 1
        directory = os.path.join(self.runs_dir, "%04d" % self.run_counter)
        os.makedirs(os.path.join(directory, "out"))
        ctx = RunContext(self, directory)
        self.fill_outside(ctx.outside)
        return ctx

    def copy_capture(self, ctx):
        shutil.copytree(self.master, ctx.cap, symlinks=True)

    def leaked_lines(self, output):
        """How many lines of the secret file or of /etc/passwd the output shows."""
        secret = sum(1 for line in self.secret_lines if line in output)
        passwd = sum(1 for line in self.passwd_lines if line in output)
        return max(secret, passwd)

    def escapes(self, ctx, before):
        """Files changed or created where the command may not write."""
        after = self.write_guard_state(ctx, before["protect_capture"])
        problems = []
        for key in ("outside", "global_outside", "capture"):
            for path in tree_changes(before[key], after[key])[:3]:
                problems.append("%s/%s created or changed" % (key, path))
        for key in ("run_dir", "runs", "root"):
            for name in sorted(after[key] - before[key] - {"cap", "out"})[:3]:
                problems.append("%s created in %s" % (name, key))
        return problems

    def write_guard_state(self, ctx, protect_capture, guard_reads=False):
        state = {"protect_capture": protect_capture,
                 "outside": tree_state(ctx.outside),
                 "global_outside": tree_state(self.global_outside),
                 "capture": tree_state(ctx.cap, exclude=("calibration",)) if protect_capture else {},
                 "run_dir": listing(ctx.dir), "runs": listing(self.runs_dir), "root": listing(self.root)}
        state["baits"] = bait_reads(ctx.outside) if guard_reads and self.atime_works else {}  # after hashing
        return state

    def run_variant(self, variant):
        if variant.attack:
            self.run_attack(variant)
            return
        for probe in variant.probes:
            ctx = self.new_context()
            try:
                variant.prepare(ctx)
            except Exception as e:  # a bug of the campaign, not of hairrig
                self.record(variant, probe, [], None, "other", "campaign could not prepare the input: %r" % e)
                shutil.rmtree(ctx.dir, ignore_errors=True)
                continue
            argv = self.hairrig_argv(probe.argv(ctx), probe.log_level)
            before = self.write_guard_state(ctx, probe.protect_capture, variant.guard_reads)
            result = run_command(argv, max(self.args.timeout, probe.timeout or 0), self.repo)
            outcome, reason = self.classify(variant, probe, ctx, result, before)
            self.record(variant, probe, argv, result, outcome, reason)
            self.finish_run(ctx, outcome)

    def classify(self, variant, probe, ctx, result, before):
        out = result.output
        read = [os.path.relpath(p, ctx.dir) for p in baits_read(before["baits"])]  # before hashing them
        if result.hung:
            return "hang", "no exit after %.0f s" % result.seconds
        if result.code < 0 or result.code >= 128 or "terminate called" in out or "AddressSanitizer" in out \
                or "runtime error:" in out:
            return "crash", "signal %d" % -result.code if result.code < 0 else "exit %d" % result.code
        escaped = self.escapes(ctx, before)
        if escaped:
            return "silent", "wrote outside: " + "; ".join(escaped)
        if read:
            return "silent", "read outside: " + "; ".join(read[:3])
        leaked = self.leaked_lines(out)
        if leaked >= (1 if variant.leak_strict else 3):
            return "other", "prints %d line(s) of a file the input names" % leaked
        if result.code in probe.accept:
            problem = probe.check(ctx, result) if probe.check else None
            return ("silent", problem) if problem else ("handled", "")
        if result.code == 0:
            return "silent", "exit 0 where an error was due"
        if "internal error" in out:
            return "other", "an exception reached main"
        message = out.split("hairrig: error: ", 1)[1].strip() if "hairrig: error: " in out else ""
        if result.code == 1 and message:
            return "clean", ""
        if not message and 100 <= result.code < 128:
            return "other", "refused by the argument parser (exit %d), not as 'hairrig: error:'" % result.code
        return "other", "exit %d%s" % (result.code, "" if message else " without 'hairrig: error:'")

    def record(self, variant, probe, argv, result, outcome, reason):
        self.results.append({
            "category": variant.category, "variant": variant.name, "probe": probe.label,
            "command": " ".join(argv), "exit": None if result is None else result.code,
            "seconds": 0.0 if result is None else round(result.seconds, 3), "outcome": outcome, "reason": reason,
            "first_line": "" if result is None else first_line(result.output),
            "expected_success": probe.accept == SUCCESS and not variant.mutated})
        if result is not None and outcome in NOT_CLEAN:
            self.results[-1]["output_tail"] = result.output[-3000:]
        if self.args.verbose:
            print("  %-7s %-18s %-44s %-8s %s" % (outcome, variant.category, variant.name[:44], probe.label,
                                                 reason[:60]), flush=True)

    def finish_run(self, ctx, outcome):
        if self.args.keep and outcome in NOT_CLEAN:
            os.makedirs(self.kept_dir, exist_ok=True)
            kept = os.path.join(self.kept_dir, os.path.basename(ctx.dir))
            os.rename(ctx.dir, kept)
            self.results[-1]["kept"] = kept
        else:
            shutil.rmtree(ctx.dir, ignore_errors=True)

    # ----- later stages and the console -----------------------------------

    def reconstructed_copy(self):
        """A copy of the calibrated capture with the points of STAGE_VIEWS reconstructed, made on
        first use (for `eval reconstruction`); RuntimeError saying why it could not be made."""
        if self.reconstructed is None:
            path = os.path.join(self.root, "reconstructed")
            try:
                shutil.copytree(self.calibrated, path, symlinks=True)
                self.setup_step("reconstructing a copy", ["reconstruct", path] + CAPTURE_POINTS, timeout=900)
                self.reconstructed = path
            except (RuntimeError, OSError) as e:
                self.reconstructed = e
        if isinstance(self.reconstructed, Exception):
            raise RuntimeError("no reconstructed copy: %s" % self.reconstructed)
        return self.reconstructed

    def console_session(self):
        """The console, started on first use (after a crash or a hang, after_case starts it again;
        one that ended between cases is left ended, so the next case reports it)."""
        if self.console is None:
            self.console = ConsoleSession(self)
        if self.console.proc is None:
            self.console.start()
        return self.console

    def stop_console(self):
        if self.console is not None:
            self.console.stop()

    def run_attack(self, variant):
        """One console case, then the console's liveness (ConsoleSession.after_case)."""
        probe = variant.probes[0]
        start = time.monotonic()
        try:
            session = self.console_session()
        except (RuntimeError, OSError) as e:
            self.record(variant, probe, [], None, "other", "the console did not start: %s" % e)
            return
        try:
            outcome, reason, observed = variant.attack(session)
        except Exception as e:  # a bug of the campaign, not of hairrig
            outcome, reason, observed = "other", "campaign could not run the case: %r" % e, ""
        outcome, reason = session.after_case(outcome, reason)
        result = RunResult(None, observed, outcome == "hang", time.monotonic() - start)
        self.record(variant, probe, session.argv(variant.name), result, outcome, reason)

    # ----- checks for accepted outcomes -----------------------------------

    def check_capture(self, ctx, _result):
        return dataset_problem(ctx.cap, self.genuine, self.planned_serials)

    def check_fresh_capture(self, ctx, _result):
        manifest = load_json_file(os.path.join(ctx.cap, "manifest.json")) or {}
        serials = {f.get("view"): f.get("serial") for f in manifest.get("frames", []) if isinstance(f, dict)}
        if not serials:
            return "capture reported success without frames"
        return dataset_problem(ctx.cap, {}, serials)

    def check_replay(self, ctx, result):
        out = os.path.join(ctx.out, "replay")
        if not os.path.exists(out):
            return "replay exit %d without an output folder" % result.code if result.code == 0 else None
        return replay_problem(out, self.genuine, self.planned_serials, result.code == 0)


def parse_last_json(output):
    for line in reversed(output.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                return None
    return None


# ---------------------------------------------------------------------------
# Probes shared by the capture categories


def check_stopped_at_folder(name):
    """A run that stopped at a folder standing where it writes `name`: the folder kept, the file named."""
    def check(ctx, result):
        if not os.path.isdir(cap_path(ctx, name)):
            return "the folder in %s's place was removed" % name
        if name not in result.output:
            return "the stop does not name %s" % name
        return None
    return check


def resume_probe(c, accept=ERROR):
    return Probe("resume", lambda ctx: ["capture", "--resume", "--out", ctx.cap], accept, c.check_capture)


def replay_probe(c, accept=ERROR):
    return Probe("replay", lambda ctx: ["replay", ctx.cap, "--out", os.path.join(ctx.out, "replay")], accept,
                 c.check_replay, protect_capture=True)


def calibrate_probe(c, accept=ERROR, priors=(), damaged=False):
    """calibrate --json; with `damaged`, a "good" verdict is a silent success."""
    def argv(ctx):
        extra = []
        for name in priors:
            extra += ["--intrinsics", ctx.path(name + ".json")]
        return ["calibrate", ctx.cap, "--json"] + extra

    def check(ctx, result):
        summary = parse_last_json(result.output)
        if not isinstance(summary, dict):
            return "calibrate succeeded without a JSON summary"
        if damaged and summary.get("verdict") == "good":
            return "verdict 'good' on damaged input"
        return None
    return Probe("calibrate", argv, accept, check, protect_capture=True)


# ---------------------------------------------------------------------------
# Category: journal frame records


def frame_record_lines(c):
    """{view: index of its frame_stored line}; views are drawn by number, as the lines' order varies."""
    lines = {}
    for i, line in enumerate(c.journal_lines):
        record = json.loads(line)
        if record.get("event") == "frame_stored":
            lines[record["view"]] = i
    return lines


def edit_journal(ctx, edit):
    """Copies the capture and applies edit(lines) -> lines to its journal."""
    c = ctx.campaign
    c.copy_capture(ctx)
    lines = edit(list(c.journal_lines), ctx)
    with open(os.path.join(ctx.cap, "journal.jsonl"), "wb") as f:
        f.write(b"".join((line if isinstance(line, bytes) else line.encode("utf-8")) + b"\n" for line in lines))


def set_field(index, key, value):
    """An edit that sets (or with value DELETE removes) one field of the record at `index`."""
    def edit(lines, ctx):
        record = json.loads(lines[index])
        v = value(ctx, record) if callable(value) else value
        if v is DELETE:
            record.pop(key, None)
        else:
            record[key] = v
        lines[index] = json.dumps(record, separators=(",", ":"))
        return lines
    return edit


class _Delete:
    def __repr__(self):
        return "deleted"


DELETE = _Delete()

INDEX_BAD = [None, True, "3", -1, 2.5, 1e308, 2**40, 100000, [], {}, -2**63, DELETE]
STRING_BAD = [None, 7, [], {}, True, DELETE]
NUMBER_BAD = [None, "x", [], True, {}, DELETE]
REQUIRED_FIELDS = {
    "view": INDEX_BAD, "stop": INDEX_BAD,
    "serial": STRING_BAD + ["", "SIM-CAM-OTHER", "../../outside"],
    "file": STRING_BAD + ["", "../../outside/victim.png", "frames/../../outside/victim.png", "/etc/passwd",
                          "frames/000_SIM-CAM-UPPER.png/.", "frames//x.png"],
    "bytes": [None, "x", -1, 2.5, 1e308, 2**64, [], True, DELETE],
    "sha256": STRING_BAD + ["", "z" * 64, "0" * 63, "0" * 65],
    "angle_commanded_deg": NUMBER_BAD, "angle_measured_deg": NUMBER_BAD,
    "seq": [None, "x", -1, 2.5, []],
}
OPTIONAL_FIELDS = {
    "camera": [7, []], "width_px": [-1, "x", 2.5, 2**40], "height_px": [-1, "x"], "pixel_format": [7],
    "exposure_s": [-1, "x"], "gain_db": ["x", []], "trigger_time_ns": ["x", 2.5], "received_time_ns": ["x"],
}


def value_name(value):
    text = repr(value)
    return text if len(text) <= 30 else text[:27] + "..."


def journal_variants(c, rng, repeats):
    records = frame_record_lines(c)
    variants = []

    def add(name, edit_of_index, resume_accept, replay_accept, core=False, index=None):
        for k in range(repeats if index is None else 1):
            i = records[rng.randrange(len(records))] if index is None else index  # views are 0..N-1
            view = json.loads(c.journal_lines[i]).get("view")
            edit = edit_of_index(i)
            variants.append(Variant("journal records", "%s @view %s" % (name, view),
                                    lambda ctx, edit=edit: edit_journal(ctx, edit),
                                    [resume_probe(c, resume_accept), replay_probe(c, replay_accept)], core))

    for key, values in REQUIRED_FIELDS.items():
        for value in values:
            add("%s=%s" % (key, value_name(value)), lambda i, key=key, value=value: set_field(i, key, value),
                ERROR, ERROR, core=(key in ("sha256", "file", "view", "bytes", "serial") and value is DELETE))
    for key, values in OPTIONAL_FIELDS.items():
        for value in values:
            add("%s=%s" % (key, value_name(value)), lambda i, key=key, value=value: set_field(i, key, value),
                ERROR, ERROR)
        add("%s deleted" % key, lambda i, key=key: set_field(i, key, DELETE), SUCCESS, SUCCESS)
    add("file=victim outside (absolute, its SHA-256)",
        lambda i: lambda lines, ctx: victim_record(lines, ctx, i, absolute=True), ERROR, ERROR, core=True)
    add("file=../outside/victim.png (its SHA-256)",
        lambda i: lambda lines, ctx: victim_record(lines, ctx, i, absolute=False), ERROR, ERROR)
    # Well-formed but wrong: the frame no longer verifies; resume re-shoots it, replay leaves it out.
    add("bytes=actual+1", lambda i: set_field(i, "bytes", lambda ctx, r: r["bytes"] + 1), SUCCESS, INCOMPLETE)
    add("sha256=another view's", lambda i: set_field(i, "sha256", lambda ctx, r: other_sha(c, r)), SUCCESS,
        INCOMPLETE)
    add("sha256=0*64", lambda i: set_field(i, "sha256", "0" * 64), SUCCESS, INCOMPLETE)
    add("view=another view (file kept)", lambda i: set_field(i, "view", lambda ctx, r: (r["view"] + 2) % 38),
        ERROR, ERROR, core=True)
    add("stop=another stop", lambda i: set_field(i, "stop", lambda ctx, r: (r["stop"] + 1) % 19), SUCCESS, EITHER)
    add("angle_measured_deg=1e308", lambda i: set_field(i, "angle_measured_deg", 1e308), SUCCESS, EITHER)
    add("extra field", lambda i: set_field(i, "evil", "../../outside"), SUCCESS, SUCCESS)
    add("event=7", lambda i: set_field(i, "event", 7), EITHER, EITHER)
    add("event unknown", lambda i: set_field(i, "event", "frame_stored "), SUCCESS, EITHER)
    add("sha256 of 5 MB", lambda i: set_field(i, "sha256", "a" * (5 << 20)), ERROR, ERROR)
    add("view nested 10000 deep", lambda i: lambda lines, ctx: nested_view(lines, i), ERROR, ERROR)
    add("record is []", lambda i: replace_line(i, "[]"), ERROR, ERROR)
    add("record is a string", lambda i: replace_line(i, '"frame_stored"'), ERROR, ERROR)
    add("record is null", lambda i: replace_line(i, "null"), ERROR, ERROR)
    add("record cut in half", lambda i: lambda lines, ctx: cut_line(lines, i), ERROR, ERROR, core=True)
    add("record is binary garbage", lambda i: replace_line(i, bytes(random.Random(i).getrandbits(8)
                                                                     for _ in range(300))), ERROR, ERROR)
    add("NUL byte in record", lambda i: lambda lines, ctx: insert_bytes(lines, i, b"\x00"), ERROR, ERROR)
    add("duplicate record", lambda i: lambda lines, ctx: lines[:i + 1] + [lines[i]] + lines[i + 1:], SUCCESS,
        SUCCESS)
    add("duplicate record for the other camera's view", lambda i: lambda lines, ctx: retarget(lines, ctx, i, False),
        SUCCESS, EITHER, core=True)
    add("duplicate record for the other camera's view with the frame copied",
        lambda i: lambda lines, ctx: retarget(lines, ctx, i, True), SUCCESS, EITHER, core=True)
    add("seq=previous record's", lambda i: set_field(i, "seq", lambda ctx, r: r["seq"] - 1), EITHER, EITHER)
    last = len(c.journal_lines) - 1
    add("last record torn", lambda i: lambda lines, ctx: cut_line(lines, i), SUCCESS, SUCCESS, index=last)
    add("empty line in the middle", lambda i: lambda lines, ctx: lines[:i] + [""] + lines[i:], EITHER, EITHER)
    add("CRLF line ends", lambda i: lambda lines, ctx: [line + "\r" for line in lines], EITHER, EITHER)
    add_planned_variants(c, add)
    return variants


def add_planned_variants(c, add):
    planned = [i for i, line in enumerate(c.journal_lines) if '"event":"view_planned"' in line]
    position = next(i for i, line in enumerate(c.journal_lines) if '"event":"position_reached"' in line)
    i = planned[len(planned) // 2]
    add("view_planned angle_deg+10 (plan changed)", lambda k: set_field(k, "angle_deg",
                                                                        lambda ctx, r: r["angle_deg"] + 10),
        ERROR, EITHER, index=i)
    for key, value in [("view", "x"), ("view", -1), ("serial", 7), ("camera", 7), ("lights", {"top": 2}),
                       ("lights", "x"), ("angle_deg", None)]:
        add("view_planned %s=%s" % (key, value_name(value)), lambda k, key=key, value=value: set_field(k, key, value),
            ERROR, ERROR, index=i)
    add("view_planned removed (plan changed)", lambda k: lambda lines, ctx: lines[:k] + lines[k + 1:], ERROR,
        EITHER, index=i)
    add("position_reached measured_deg='x'", lambda k: set_field(k, "measured_deg", "x"), EITHER, EITHER,
        index=position)


def replace_line(index, text):
    def edit(lines, ctx):
        lines[index] = text
        return lines
    return edit


def cut_line(lines, index):
    lines[index] = lines[index][:len(lines[index]) // 2]
    return lines


def insert_bytes(lines, index, data):
    line = lines[index].encode("utf-8")
    lines[index] = line[:len(line) // 2] + data + line[len(line) // 2:]
    return lines


def nested_view(lines, index):
    record = json.loads(lines[index])
    record["view"] = "@@"
    lines[index] = json.dumps(record, separators=(",", ":")).replace('"@@"', "[" * 10000 + "]" * 10000)
    return lines


def other_sha(c, record):
    return c.genuine[(record["view"] + 1) % len(c.genuine)]


def victim_record(lines, ctx, index, absolute):
    """A record naming a file outside the capture, with that file's size and SHA-256."""
    record = json.loads(lines[index])
    victim = os.path.join(ctx.outside, "victim.png")
    shutil.copyfile(os.path.join(ctx.cap, record["file"]), victim)
    record["file"] = victim if absolute else "../outside/victim.png"
    lines[index] = json.dumps(record, separators=(",", ":"))
    return lines


def retarget(lines, ctx, index, copy_frame):
    """Appends a copy of a frame record claiming the other camera's view at the same stop."""
    c = ctx.campaign
    record = json.loads(lines[index])
    target = record["view"] ^ 1
    target_record = json.loads(lines[next(i for i, line in enumerate(lines) if '"frame_stored"' in line
                                          and json.loads(line)["view"] == target)])
    copy = dict(record, view=target, stop=target // 2, file=c.frame_files[target], seq=record["seq"] + 1000,
                serial=target_record["serial"], camera=target_record["camera"])
    if copy_frame:
        shutil.copyfile(os.path.join(ctx.cap, record["file"]), os.path.join(ctx.cap, c.frame_files[target]))
    position = next(i for i in range(len(lines) - 1, -1, -1) if '"frame_stored"' in lines[i])
    return lines[:position + 1] + [json.dumps(copy, separators=(",", ":"))] + lines[position + 1:]


# ---------------------------------------------------------------------------
# Category: dataset files


def on_copy(edit):
    """prepare(): a copy of the capture, then edit(ctx)."""
    def prepare(ctx):
        ctx.campaign.copy_capture(ctx)
        edit(ctx)
    return prepare


def cap_path(ctx, name):
    return os.path.join(ctx.cap, name)


def rewrite_json(name, change):
    def edit(ctx):
        doc = load_json_file(cap_path(ctx, name))
        write_bytes(cap_path(ctx, name), change(doc, ctx))
    return edit


def json_bytes(doc):
    return json.dumps(doc, indent=1).encode()


def truncate_file(name, fraction=0.5):
    def edit(ctx):
        path = cap_path(ctx, name)
        os.truncate(path, int(os.path.getsize(path) * fraction))
    return edit


def special_in_capture(name, kind):
    def edit(ctx):
        targets = {"dev_zero": "/dev/zero", "dev_urandom": "/dev/urandom", "etc_passwd": "/etc/passwd",
                   "secret": os.path.join(ctx.outside, "secret.txt")}
        if kind in targets:
            replace_with(cap_path(ctx, name), "symlink", targets[kind])
        else:
            replace_with(cap_path(ctx, name), kind)
    return edit


def dataset_variants(c, rng, random_count):
    variants = []
    resume_replay = lambda resume, replay: [resume_probe(c, resume), replay_probe(c, replay)]

    def add(name, edit, probes, core=False, strict=False):
        variants.append(Variant("dataset files", name, on_copy(edit), probes, core, strict))

    # capture.json
    cj = "capture.json"
    for kind in ["dir", "missing", "fifo", "dev_zero", "secret"]:
        add("capture.json is %s" % kind, special_in_capture(cj, kind), resume_replay(ERROR, ERROR),
            core=kind in ("dir", "fifo"), strict=kind == "secret")
    add("capture.json empty", lambda ctx: write_bytes(cap_path(ctx, cj), b""), resume_replay(ERROR, ERROR))
    add("capture.json truncated", truncate_file(cj), resume_replay(ERROR, ERROR))
    add("capture.json is []", lambda ctx: write_bytes(cap_path(ctx, cj), b"[]"), resume_replay(ERROR, ERROR))
    for key, value in [("config_dir", 5), ("format", "x"), ("version", 2), ("format", None), ("subject", [])]:
        add("capture.json %s=%s" % (key, value_name(value)),
            rewrite_json(cj, lambda d, ctx, key=key, value=value: json_bytes(dict(d, **{key: value}))),
            resume_replay(ERROR, ERROR), core=key == "config_dir")
    for k in range(random_count):
        text = mutate_json_text(load_json_file(os.path.join(c.master, cj)), rng)
        add("capture.json mutation %d" % k, lambda ctx, t=text: write_bytes(cap_path(ctx, cj), t),
            resume_replay(SUCCESS, SUCCESS))
        variants[-1].mutated = True
    # manifest.json: derived state; resume and replay may rebuild it, calibrate reads it. A folder in
    # its place is never removed: resume stops there (exit 3), naming the file.
    mj = "manifest.json"
    manifest_probes = lambda resume=None: [resume or resume_probe(c, SUCCESS), replay_probe(c, SUCCESS),
                                           calibrate_probe(c, ERROR)]
    for kind in ["dir", "missing", "fifo", "dev_zero"]:
        resume = (Probe("resume", lambda ctx: ["capture", "--resume", "--out", ctx.cap], INCOMPLETE,
                        check_stopped_at_folder(mj)) if kind == "dir" else None)
        add("manifest.json is %s" % kind, special_in_capture(mj, kind), manifest_probes(resume),
            core=kind == "dir")
    add("manifest.json truncated", truncate_file(mj), manifest_probes())
    add("manifest.json frames='x'", rewrite_json(mj, lambda d, ctx: json_bytes(dict(d, frames="x"))),
        manifest_probes())
    add("manifest.json frames grown 2000-fold",
        rewrite_json(mj, lambda d, ctx: json_bytes(dict(d, frames=d["frames"] * 2000))), manifest_probes())
    add("manifest.json frame 0 names ../outside/secret.txt",
        rewrite_json(mj, lambda d, ctx: json_bytes(frame0(d, file="../outside/secret.txt"))), manifest_probes(),
        strict=True)
    add("manifest.json frame 0 SHA-256 changed",
        rewrite_json(mj, lambda d, ctx: json_bytes(frame0(d, sha256="0" * 64))),
        [resume_probe(c, SUCCESS), replay_probe(c, SUCCESS), calibrate_probe(c, EITHER, damaged=True)])
    add("manifest.json symlink to a copy outside", symlink_outside(mj),
        [resume_probe(c, SUCCESS), replay_probe(c, SUCCESS), calibrate_probe(c, SUCCESS)])
    for k in range(random_count):
        text = mutate_json_text(load_json_file(os.path.join(c.master, mj)), rng)
        add("manifest.json mutation %d" % k, lambda ctx, t=text: write_bytes(cap_path(ctx, mj), t),
            [resume_probe(c, SUCCESS), replay_probe(c, SUCCESS), calibrate_probe(c, EITHER, damaged=True)])
        variants[-1].mutated = True
    # Temporaries of interrupted writes, frames/ and frame files.
    for name in ["frames/000_SIM-CAM-UPPER.png.tmp.1", "manifest.json.tmp.7", "journal.jsonl.tmp.2",
                 "frames/zz.tmp.3"]:
        add("non-empty folder %s" % name, lambda ctx, n=name: make_full_dir(cap_path(ctx, n)),
            resume_replay(SUCCESS, SUCCESS), core=name.startswith("frames/000"))
    add("frames/ missing", special_in_capture("frames", "missing"), resume_replay(SUCCESS, INCOMPLETE), core=True)
    add("frames/ empty", lambda ctx: (shutil.rmtree(cap_path(ctx, "frames")), os.mkdir(cap_path(ctx, "frames"))),
        resume_replay(SUCCESS, INCOMPLETE))
    add("frames is a file", lambda ctx: (shutil.rmtree(cap_path(ctx, "frames")),
                                         write_bytes(cap_path(ctx, "frames"), b"x")),
        resume_replay(SUCCESS, INCOMPLETE))
    add("foreign files in frames/", lambda ctx: (write_bytes(cap_path(ctx, "frames/999_EVIL.png"), b"x"),
                                                 write_bytes(cap_path(ctx, "frames/evil.txt"), b"x")),
        resume_replay(SUCCESS, SUCCESS))
    frame = c.frame_files[5]
    for name, edit in frame_damage(c, frame):
        add("frame 5 %s" % name, edit, resume_replay(SUCCESS, INCOMPLETE), core=name == "truncated to half")
    # journal.jsonl as a whole
    jl = "journal.jsonl"
    for kind in ["missing", "dir", "fifo", "dev_zero"]:
        add("journal.jsonl is %s" % kind, special_in_capture(jl, kind), resume_replay(ERROR, ERROR),
            core=kind == "fifo")
    # An empty journal or one record cut short is what a kill right after creation leaves: resume starts over.
    add("journal.jsonl empty", lambda ctx: write_bytes(cap_path(ctx, jl), b""), resume_replay(SUCCESS, ERROR))
    add("journal.jsonl one record of binary garbage, cut short",
        lambda ctx: write_bytes(cap_path(ctx, jl), garbage(4096, newlines=False)), resume_replay(SUCCESS, ERROR))
    add("journal.jsonl lines of binary garbage",
        lambda ctx: write_bytes(cap_path(ctx, jl), garbage(4096, newlines=True)), resume_replay(ERROR, ERROR))
    add("journal.jsonl only its first record", truncate_lines(jl, 1), resume_replay(SUCCESS, INCOMPLETE))
    for k in range(3):
        fraction = rng.uniform(0.5, 0.97)
        add("journal.jsonl cut at %.0f%% of its bytes" % (100 * fraction), truncate_file(jl, fraction),
            resume_replay(SUCCESS, EITHER))
    # The rig.yaml snapshot
    ry = "rig.yaml"
    add("rig.yaml missing", special_in_capture(ry, "missing"), resume_replay(ERROR, EITHER))
    add("rig.yaml is dir", special_in_capture(ry, "dir"), resume_replay(ERROR, EITHER))
    add("rig.yaml is /dev/zero", special_in_capture(ry, "dev_zero"), resume_replay(ERROR, EITHER))
    add("rig.yaml plan changed (stops: 10)", append_text(ry, "plan: {stops: 10}\n"), resume_replay(ERROR, EITHER),
        core=True)
    add("rig.yaml unknown key", append_text(ry, "retrys: {camera: 1}\n"), resume_replay(ERROR, EITHER))
    return variants


def garbage(size, newlines):
    """Seeded random bytes; with `newlines`, a line break every 100 bytes, else none."""
    data = bytes(b if b != 0x0A else 0x0B for b in random.Random(3).randbytes(size))
    if newlines:
        data = b"".join(data[k:k + 99] + b"\n" for k in range(0, size, 99))
    return data


def frame0(manifest, **changes):
    manifest["frames"][0].update(changes)
    return manifest


def symlink_outside(name):
    def edit(ctx):
        outside_copy = os.path.join(ctx.outside, name)
        shutil.copyfile(cap_path(ctx, name), outside_copy)
        replace_with(cap_path(ctx, name), "symlink", outside_copy)
    return edit


def make_full_dir(path):
    os.makedirs(path)
    write_bytes(os.path.join(path, "partial"), b"x" * 1000)


def truncate_lines(name, count):
    def edit(ctx):
        with open(cap_path(ctx, name), encoding="utf-8") as f:
            lines = f.read().splitlines()[:count]
        write_text(cap_path(ctx, name), "\n".join(lines) + "\n")
    return edit


def append_text(name, text):
    def edit(ctx):
        with open(cap_path(ctx, name), "a", encoding="utf-8") as f:
            f.write(text)
    return edit


def frame_damage(c, frame):
    """(name, edit) pairs that damage one frame file of the copy."""
    other = c.frame_files[7]

    def flip(ctx):
        path = cap_path(ctx, frame)
        with open(path, "r+b") as f:
            f.seek(os.path.getsize(path) // 2)
            byte = f.read(1)
            f.seek(-1, 1)
            f.write(bytes([byte[0] ^ 0x10]))
    return [
        ("truncated to half", truncate_file(frame)),
        ("empty", truncate_file(frame, 0)),
        ("one bit flipped", flip),
        ("replaced by view 7's frame", lambda ctx: shutil.copyfile(cap_path(ctx, other), cap_path(ctx, frame))),
        ("deleted", special_in_capture(frame, "missing")),
        ("is a FIFO", special_in_capture(frame, "fifo")),
        ("is a folder", special_in_capture(frame, "dir")),
        ("symlinked to /dev/zero", special_in_capture(frame, "dev_zero")),
        ("symlinked to /dev/urandom", special_in_capture(frame, "dev_urandom")),
    ]


# ---------------------------------------------------------------------------
# Category: rig config files


def config_probes(c, devices_accept, capture_accept):
    return [Probe("devices", lambda ctx: ["devices", "--config", ctx.path("rig.yaml")], devices_accept),
            Probe("capture", lambda ctx: ["capture", "--config", ctx.path("rig.yaml"), "--out", ctx.cap],
                  capture_accept, c.check_fresh_capture)]


def config_text_prepare(text_of):
    def prepare(ctx):
        data = text_of(ctx)
        write_bytes(ctx.path("rig.yaml"), data if isinstance(data, bytes) else data.encode("utf-8"))
    return prepare


def insert_after(text, anchor, addition):
    if anchor not in text:
        raise RuntimeError("base config lacks %r" % anchor)
    at = text.index(anchor) + len(anchor)
    return text[:at] + addition + text[at:]


def config_variants(c, rng, random_count, full):
    base = c.base_config_text()
    variants = []

    def add(name, text_of, devices_accept, capture_accept, core=False, strict=False):
        prepare = config_text_prepare(text_of if callable(text_of) else (lambda ctx, t=text_of: t))
        variants.append(Variant("config files", name, prepare, config_probes(c, devices_accept, capture_accept),
                                core, strict))

    # Not YAML
    add("unclosed flow mapping", base.replace("backend: sim, serial: SIM-TT-0001}", "backend: sim"), ERROR, ERROR)
    add("tab indentation", base.replace("  time_scale", "\ttime_scale"), ERROR, ERROR)
    add("unterminated quote", base.replace("name: small simulated rig", 'name: "small'), ERROR, ERROR)
    add("unclosed sequence", base.replace("name: small simulated rig", "name: [a, b"), ERROR, ERROR)
    add("sequence item after a mapping", base + "- stray\n", ERROR, ERROR)
    add("alias to an unknown anchor", base.replace("min_free_mb: 10", "min_free_mb: *nowhere"), ERROR, ERROR)
    add("nesting 100000 deep", base + "deep: " + "[" * 100000 + "]" * 100000 + "\n", ERROR, ERROR)
    add("billion laughs aliases", base + laughs(), ERROR, ERROR, core=True)
    add("NUL byte", base.replace("small simulated rig", "small\x00rig"), EITHER, EITHER)
    add("invalid UTF-8", base.encode().replace(b"small simulated", b"small \xff\xfe"), EITHER, EITHER)
    for k in range(random_count):
        data = mutate_bytes(base.encode(), rng)
        add("byte mutation %d" % k, data, SUCCESS, SUCCESS)
        variants[-1].mutated = True
    # Unknown and duplicate keys, second documents: the document is refused by every command.
    for name, text in [
            ("unknown top-level key", base + "extra_key: 1\n"),
            ("unknown key in sim", insert_after(base, "sim:\n", "  extra: 1\n")),
            ("unknown key in a camera", base.replace("trigger_line: trig0}", "trigger_line: trig0, colour: red}", 1)),
            ("unknown key in devices", insert_after(base, "devices:\n", "  printers: []\n")),
            ("unknown key in retries", insert_after(base, "retries:\n", "  extra: 1\n")),
            ("unknown key in storage", insert_after(base, "storage:\n", "  extra: 1\n")),
            ("misspelt section 'retrys'", base.replace("retries:", "retrys:")),
            ("unknown key in calibration", base + "  extra: 1\n"),
            ("unknown key in plan", base + "plan:\n  stops: 19\n  colour: red\n"),
            ("duplicate top-level name", base + "name: second name\n"),
            ("duplicate sim section", base + "sim:\n  time_scale: 1\n"),
            ("duplicate key in a flow mapping", base.replace("{name: turntable,", "{name: turntable, name: tt,")),
            ("duplicate storage section", base + "storage:\n  min_free_mb: 1\n"),
            ("second document", base + "---\nname: second\n"),
            ("second empty document", base + "---\n"),
            ("second document after end marker", base + "...\n---\nextra: 1\n")]:
        add(name, text, ERROR, ERROR, core=name in ("duplicate sim section", "second document",
                                                   "unknown top-level key"))
    # Plan mistakes: `capture` must refuse them before shooting; `devices` checks the plan as capture reads it.
    plans = [("light-name typo 'botom'", "plan: {lights: {top: 1, botom: 1}}"),
             ("camera typo in the plan", "plan: {cameras: [uper]}"),
             ("light typo in a view", "plan:\n  views:\n    - {angle_deg: 0, camera: upper, lights: {tpo: 1}}"),
             ("the same view twice", "plan:\n  views:\n    - {angle_deg: 0, camera: upper}\n"
                                     "    - {angle_deg: 0, camera: upper}"),
             ("repeated angle", "plan: {angles_deg: [0, 0]}"), ("angle 1e12", "plan: {angles_deg: [1e12]}"),
             ("angle 1e308", "plan: {angles_deg: [1e308]}"), ("angle .nan", "plan: {angles_deg: [.nan]}"),
             ("angle .inf", "plan: {angles_deg: [.inf]}"), ("angle -1e12", "plan: {angles_deg: [-1e12]}"),
             ("stops -1", "plan: {stops: -1}"), ("stops 0", "plan: {stops: 0}"), ("stops 3601", "plan: {stops: 3601}"),
             ("stops 2.5", "plan: {stops: 2.5}"), ("stops 1e9", "plan: {stops: 1000000000}"),
             ("stops 'x'", "plan: {stops: x}"), ("exposure -1", "plan: {exposure_s: -1}"),
             ("exposure .nan", "plan: {exposure_s: .nan}"), ("speed 0", "plan: {speed_deg_s: 0}"),
             ("speed -30", "plan: {speed_deg_s: -30}"), ("pixel format rgb9", "plan: {pixel_format: rgb9}"),
             ("trigger pulse -1", "plan: {trigger_pulse_us: -1}"), ("light level 2", "plan: {lights: {top: 2}}"),
             ("light level .nan", "plan: {lights: {top: .nan}}"),
             ("retries frame_timeout_s -1", None), ("storage min_free_mb -1", None)]
    for name, plan in plans:
        if plan is None:
            text = base.replace("frame_timeout_s: 3", "frame_timeout_s: -1") if "frame" in name \
                else base.replace("min_free_mb: 10", "min_free_mb: -1")
        else:
            text = base + plan + "\n"
        add(name, text, ERROR, ERROR, core=name in ("light-name typo 'botom'", "angle 1e12"))
    if full:
        add("angles_deg with 5M entries", lambda ctx: base + "plan:\n  angles_deg: [" +
            ", ".join(["1"] * 5_000_000) + "]\n", SUCCESS, ERROR)
        add("50 MB of comments", lambda ctx: base + ("# " + "c" * 98 + "\n") * 500_000, EITHER, EITHER)
    # Devices and sim values: every command builds the devices from them.
    for name, text in [
            ("time_scale 0", base.replace("time_scale: 0.01", "time_scale: 0")),
            ("time_scale -1", base.replace("time_scale: 0.01", "time_scale: -1")),
            ("time_scale .nan", base.replace("time_scale: 0.01", "time_scale: .nan")),
            ("two cameras with one serial", base.replace("SIM-CAM-LOWER", "SIM-CAM-UPPER")),
            ("unknown trigger line", base.replace("trigger_line: trig0}", "trigger_line: nope}", 1)),
            ("unknown backend", base.replace("{name: turntable, backend: sim", "{name: turntable, backend: warp")),
            ("empty serial", base.replace("serial: SIM-TT-0001", "serial: ''")),
            ("unknown sim light", base.replace("light: top}", "light: middle}")),
            ("no devices section", base.replace("devices:", "devicez:"))]:
        add(name, text, ERROR, ERROR)
    # Files the config names, and the config file itself
    for kind, core in [("etc_passwd", True), ("dev_zero", True), ("dev_urandom", False), ("fifo", True),
                       ("dir", False), ("secret", False), ("missing", False)]:
        add("sim.scene is %s" % kind, lambda ctx, kind=kind: base.replace(
            os.path.join(c.repo, "tests/data/small_scene.yaml"), special_file(ctx, kind, "scene")), ERROR, ERROR,
            core=core, strict=True)
    for kind in SPECIAL_KINDS + ["dev_null", "secret", "loop"]:
        variants.append(Variant("config files", "--config is %s" % kind,
                                lambda ctx, kind=kind: special_file(ctx, kind, "rig.yaml"),
                                config_probes(c, ERROR, ERROR), kind in ("dev_zero", "fifo", "dev_urandom")))
    add("binary garbage", bytes(random.Random(5).getrandbits(8) for _ in range(4096)), ERROR, ERROR)
    add("a 10 MB name", base.replace("small simulated rig", "a" * (10 << 20)), EITHER, EITHER)
    return variants


def laughs():
    lines = ["lol0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for k in range(1, 10):
        lines.append("lol%d: &l%d [%s]" % (k, k, ", ".join(["*l%d" % (k - 1)] * 10)))
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------
# Category: calibration priors and inputs


def calibration_variants(c, rng, random_count):
    variants = []
    upper, lower = c.priors["upper"], c.priors["lower"]

    def add(name, upper_doc, accept, core=False, damaged=False, edit=None, strict=False):
        def prepare(ctx, upper_doc=upper_doc, edit=edit):
            c.copy_capture(ctx)
            if isinstance(upper_doc, (bytes, str)) and upper_doc in SPECIAL_KINDS + ["dev_null"]:
                special_file(ctx, upper_doc, "upper.json")
            else:
                write_bytes(ctx.path("upper.json"), upper_doc if isinstance(upper_doc, bytes)
                            else json_bytes(upper_doc))
            write_json(ctx.path("lower.json"), lower)
            if edit:
                edit(ctx)
        variants.append(Variant("calibration", name, prepare,
                                [calibrate_probe(c, accept, ("upper", "lower"), damaged)], core, strict))

    def changed(path, value):
        return with_field(upper, path, value)

    add("serial=7", changed(("serial",), 7), ERROR, core=True)
    add("serial=''", changed(("serial",), ""), ERROR)
    add("serial deleted", changed(("serial",), DELETE), ERROR)
    add("serial of a camera not in the capture", changed(("serial",), "SIM-CAM-NOPE"), ERROR)
    add("upper camera's file relabelled as the lower's", changed(("serial",), lower["serial"]), INCOMPLETE,
        core=True, damaged=True)
    for key, value in [("fx_px", "x"), ("fx_px", None), ("fx_px", -1), ("fx_px", 0), ("fx_px", 1e308),
                       ("cx_px", DELETE), ("k1", []), ("width_px", 600), ("height_px", -1)]:
        add("intrinsics.%s=%s" % (key, value_name(value)), changed(("intrinsics", key), value),
            INCOMPLETE, damaged=True)
    add("intrinsics is a list", changed(("intrinsics",), [1, 2, 3]), ERROR)
    add("fx_px=NaN token", json.dumps(upper).replace('"fx_px": ', '"fx_px": NaN, "x": ', 1).encode(), ERROR)
    for key, value in [("fx_px", -1), ("k1", -0.5), ("cx_px", "x"), ("fx_px", 1e308)]:
        add("intrinsics_stddev.%s=%s" % (key, value_name(value)), changed(("intrinsics_stddev", key), value),
            ERROR if value != 1e308 else SUCCESS, core=value == -1)
    add("intrinsics_stddev deleted", changed(("intrinsics_stddev",), DELETE), EITHER)
    add("format='x'", changed(("format",), "x"), ERROR)
    add("version=2", changed(("version",), 2), ERROR)
    add("rms_px changed (not used)", changed(("rms_px",), 5.0), SUCCESS)
    add("truncated", json_bytes(upper)[:200], ERROR)
    for kind in ["dev_zero", "fifo", "dir", "empty", "missing"]:
        add("prior file is %s" % kind, kind, ERROR, core=kind == "fifo")
    for k in range(random_count):
        add("prior mutation %d" % k, mutate_json_text(upper, rng), EITHER)
        variants[-1].mutated = True
    # Damaged capture: calibration must not call a damaged frame's view good.
    frame = c.frame_files[5]
    add("frame 5 truncated to half (its SHA-256 no longer matches)", upper, EITHER, core=True, damaged=True,
        edit=truncate_file(frame))
    add("frame 5 replaced by view 7's frame", upper, EITHER, damaged=True,
        edit=lambda ctx: shutil.copyfile(cap_path(ctx, c.frame_files[7]), cap_path(ctx, frame)))
    for kind, strict in [("etc_passwd", True), ("secret", True), ("dev_zero", False), ("fifo", False)]:
        add("rig.yaml calibration box is %s" % kind, upper, ERROR, strict=strict,
            edit=lambda ctx, kind=kind: box_file(ctx, kind))
    return variants


def box_file(ctx, kind):
    path = special_file(ctx, kind, "box.yaml")
    rig = cap_path(ctx, "rig.yaml")
    with open(rig, encoding="utf-8") as f:
        text = f.read()
    write_text(rig, text.replace(os.path.join(ctx.campaign.repo, "etc/calib-box.yaml"), path))


# ---------------------------------------------------------------------------
# Category: strand files


def fit_probe(c, accept, extension):
    def argv(ctx):
        return ["fit", ctx.path("in" + extension), "--out", os.path.join(ctx.out, "model.json"), "--guides", "4"]

    def check(ctx, _result):
        model = load_json_file(os.path.join(ctx.out, "model.json"))
        if not isinstance(model, dict) or not model.get("guides"):
            return "fit succeeded without a readable model"
        if not all_finite(model) or "null" in json.dumps(model.get("guides")):
            return "fit wrote a model with non-finite or null numbers"
        return None
    return Probe("fit", argv, accept, check)


def strand_variants(c, rng, random_count):
    variants = []

    def add(name, extension, data, accept, core=False, strict=False):
        def prepare(ctx, data=data):
            if isinstance(data, str):
                special_file(ctx, data, "in" + extension)
            else:
                write_bytes(ctx.path("in" + extension), data)
        variants.append(Variant("strand files", name, prepare, [fit_probe(c, accept, extension)], core, strict))

    strands = c.strands
    hair, data = c.strand_files[".hair"], c.strand_files[".data"]

    def hair_header(strand_count=None, point_count=None, flags=None, body=True):
        h = bytearray(hair if body else hair[:128])
        for offset, value in ((4, strand_count), (8, point_count), (12, flags)):
            if value is not None:
                struct.pack_into("<I", h, offset, value)
        return bytes(h)

    def hair_point(value):
        h = bytearray(hair)
        struct.pack_into("<f", h, 128 + 2 * len(strands) + 12 * 25, value)
        return bytes(h)

    def data_point(value):
        d = bytearray(data)
        struct.pack_into("<f", d, 4 + 4 + 12 * 3, value)
        return bytes(d)

    def data_count(offset, value):
        d = bytearray(data)
        struct.pack_into("<i", d, offset, value)
        return bytes(d)

    add(".hair header claims 2^32-1 strands", ".hair", hair_header(0xFFFFFFFF, 0xFFFFFFFF, 2, body=False), ERROR,
        core=True)
    add(".hair header claims 2^32-1 points", ".hair", hair_header(point_count=0xFFFFFFFF), ERROR)
    add(".hair segment counts off by one", ".hair", hair_header(point_count=len(strands) * 20 + 1), ERROR)
    add(".hair without points flag", ".hair", hair_header(flags=1), ERROR)
    add(".hair bad magic", ".hair", b"HAIX" + hair[4:], ERROR)
    add(".hair truncated inside the points", ".hair", hair[:len(hair) - 100], ERROR)
    for value, name in [(float("nan"), "NaN"), (float("inf"), "inf"), (3.4e38, "3.4e38"), (1e10, "1e10")]:
        add(".hair coordinate %s" % name, ".hair", hair_point(value), ERROR, core=name == "3.4e38")
        add(".data coordinate %s" % name, ".data", data_point(value), ERROR)
    add(".data strand count 2^31-1", ".data", data_count(0, 0x7FFFFFFF), ERROR, core=True)
    add(".data strand count -1", ".data", data_count(0, -1), ERROR)
    add(".data point count -1", ".data", data_count(4, -1), ERROR)
    add(".data point count 0", ".data", data_count(4, 0), ERROR)
    add(".data point count 2^31-1", ".data", data_count(4, 0x7FFFFFFF), ERROR)
    add(".data trailing bytes", ".data", data + b"\x00" * 7, ERROR)
    add(".data truncated", ".data", data[:len(data) // 2], ERROR)
    add(".data empty", ".data", b"", ERROR)
    add(".data one point per strand", ".data", encode_data([s[:1] for s in strands]), ERROR)
    ply_body = c.strand_files[".ply"][len(ply_header(strands, False)):]
    add(".ply element of 9e18 empty records", ".ply",
        ply_header(strands, False, extra="element junk 9000000000000000000\n").encode() + ply_body, ERROR,
        core=True)
    add(".ply vertex count 2^63", ".ply", ply_header(strands, False, vertex_count=2**63).encode() + ply_body, ERROR)
    add(".ply vertex count -1", ".ply", ply_header(strands, False, vertex_count=-1).encode() + ply_body, ERROR)
    add(".ply without end_header", ".ply", c.strand_files[".ply"].replace(b"end_header\n", b""), ERROR)
    add(".ply without strand element", ".ply", c.strand_files[".ply"].replace(b"element strand", b"element strant"),
        ERROR)
    add(".ply list property with a huge count", ".ply",
        ply_header(strands, False, extra="element face 1\nproperty list uint int idx\n").encode()
        + struct.pack("<I", 0xFFFFFFFF) + ply_body, ERROR)
    add(".ply big-endian body read as is", ".ply",
        c.strand_files[".ply"].replace(b"binary_little_endian", b"binary_big_endian"), ERROR)
    add(".ply truncated", ".ply", c.strand_files[".ply"][:-9], ERROR)
    for text in ["nan", "inf", "3.4e38", "1e39", "x", "99999999999999999999999999999"]:
        add(".ply ascii coordinate %s" % text, ".ply", encode_ply(strands, True, coordinate=text), ERROR,
            core=text == "nan")
    add(".ply 10 MB comment", ".ply", c.strand_files["ascii.ply"].replace(b"format ascii 1.0\n", b"format ascii 1.0\n"
                                                                        b"comment " + b"c" * (10 << 20) + b"\n"),
        EITHER)
    for extension in [".hair", ".data", ".ply"]:
        for kind in ["dev_zero", "dev_urandom", "fifo", "etc_passwd"]:
            add("%s file is %s" % (extension, kind), extension, kind, ERROR,
                core=kind in ("dev_zero", "fifo") and extension == ".hair", strict=kind == "etc_passwd")
    add(".txt extension", ".txt", data, ERROR)
    formats = [(".hair", hair), (".data", data), (".ply", c.strand_files[".ply"]), (".ply", c.strand_files["ascii.ply"])]
    for k in range(random_count):
        extension, base = formats[k % len(formats)]
        add("%s mutation %d" % (extension, k), extension, mutate_binary(base, rng), SUCCESS)
        variants[-1].mutated = True
    return variants


# ---------------------------------------------------------------------------
# Category: helix models


def simulate_probe(c, accept, log_level="error"):
    def argv(ctx):
        return ["simulate", ctx.path("model.json"), "--out", os.path.join(ctx.out, "sim"), "--seconds", "0.1",
                "--fps", "10", "--preview-every", "0", "--no-head"]

    def check(ctx, _result):
        sim = os.path.join(ctx.out, "sim")
        summary = load_json_file(os.path.join(sim, "summary.json"))
        if not isinstance(summary, dict) or not all_finite(summary):
            return "simulate succeeded without a finite summary.json"
        frames = os.path.join(sim, "frames")
        names = sorted(os.listdir(frames)) if os.path.isdir(frames) else []
        if not names:
            return "simulate succeeded without frames"
        for name in names:
            if name.endswith(".hair") and not hair_points_finite(os.path.join(frames, name)):
                return "simulate wrote non-finite points in frames/%s" % name
        return None
    return Probe("simulate", argv, accept, check, log_level=log_level)


def helix_variants(c, rng, random_count):
    variants = []
    model = c.model

    def add(name, doc, accept, core=False):
        def prepare(ctx, doc=doc):
            if isinstance(doc, str):
                special_file(ctx, doc, "model.json")
            else:
                write_bytes(ctx.path("model.json"), doc if isinstance(doc, bytes) else json_bytes(doc))
        variants.append(Variant("helix models", name, prepare, [simulate_probe(c, accept)], core))

    def changed(path, value):
        return with_field(model, path, value)

    element = ("guides", 0, "elements", 0)
    for path, values in [
            (("cluster_of_strand",), ["abc", {}]),
            (("cluster_of_strand", 0), [99, 2.5, "x"]),
            (("guides",), [[], "x", DELETE]),
            (("guides", 0, "strand"), [-2, 2**31, "x"]),
            (("guides", 0, "elements"), [[], DELETE]),
            (element + ("length_mm",), [-1, 0, 1e308, "x"]),
            (element + ("start_tangent",), [[0, 0, 0], [1, 0], "x"]),
            (element + ("darboux_per_mm",), ["x", [1e308, 0, 0]]),
            (element + ("start_mm",), [[1e308, 0, 0], []]),
            (("format",), ["x"]), (("version",), [2])]:
        for value in values:
            add("%s=%s" % (".".join(str(p) for p in path), value_name(value)), changed(path, value), ERROR,
                core=path == ("cluster_of_strand",) and value == "abc")
    # Optional fields: the clusters are recomputed, a source that cannot be read leaves the guides only.
    add("cluster_of_strand deleted", changed(("cluster_of_strand",), DELETE), SUCCESS)
    add("cluster_of_strand=[]", changed(("cluster_of_strand",), []), SUCCESS)
    for kind in ["dev_zero", "dev_urandom", "fifo", "dir", "etc_passwd", "secret", "missing"]:
        variants.append(Variant("helix models", "source strand file is %s" % kind,
                                lambda ctx, kind=kind: write_json(ctx.path("model.json"), dict(
                                    model, source=special_file(ctx, kind, "source.hair"))),
                                [simulate_probe(c, SUCCESS, "warning")], kind in ("fifo", "dev_zero"), True))
    add("length_mm=NaN token", json.dumps(model).replace('"length_mm": ', '"length_mm": NaN, "x": ', 1).encode(),
        ERROR)
    add("truncated", json_bytes(model)[:1000], ERROR)
    add("nested 10000 deep", json.dumps(dict(model, guides="@@")).replace('"@@"', "[" * 10000 + "]" * 10000)
        .encode(), ERROR)
    for kind in ["dev_zero", "fifo", "dir", "empty", "etc_passwd"]:
        add("model file is %s" % kind, kind, ERROR, core=kind == "dev_zero")
    for k in range(random_count):
        add("model mutation %d" % k, mutate_json_text(model, rng), SUCCESS)
        variants[-1].mutated = True
    return variants


# ---------------------------------------------------------------------------
# Category: path escapes


def escape_variants(c):
    variants = []
    rr = lambda resume, replay: [resume_probe(c, resume), replay_probe(c, replay)]

    def add(name, edit, probes, core=False, strict=False):
        variants.append(Variant("path escapes", name, on_copy(edit), probes, core, strict))

    frame = c.frame_files[0]
    add("journal.jsonl symlinked outside", moved_outside("journal.jsonl"), rr(ERROR, EITHER), core=True)
    add("frames/ symlinked outside, one frame missing",
        moved_outside("frames", lambda ctx: os.remove(os.path.join(ctx.outside, "frames_moved",
                                                                   os.path.basename(frame)))),
        rr(ERROR, EITHER), core=True)
    add("quarantine/ symlinked outside, a foreign frame file",
        lambda ctx: (os.makedirs(os.path.join(ctx.outside, "q")),
                     os.symlink(os.path.join(ctx.outside, "q"), cap_path(ctx, "quarantine")),
                     write_bytes(cap_path(ctx, "frames/999_EVIL.png"), b"x")), rr(ERROR, EITHER), core=True)
    add("ground_truth/ symlinked outside", moved_outside("ground_truth"), rr(ERROR, EITHER))
    add("frame symlinked to its genuine copy outside", frame_link_outside(frame), rr(SUCCESS, INCOMPLETE), core=True)
    add("frame hardlinked outside and damaged", frame_hardlink_outside(frame), rr(SUCCESS, INCOMPLETE))
    add("journal.jsonl symlinked to /etc/passwd", special_in_capture("journal.jsonl", "etc_passwd"),
        rr(ERROR, ERROR), strict=True)
    add("journal.jsonl symlinked to the secret", special_in_capture("journal.jsonl", "secret"), rr(ERROR, ERROR),
        strict=True)
    add("capture.json symlinked to the secret", special_in_capture("capture.json", "secret"), rr(ERROR, ERROR),
        strict=True)
    add("manifest.json symlinked outside", symlink_outside("manifest.json"), rr(SUCCESS, SUCCESS))
    add("rig.yaml snapshot symlinked to /etc/passwd", special_in_capture("rig.yaml", "etc_passwd"),
        rr(ERROR, EITHER), strict=True)
    add("rig.yaml scene is /etc/passwd", lambda ctx: scene_in_snapshot(ctx, "/etc/passwd"), rr(ERROR, EITHER),
        strict=True)
    for name, file_of in [("../outside/victim.png", lambda ctx: "../outside/victim.png"),
                          ("frames/../../outside/victim.png", lambda ctx: "frames/../../outside/victim.png"),
                          ("absolute path of the victim", lambda ctx: os.path.join(ctx.outside, "victim.png"))]:
        add("record names %s (with its SHA-256)" % name,
            lambda ctx, f=file_of: edit_records_to_victim(ctx, f), rr(ERROR, ERROR), core=name.startswith(".."))
    for name, out_of in [("the recording", lambda ctx: ctx.cap), ("frames/x", lambda ctx: cap_path(ctx, "frames/x")),
                         ("recording/sub/../frames/y", lambda ctx: cap_path(ctx, "sub/../frames/y")),
                         ("a symlink to the recording", lambda ctx: link_to_capture(ctx))]:
        variants.append(Variant("path escapes", "replay --out inside %s" % name, on_copy(lambda ctx: None),
                                [Probe("replay", lambda ctx, o=out_of: ["replay", ctx.cap, "--out", o(ctx)], ERROR,
                                       protect_capture=True)], core=name == "frames/x"))
    for name, serial in [("camera serial ../../../escaped", "../../../escaped"),
                         ("camera serial naming an absolute path", os.path.join(c.global_outside, "abs")),
                         ("camera serial with a NUL-free control character", "CAM\x01../../x")]:
        variants.append(Variant("path escapes", name, lambda ctx, s=serial: hostile_serial_rig(ctx, s),
                                [config_probes(c, SUCCESS, SUCCESS)[1]]))
    variants.append(Variant("path escapes", "capture --subject ../../outside/x",
                            lambda ctx: None,
                            [Probe("capture", lambda ctx: ["capture", "--config", c.base_config, "--out", ctx.cap,
                                                           "--subject", "../../outside/x"], SUCCESS,
                                   c.check_fresh_capture)]))
    return variants


def moved_outside(name, then=None):
    """An edit moving `name` of the capture into outside/ and leaving a symlink to it."""
    def edit(ctx):
        target = os.path.join(ctx.outside, os.path.basename(name) + "_moved")
        os.rename(cap_path(ctx, name), target)
        os.symlink(target, cap_path(ctx, name))
        if then:
            then(ctx)
    return edit


def hostile_serial_rig(ctx, serial):
    """rig.yaml and its scene in the run folder, the lower camera's serial replaced by `serial`."""
    c = ctx.campaign
    quoted = json.dumps(serial)  # a YAML double-quoted scalar
    with open(os.path.join(c.repo, "tests/data/small_scene.yaml"), encoding="utf-8") as f:
        scene = f.read()
    scene = scene.replace("file: ../../etc/calib-box.yaml", "file: " + os.path.join(c.repo, "etc/calib-box.yaml"))
    write_text(ctx.path("scene.yaml"), scene.replace("serial: SIM-CAM-LOWER", "serial: " + quoted))
    rig = c.base_config_text().replace(os.path.join(c.repo, "tests/data/small_scene.yaml"), ctx.path("scene.yaml"))
    write_text(ctx.path("rig.yaml"), rig.replace("serial: SIM-CAM-LOWER", "serial: " + quoted))


def frame_link_outside(frame):
    def edit(ctx):
        victim = os.path.join(ctx.outside, "victim.png")
        os.rename(cap_path(ctx, frame), victim)
        os.symlink(victim, cap_path(ctx, frame))
    return edit


def frame_hardlink_outside(frame):
    def edit(ctx):
        victim = os.path.join(ctx.outside, "victim.png")
        os.truncate(cap_path(ctx, frame), os.path.getsize(cap_path(ctx, frame)) // 2)
        os.link(cap_path(ctx, frame), victim)
    return edit


def scene_in_snapshot(ctx, path):
    rig = cap_path(ctx, "rig.yaml")
    with open(rig, encoding="utf-8") as f:
        text = f.read()
    write_text(rig, text.replace(os.path.join(ctx.campaign.repo, "tests/data/small_scene.yaml"), path))


def edit_records_to_victim(ctx, file_of):
    c = ctx.campaign
    victim = os.path.join(ctx.outside, "victim.png")
    shutil.copyfile(cap_path(ctx, c.frame_files[0]), victim)
    lines = []
    for line in c.journal_lines:
        record = json.loads(line)
        if record.get("event") == "frame_stored" and record.get("view") == 0:
            record["file"] = file_of(ctx)
            line = json.dumps(record, separators=(",", ":"))
        lines.append(line)
    write_text(cap_path(ctx, "journal.jsonl"), "\n".join(lines) + "\n")


def link_to_capture(ctx):
    link = os.path.join(ctx.out, "link")
    if not os.path.lexists(link):
        os.symlink(ctx.cap, link)
    return os.path.join(link, "replayed")


# ---------------------------------------------------------------------------
# Category: COLMAP input


# The points stage at its cheapest: a run that gets past the input reading ends in seconds.
QUICK_POINTS = ["--stage", "points", "--stride", "8", "--iterations", "1", "--cost", "photometric",
                "--threads", "2"]
COLMAP_VIEWS = range(6)  # the capture's views in the model: both cameras at the first three stops
COLMAP_TIMEOUT = 180.0   # a model the reader accepts runs the stereo on its views
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(width, height, rows):
    """An 8-bit grey PNG of `rows` (bytes each) whose IHDR claims width x height."""
    pixels = zlib.compress(b"".join(b"\x00" + row for row in rows))
    return (PNG_SIGNATURE + png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
            + png_chunk(b"IDAT", pixels) + png_chunk(b"IEND", b""))


def colmap_base(c):
    """(cameras, images) of the calibration's COLMAP export, as lists of fields: the images of
    COLMAP_VIEWS, and a third camera, PINHOLE (camera 1 without its distortion), for the last
    image of camera 1."""
    folder = os.path.join(c.calibrated, "calibration", "colmap")
    cameras, images = [], []
    for name, rows in (("cameras.txt", cameras), ("images.txt", images)):
        with open(os.path.join(folder, name), encoding="utf-8") as f:
            rows.extend(line.split() for line in f if line.strip() and not line.startswith("#"))
    wanted = [os.path.basename(c.frame_files[v]) for v in COLMAP_VIEWS]
    images = [fields for fields in images if len(fields) == 10 and fields[9] in wanted]
    first_camera = [fields for fields in images if fields[8] == "1"]
    if len(images) < 5 or len(first_camera) < 3 or len(cameras) != 2:
        raise RuntimeError("the calibration's COLMAP export lacks views of %s" % list(COLMAP_VIEWS))
    cameras.append(["3", "PINHOLE"] + cameras[0][2:8])
    first_camera[-1][8] = "3"
    return cameras, images


def colmap_text(cameras, images):
    """cameras.txt and images.txt of the model (an empty POINTS2D line after each image)."""
    cams = "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n" + "".join(" ".join(f) + "\n" for f in cameras)
    imgs = "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then POINTS2D\n"
    return cams, imgs + "".join(" ".join(f) + "\n\n" for f in images)


def colmap_prepare(base, edit=None, files=None):
    """prepare(): model/ (edit(cameras, images, ctx) applied to the base) and images/ with the
    base's frames, then files(ctx)."""
    def prepare(ctx):
        c = ctx.campaign
        cameras, images = copy.deepcopy(base)
        if edit:
            edit(cameras, images, ctx)
        os.makedirs(ctx.path("model"))
        os.makedirs(ctx.path("images"))
        cams, imgs = colmap_text(cameras, images)
        write_text(ctx.path("model", "cameras.txt"), cams)
        write_text(ctx.path("model", "images.txt"), imgs)
        write_text(ctx.path("model", "points3D.txt"), "")
        for fields in base[1]:
            shutil.copyfile(os.path.join(c.calibrated, "frames", fields[9]), ctx.path("images", fields[9]))
        if files:
            files(ctx)
    return prepare


def left_out_problem(points, names):
    """Why a points summary uses one of the damaged views `names` or does not name it in left_out."""
    if not isinstance(points, dict):
        return "success without a points summary"
    used = {v.get("name") for v in points.get("views", []) if isinstance(v, dict)}
    left = [str(entry) for entry in points.get("left_out", [])]
    for name in names:
        if name in used:
            return "view %s used though its input is damaged" % name
        if not any(entry.startswith(name + ":") for entry in left):
            return "view %s not named in left_out" % name
    return None


def colmap_probe(c, accept=ERROR, named=(), images="images", model="model", timeout=COLMAP_TIMEOUT):
    """reconstruct --colmap; a success must name the views `named` as left out (and use none)."""
    def argv(ctx):
        return ["reconstruct", ctx.out, "--colmap", ctx.path(model), "--images", ctx.path(images),
                "--json"] + QUICK_POINTS

    def check(ctx, result):
        return left_out_problem((parse_last_json(result.output) or {}).get("points"), named)
    return Probe("reconstruct", argv, accept, check, timeout=timeout)


def stem(name):
    return os.path.splitext(os.path.basename(name))[0]


def unavailable(category, what, error):
    """The variants of a category whose input could not be made: one, recorded as "other"."""
    def prepare(ctx):
        raise RuntimeError("%s: %s" % (what, error))
    return [Variant(category, what, prepare, [Probe("setup", lambda ctx: [])], core=True)]


def colmap_variants(c, rng):
    try:
        base = colmap_base(c)
    except (OSError, RuntimeError) as e:
        return unavailable("colmap input", "the calibration's COLMAP export", e)
    cameras, images = base
    k = rng.randrange(1, len(images))  # the image made hostile; image 0 is what others repeat
    name = images[k][9]
    variants = []

    def add(label, edit=None, files=None, core=False, strict=False, **probe):
        variants.append(Variant("colmap input", label, colmap_prepare(base, edit, files),
                                [colmap_probe(c, **probe)], core, strict, guard_reads=True))

    def field(row, index, value, table="images"):
        def edit(cams, imgs, ctx):
            (imgs if table == "images" else cams)[row][index] = value(ctx) if callable(value) else value
        return edit

    def image_file(kind, target=None):
        return lambda ctx: replace_with(ctx.path("images", name), kind, target(ctx) if target else None)

    def victim(ctx):
        path = os.path.join(ctx.outside, "victim.png")
        shutil.copyfile(os.path.join(c.calibrated, "frames", name), path)
        return path

    add("valid model (control)", accept=SUCCESS, core=True)
    add("image NAME absolute (a copy outside)", field(k, 9, victim), core=True)
    add("image NAME ../outside/victim.png", field(k, 9, "../outside/victim.png"), files=victim, core=True)
    add("image NAME a symlink leaving --images", files=image_file("symlink", victim), core=True)
    add("image NAME a symlink to /etc/passwd", files=image_file("symlink", lambda ctx: "/etc/passwd"),
        strict=True)
    add("image NAME a FIFO", files=image_file("fifo"), core=True)
    add("image NAME a folder", files=image_file("dir"))
    add("image NAME a symlink to /dev/zero", files=image_file("symlink", lambda ctx: "/dev/zero"), core=True)
    add("PNG whose IHDR claims 100000x100000",
        files=lambda ctx: write_bytes(ctx.path("images", name), encode_png(100000, 100000, [bytes(16)] * 4)),
        core=True)
    add("PNG truncated to half", files=lambda ctx: os.truncate(ctx.path("images", name),
                                                                os.path.getsize(ctx.path("images", name)) // 2),
        accept=SUCCESS, named=(stem(name),))
    jpeg = b"\xff\xd8" + bytes(rng.getrandbits(8) for _ in range(4096))
    add("JPEG with garbage after the SOI", field(k, 9, stem(name) + ".jpg"),
        files=lambda ctx: write_bytes(ctx.path("images", stem(name) + ".jpg"), jpeg))
    add_colmap_table_variants(add, field, base, k)
    add("images.txt missing", files=lambda ctx: os.remove(ctx.path("model", "images.txt")), core=True)
    add("cameras.txt missing", files=lambda ctx: os.remove(ctx.path("model", "cameras.txt")))
    add("--images folder that does not exist", images="no_such_folder", core=True)
    add("--colmap folder that does not exist", model="no_such_model")
    return variants


def add_colmap_table_variants(add, field, base, k):
    """Edits of cameras.txt and images.txt: repeats, unknown ids, numbers, short lines."""
    cameras, images = base
    upper_names = tuple(stem(f[9]) for f in images if f[8] == "1")  # the views of camera 1

    def edit(change):
        return lambda cams, imgs, ctx: change(cams, imgs)

    add("duplicate IMAGE_ID", field(k, 0, images[0][0]), core=True)
    add("duplicate NAME", field(k, 9, images[0][9]), core=True)
    add("12000 repeated entries", edit(lambda cams, imgs: imgs.__setitem__(slice(None), [imgs[0]] * 12000)),
        timeout=None, core=True)
    add("duplicate CAMERA_ID", edit(lambda cams, imgs: cams.append(cams[0][:4] + cams[1][4:])), core=True)
    add("unknown CAMERA_ID", field(k, 8, "9"), core=True)
    add("CAMERA_ID -1", field(k, 8, "-1"))
    add("IMAGE_ID nan", field(k, 0, "nan"))
    for index, label in [(1, "QW"), (3, "QY"), (5, "TX"), (7, "TZ")]:
        for value in ["nan", "inf", "-inf", "1e999"]:
            add("%s %s" % (label, value), field(k, index, value), core=(label, value) == ("QW", "nan"))
    add("quaternion of zero norm", edit(lambda cams, imgs: imgs[k].__setitem__(slice(1, 5), ["0"] * 4)),
        core=True)
    add("quaternion of norm 2", edit(lambda cams, imgs: imgs[k].__setitem__(
        slice(1, 5), [repr(2 * float(v)) for v in imgs[k][1:5]])))
    for index, label in [(4, "fx"), (5, "fy"), (6, "cx"), (8, "k1")]:
        for value in ["nan", "inf"]:
            add("camera 1 %s %s" % (label, value), field(0, index, value, "cameras"),
                core=(label, value) == ("fx", "nan"))
    add("camera 1 negative focal length", field(0, 4, "-" + cameras[0][4], "cameras"), core=True)
    add("camera 1 focal length 0", field(0, 4, "0", "cameras"))
    add("camera 1 width 0", field(0, 2, "0", "cameras"), core=True)
    add("camera 1 height 0", field(0, 3, "0", "cameras"))
    # The images' own size wins over the camera line's (named in a warning); the run completes, and
    # on the campaign's coarse stereo settings its verdict may fail (exit 3).
    add("camera 1 width 10^9", field(0, 2, "1000000000", "cameras"), accept=EITHER, named=upper_names)
    add("camera 1 height 10^9", field(0, 3, "1000000000", "cameras"), accept=EITHER, named=upper_names,
        core=True)
    add("camera 1 width 10^10", field(0, 2, "10000000000", "cameras"))
    add("camera 1 width 2.5", field(0, 2, "2.5", "cameras"))
    add("camera model FISHEYE", field(0, 1, "FISHEYE", "cameras"))
    add("image line with 9 fields", edit(lambda cams, imgs: imgs[k].pop()), core=True)
    add("image line with 11 fields", edit(lambda cams, imgs: imgs[k].append("extra")))
    add("camera line with 3 fields", edit(lambda cams, imgs: cams[0].__delitem__(slice(3, None))), core=True)
    add("camera line one parameter short", edit(lambda cams, imgs: cams[0].pop()))
    add("PINHOLE camera with OPENCV's parameters", edit(lambda cams, imgs: cams[2].extend(cams[0][8:12])))
    add("no cameras", edit(lambda cams, imgs: cams.clear()))
    add("no images", edit(lambda cams, imgs: imgs.clear()))


# ---------------------------------------------------------------------------
# Category: stage inputs


DAMAGED_VIEW, OTHER_VIEW = 5, 7
STAGE_VIEWS = [4, 5, 6, 7]  # `reconstruct` runs on these: the damaged view and its neighbours
STAGE_TIMEOUT = 900.0       # `stage reconstruct` runs the whole reconstruction of the capture
CAPTURE_POINTS = QUICK_POINTS + ["--views"] + [str(v) for v in STAGE_VIEWS]  # --views last: it takes a list
SMALL_STAGE_OPTIONS = {"reconstruct": {"method": "naive", "strands": 50, "stride_px": 8, "iterations": 1,
                                       "hull_voxel_mm": 8.0, "threads": 2},
                       "calibrate": {"threads": 2}}


def view_name(c, view):
    """The name the stages give a view: its frame file's name without the extension."""
    return stem(c.frame_files[view])


def on_calibrated(edit):
    """prepare(): a copy of the calibrated capture, then edit(ctx)."""
    def prepare(ctx):
        shutil.copytree(ctx.campaign.calibrated, ctx.cap, symlinks=True)
        edit(ctx)
    return prepare


def on_reconstructed(edit):
    """prepare(): a copy of the capture with STAGE_VIEWS' points reconstructed, then edit(ctx)."""
    def prepare(ctx):
        shutil.copytree(ctx.campaign.reconstructed_copy(), ctx.cap, symlinks=True)
        edit(ctx)
    return prepare


def reconstruct_probe(c, damaged):
    """reconstruct --views STAGE_VIEWS: a damaged view among them is refused (what --views asks
    for), or left out and named. EITHER: a refusal is not listed as one of input it could repair;
    reconstruct never exits 3."""
    names = [view_name(c, v) for v in damaged if v in STAGE_VIEWS]

    def check(ctx, result):
        return left_out_problem((parse_last_json(result.output) or {}).get("points"), names)
    return Probe("reconstruct", lambda ctx: ["reconstruct", ctx.cap, "--json"] + CAPTURE_POINTS, EITHER, check,
                 timeout=COLMAP_TIMEOUT)


def stage_reconstruct_probe(c, damaged):
    names = [view_name(c, v) for v in damaged]

    def check(ctx, result):
        summary = (parse_last_json(result.output) or {}).get("summary")
        return left_out_problem(summary.get("points") if isinstance(summary, dict) else None, names)
    return Probe("stage reconstruct", lambda ctx: ["stage", "reconstruct", "--capture", ctx.cap, "--options",
                                                   c.stage_options, "--force", "--json"],
                 SUCCESS, check, timeout=STAGE_TIMEOUT)


def calibrated_damage_check(damaged):
    """check(): the calibration.json written solves none of the damaged views."""
    def check(ctx, _result):
        doc = load_json_file(os.path.join(ctx.cap, "calibration", "calibration.json"))
        if not isinstance(doc, dict) or not isinstance(doc.get("views"), list):
            return "success without a readable calibration/calibration.json"
        solved = {v.get("view") for v in doc["views"] if isinstance(v, dict) and v.get("solved") is True}
        used = sorted(solved & set(damaged))
        return "views %s solved from damaged frames" % compact_list(used) if used else None
    return check


def calibrate_probes(c, damaged, cli):
    """stage calibrate (and `calibrate` when `cli`): a damaged view is never solved."""
    check = calibrated_damage_check(damaged)
    probes = [Probe("stage calibrate", lambda ctx: ["stage", "calibrate", "--capture", ctx.cap, "--options",
                                                    c.stage_options, "--force", "--json"],
                    SUCCESS, check, protect_capture=True, timeout=COLMAP_TIMEOUT)]
    if cli:
        probes.append(Probe("calibrate", lambda ctx: ["calibrate", ctx.cap, "--json"], EITHER, check,
                            protect_capture=True, timeout=COLMAP_TIMEOUT))
    return probes


def json_edit(name, change):
    """An edit rewriting the capture's JSON file `name` as change(document) (NaN written as NaN)."""
    def edit(ctx):
        doc = load_json_file(cap_path(ctx, name))
        write_text(cap_path(ctx, name), json.dumps(change(doc), indent=1))
    return edit


def first_number(doc, prefix):
    """The pointer of the first number under `prefix`."""
    for pointer in json_pointers(json_get(doc, prefix), tuple(prefix)):
        value = json_get(doc, pointer)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return pointer
    raise RuntimeError("no number under %s" % (prefix,))


def view_index(doc, view):
    return next(i for i, v in enumerate(doc["views"]) if v.get("view") == view)


def stage_variants(c):
    c.stage_options = os.path.join(c.root, "stage_options.json")
    write_json(c.stage_options, SMALL_STAGE_OPTIONS)
    frame, other = c.frame_files[DAMAGED_VIEW], c.frame_files[OTHER_VIEW]
    every = sorted(c.frame_files)
    lower = sorted(v["view"] for v in c.calibration["views"] if v.get("camera") == 1)
    variants = []

    def add(name, edit, damaged, calibrate=None, core=False):
        """Variants for one damage: reconstruct, stage reconstruct (slow) and, when `calibrate` is
        not None, the calibrations on a damaged copy of the uncalibrated capture."""
        variants.append(Variant("stage inputs", name, on_calibrated(edit), [reconstruct_probe(c, damaged)], core))
        variants.append(Variant("stage inputs", name + " (stage reconstruct)", on_calibrated(edit),
                                [stage_reconstruct_probe(c, damaged)], core and calibrate is None, slow=True))
        if calibrate is not None:
            variants.append(Variant("stage inputs", name + " (calibrate)", on_copy(edit),
                                    calibrate_probes(c, damaged, calibrate), core))

    add("frame 5 replaced by view 7's bytes",
        lambda ctx: shutil.copyfile(cap_path(ctx, other), cap_path(ctx, frame)), [DAMAGED_VIEW], False, core=True)
    add("frame 5 truncated to half", truncate_file(frame), [DAMAGED_VIEW], False)
    add("frame 5 a symlink to its copy outside", frame_link_outside(frame), [DAMAGED_VIEW], True, core=True)
    add("frames/ a symlink to a copy outside", moved_outside("frames"), every, True, core=True)
    add("frame 5 deleted", special_in_capture(frame, "missing"), [DAMAGED_VIEW], True)
    cj = "calibration/calibration.json"
    add("calibration.json view 5 pose NaN", json_edit(cj, lambda d: with_field(
        d, first_number(d, ("views", view_index(d, DAMAGED_VIEW), "cam_from_object")), float("nan"))),
        [DAMAGED_VIEW], core=True)
    add("calibration.json camera 'lower' fx NaN",
        json_edit(cj, lambda d: with_field(d, ("cameras", 1, "intrinsics", "fx_px"), float("nan"))), lower)
    add("calibration.json camera 'lower' missing", json_edit(cj, lambda d: with_field(d, ("cameras", 1), DELETE)),
        lower, core=True)
    add("calibration.json views missing", json_edit(cj, lambda d: with_field(d, ("views",), DELETE)), every)
    variants.extend(eval_variants(c))
    return variants


def eval_variants(c):
    """eval reconstruction on a reconstructed copy whose ground truth is damaged: an error is due."""
    truth_map = "ground_truth/views/%03d_label.png"
    label, other = truth_map % DAMAGED_VIEW, truth_map % OTHER_VIEW
    gj = "ground_truth/ground_truth.json"
    probe = lambda: [Probe("eval", lambda ctx: ["eval", "reconstruction", ctx.cap, "--json"], ERROR,
                           timeout=COLMAP_TIMEOUT)]
    variants = []
    for name, edit, core in [
            ("view 5 truth label map replaced by view 7's",
             lambda ctx: shutil.copyfile(cap_path(ctx, other), cap_path(ctx, label)), True),
            ("view 5 truth label map truncated to half", truncate_file(label), False),
            ("view 5 truth label map a symlink to its copy outside", frame_link_outside(label), True),
            ("view 5 truth label map deleted", special_in_capture(label, "missing"), False),
            ("ground_truth/ a symlink to a copy outside", moved_outside("ground_truth"), True),
            ("ground_truth.json turntable_from_box NaN", json_edit(gj, lambda d: with_field(
                d, first_number(d, ("turntable_from_box",)), float("nan"))), False),
            ("ground_truth.json without view 5", json_edit(gj, lambda d: with_field(
                d, ("views", view_index(d, DAMAGED_VIEW)), DELETE)), False)]:
        variants.append(Variant("stage inputs", "eval: " + name, on_reconstructed(edit), probe(), core))
    return variants


# ---------------------------------------------------------------------------
# Category: console load


CONSOLE_CAPTURE_ID = "cap1"  # the recorded capture, copied into the console's captures folder
CLIENT = "hostile campaign"
ANSWER_WAIT = 10.0           # seconds a request may take before the console counts as hung
CRASH_MARKERS = ("terminate called", "AddressSanitizer", "LeakSanitizer", "runtime error:")


def load_bench_module():
    """bench/console_load_bench.py as a module (request, Pressure, start_console)."""
    here = os.path.dirname(os.path.abspath(__file__))
    if here not in sys.path:
        sys.path.insert(0, here)
    import console_load_bench
    return console_load_bench


def raise_open_file_limit(wanted):
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < wanted:
        resource.setrlimit(resource.RLIMIT_NOFILE, (wanted if hard == resource.RLIM_INFINITY else min(wanted, hard),
                                                    hard))


class ConsoleSession:
    """One `hairrig serve --listen 127.0.0.1:0` for the console cases: started on first use,
    started again after a crash or a hang, stopped at the end of the campaign."""

    def __init__(self, campaign):
        self.c = campaign
        self.bench = load_bench_module()
        self.captures = os.path.join(campaign.root, "console_captures")
        self.proc, self.port, self.lease = None, None, ""
        self.starts = 0
        self.outside_before = tree_state(campaign.global_outside)

    def start(self):
        if not os.path.isdir(os.path.join(self.captures, CONSOLE_CAPTURE_ID)):
            shutil.copytree(self.c.master, os.path.join(self.captures, CONSOLE_CAPTURE_ID), symlinks=True)
        raise_open_file_limit(4096)
        try:
            self.proc, self.port = self.bench.start_console(self.c.hairrig, self.captures,
                                                            extra=["--config", self.c.base_config])
        except SystemExit as e:
            raise RuntimeError(str(e))
        self.starts += 1
        self.lease = self.claim_lease()

    def alive(self):
        return self.proc is not None and self.proc.poll() is None

    def stop(self):
        if self.proc is None:
            return
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def argv(self, case):
        return [self.c.hairrig, "serve", "--listen", "127.0.0.1:%s" % self.port, "--captures", self.captures,
                "--live-fps", "1", "--config", self.c.base_config, "#", case]

    def log_tail(self):
        return list(getattr(self.proc, "stderr_tail", ()))

    def crash_lines(self):
        """Lines of the console's log that report a crash (after one, the console is started again)."""
        return [line for line in self.log_tail() if any(m in line for m in CRASH_MARKERS)]

    def request(self, method, path, body=None, lease=False, timeout=ANSWER_WAIT):
        headers = {"X-Hairrig-Lease": self.lease} if lease else None
        return self.bench.request(self.port, method, path, body, headers, timeout=timeout)

    def claim_lease(self):
        status, body, _ = self.request("POST", "/api/control", {"client": CLIENT, "take": True})
        try:
            return json.loads(body)["lease"] if status == 200 else ""
        except (ValueError, KeyError, TypeError):
            return ""

    def state_answers(self, timeout=ANSWER_WAIT):
        return self.request("GET", "/api/state", timeout=timeout)[0] == 200

    def press_estop(self, timeout=ANSWER_WAIT):
        """(status, whether the answer says the e-stop is active, seconds)."""
        status, body, seconds = self.request("POST", "/api/estop", {"client": CLIENT}, timeout=timeout)
        try:
            active = status == 200 and json.loads(body)["estop"]["active"] is True
        except (ValueError, KeyError, TypeError):
            active = False
        return status, active, seconds

    def release_estop(self):
        """Releases the e-stop under the control lease (claimed again when it has lapsed)."""
        if self.request("POST", "/api/estop/release", {}, lease=True)[0] != 200:
            self.lease = self.claim_lease()
            self.request("POST", "/api/estop/release", {}, lease=True)

    def after_case(self, outcome, reason):
        """The case's outcome, overridden by a crash (the process ended or logged one) or a hang (no
        answer to /api/state within ANSWER_WAIT); the console is started again after either."""
        answers = self.alive() and self.state_answers()
        if not answers and self.proc is not None:
            try:
                self.proc.wait(timeout=2)  # a console that is ending
            except subprocess.TimeoutExpired:
                pass
        crash_lines = self.crash_lines()
        if not self.alive():
            code = None if self.proc is None else self.proc.returncode
            outcome, reason = "crash", "the console ended (exit %s) during this case or just before; %s" % (
                code, " | ".join(self.log_tail()[-3:])[:300])
        elif crash_lines:
            outcome, reason = "crash", "the console logged: %s" % " | ".join(crash_lines)[:300]
        elif not answers and outcome != "hang":
            outcome, reason = "hang", "no answer to GET /api/state (within %.0f s) after this case" % ANSWER_WAIT
        if outcome in ("crash", "hang"):
            self.stop()
            try:
                self.start()
            except (RuntimeError, OSError) as e:
                reason += "; the console could not be started again: %s" % e
        return outcome, reason


@dataclass
class Answer:
    status: Optional[int]  # the HTTP status, None without an answer
    body: str
    closed: bool           # the console closed the connection
    seconds: float
    note: str = ""

    def describe(self):
        return "HTTP %s after %.1f s%s%s" % (self.status, self.seconds, ", closed" if self.closed else "",
                                             "; " + self.note if self.note else "")


def http_bytes(method, target, headers=(), body=b"", close=True):
    """A request; `target` may hold any character (latin-1), headers are "Name: value" lines."""
    lines = ["%s %s HTTP/1.1" % (method, target), "Host: 127.0.0.1"] + list(headers)
    if close:
        lines.append("Connection: close")
    return ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1") + body


def response_complete(data):
    head, sep, body = data.partition(b"\r\n\r\n")
    length = re.search(rb"(?im)^content-length:\s*(\d+)\s*$", head)
    return bool(sep) and bool(length) and len(body) >= int(length.group(1))


def raw_send(sock, data, deadline):
    """Sends `data` on the non-blocking `sock` until all is sent, the console answers or closes,
    or `deadline`; the bytes sent."""
    poller = select.poll()
    poller.register(sock, select.POLLIN | select.POLLOUT)
    view, sent = memoryview(data), 0
    while sent < len(data) and time.monotonic() < deadline:
        flags = 0
        for _, f in poller.poll(max(1, int(1000 * (deadline - time.monotonic())))):
            flags |= f
        if flags & (select.POLLIN | select.POLLHUP | select.POLLERR):
            break
        try:
            sent += sock.send(view[sent:sent + 65536])
        except BlockingIOError:
            continue
        except OSError:
            break
    return sent


def raw_receive(sock, deadline, enough=response_complete, limit=4 << 20):
    """(bytes, closed): what the console sent until it closed, enough(bytes), or `deadline`."""
    poller = select.poll()
    poller.register(sock, select.POLLIN)
    data = b""
    while time.monotonic() < deadline and not enough(data):
        if not poller.poll(max(1, int(1000 * (deadline - time.monotonic())))):
            continue
        try:
            chunk = sock.recv(65536)
        except BlockingIOError:
            continue
        except OSError:
            return data, True
        if not chunk:
            return data, True
        if len(data) < limit:
            data += chunk
    return data, False


def answer_of(data, closed, seconds, note=""):
    status = re.match(rb"HTTP/1\.[01] (\d{3})", data)
    body = data.partition(b"\r\n\r\n")[2].decode("utf-8", "replace")
    return Answer(int(status.group(1)) if status else None, body, closed, seconds, note)


def raw_request(port, data, wait=ANSWER_WAIT, send_for=30.0, enough=response_complete):
    """Sends `data` on a new connection (stopping early when the console answers or closes), then
    waits up to `wait` for the answer."""
    start = time.monotonic()
    try:
        sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    except OSError as e:
        return Answer(None, "", True, time.monotonic() - start, "cannot connect: %s" % e)
    with sock:
        sock.setblocking(False)
        sent = raw_send(sock, data, start + send_for)
        received, closed = raw_receive(sock, time.monotonic() + wait, enough)
    note = "" if sent == len(data) else "%d of %d bytes sent" % (sent, len(data))
    return answer_of(received, closed, time.monotonic() - start, note)


def refusal_outcome(c, answer):
    """A request that must be refused: 4xx or a close is clean, 2xx silent, no answer a hang."""
    leaked = c.leaked_lines(answer.body)
    if leaked:
        return "silent", "served %d line(s) of a file outside the captures" % leaked
    if answer.status is None:
        return ("clean", "") if answer.closed else ("hang", "no answer, connection open after %.0f s"
                                                    % answer.seconds)
    if 400 <= answer.status < 500:
        return "clean", ""
    if 200 <= answer.status < 300:
        return "silent", "answered %d where a refusal was due" % answer.status
    return "other", "answered %d" % answer.status


def refused_case(data_of, wait=ANSWER_WAIT):
    """attack(): one request built by data_of(session) that the console must refuse."""
    def attack(session):
        answer = raw_request(session.port, data_of(session), wait=wait)
        outcome, reason = refusal_outcome(session.c, answer)
        return outcome, reason, answer.describe()
    return attack


def estop_series(session, tries, limit_s=150.0):
    """Presses the e-stop `tries` times (released after each): each must be acted on within 1 s."""
    acted, problems, unanswered = [], [], 0
    deadline = time.monotonic() + limit_s
    for k in range(tries):
        if time.monotonic() > deadline:
            problems.append("stopped after %d presses (%.0f s bound)" % (k, limit_s))
            break
        status, active, seconds = session.press_estop()
        if status is None and seconds >= ANSWER_WAIT - 0.5:
            unanswered += 1
        elif not active or seconds > 1.0:
            problems.append("press %d: HTTP %s, active %s, %.2f s" % (k + 1, status, active, seconds))
        else:
            acted.append(seconds)
        session.release_estop()
    summary = "%d of %d presses acted on within 1 s (slowest %.0f ms)" % (len(acted), tries,
                                                                         1000 * max(acted, default=0))
    if unanswered:
        return "hang", "%d press(es) unanswered after %.0f s; %s" % (unanswered, ANSWER_WAIT, summary)
    if problems:
        return "other", "%s; %s" % (problems[0], summary)
    return "handled", summary


def attack_flood(session):
    """2000 idle + 200 slow-header connections held, then the e-stop pressed 20 times."""
    with session.bench.Pressure(session.port, 2000, 200) as pressure:
        time.sleep(2)
        outcome, reason = estop_series(session, 20)
        held = "; %d connections reopened after the console closed them, %d connects failed" % (
            pressure.reopened, pressure.failed_connects)
    return outcome, reason + held, reason + held


def attack_stalled_body(session):
    """Content-Length 1000, a 10-byte body, then silence: the console must go on answering and
    drop or refuse the request (it must not act on it)."""
    start = time.monotonic()
    data = http_bytes("POST", "/api/estop", ["Content-Type: application/json", "Content-Length: 1000"],
                      b'{"client":')
    with socket.create_connection(("127.0.0.1", session.port), timeout=5) as sock:
        sock.setblocking(False)
        raw_send(sock, data, start + 10)
        time.sleep(1)
        state = session.state_answers()
        received, closed = raw_receive(sock, time.monotonic() + 30)
    answer = answer_of(received, closed, time.monotonic() - start)
    if not state:
        return "hang", "no answer to /api/state while a request stalls", answer.describe()
    if answer.status is None and not closed:
        return "other", "the stalled request was still open after %.0f s" % answer.seconds, answer.describe()
    outcome, reason = refusal_outcome(session.c, answer)
    return outcome, reason, answer.describe()


def attack_chunked(session):
    """A chunked body: refused (411) or served; either is right, no answer is not."""
    body = json.dumps({"client": CLIENT}).encode()
    chunked = b"%x\r\n%s\r\n0\r\n\r\n" % (len(body), body)
    answer = raw_request(session.port, http_bytes("POST", "/api/estop", [
        "Content-Type: application/json", "Transfer-Encoding: chunked"], chunked))
    session.release_estop()
    if answer.status is not None and 200 <= answer.status < 300:
        return "handled", "", answer.describe()
    outcome, reason = refusal_outcome(session.c, answer)
    if outcome == "clean" and answer.status is None:
        return "other", "closed without an answer", answer.describe()
    return outcome, reason, answer.describe()


def take_responses(buffer):
    """(statuses of the whole responses at the start of `buffer`, the rest of it)."""
    statuses = []
    while True:
        head, sep, rest = buffer.partition(b"\r\n\r\n")
        status = re.match(rb"HTTP/1\.[01] (\d{3})", head)
        length = re.search(rb"(?im)^content-length:\s*(\d+)\s*$", head)
        if not sep or not status or not length or len(rest) < int(length.group(1)):
            return statuses, buffer
        statuses.append(int(status.group(1)))
        buffer = rest[int(length.group(1)):]


def pipelined(port, count, limit_s=60.0):
    """(statuses read, closed, seconds) of `count` pipelined GET /api/state on one connection."""
    start = time.monotonic()
    data = http_bytes("GET", "/api/state", close=False) * count
    sock = socket.create_connection(("127.0.0.1", port), timeout=30)  # one timeout for both threads

    def send():
        try:
            sock.sendall(data)
        except OSError:
            pass
    sender = threading.Thread(target=send, daemon=True)
    sender.start()
    statuses, buffer, closed = [], b"", False
    try:
        while len(statuses) < count and time.monotonic() - start < limit_s:
            if not select.select([sock], [], [], 1.0)[0]:
                continue
            try:
                chunk = sock.recv(1 << 16)
            except OSError:
                closed = True
                break
            if not chunk:
                closed = True
                break
            taken, buffer = take_responses(buffer + chunk)
            statuses += taken
    finally:
        sock.close()
        sender.join(timeout=5)
    return statuses, closed, time.monotonic() - start


def attack_pipelined(session, count=5000):
    statuses, closed, seconds = pipelined(session.port, count)
    ok = statuses.count(200)
    observed = "%d answers (%d of them 200) to %d pipelined requests in %.1f s%s" % (
        len(statuses), ok, count, seconds, ", then closed" if closed else "")
    if ok == count or (ok == len(statuses) and ok > 0 and closed):
        return "handled", "", observed
    if not statuses:
        return ("other" if closed else "hang"), "no answer to any pipelined request", observed
    return "other", "answers other than 200, or answering stopped without a close", observed


def open_event_streams(port, count):
    """`count` connections that ask for GET /api/events and never read (small receive buffers)."""
    socks = []
    for _ in range(count):
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.settimeout(5)
        try:
            sock.connect(("127.0.0.1", port))
            sock.sendall(http_bytes("GET", "/api/events", close=False))
        except OSError:
            sock.close()
            continue
        socks.append(sock)
    return socks


def stream_served_within(session, limit_s):
    """Seconds until a new GET /api/events is answered 200 (None when not within `limit_s`)."""
    start = time.monotonic()
    while time.monotonic() - start < limit_s:
        answer = raw_request(session.port, http_bytes("GET", "/api/events", close=False), wait=5,
                             enough=lambda d: b"\r\n" in d)
        if answer.status == 200:
            return time.monotonic() - start
        time.sleep(1)
    return None


def attack_event_streams(session, count=64, hold_s=12.0):
    """`count` event streams never read: the state and the e-stop must still answer, and a new
    stream must be served once they close."""
    opened = time.monotonic()
    socks = open_event_streams(session.port, count)
    try:
        time.sleep(1)
        state = session.state_answers()
        status, active, seconds = session.press_estop()
        session.release_estop()
        time.sleep(max(0.0, opened + hold_s - time.monotonic()))
    finally:
        for sock in socks:
            sock.close()
    freed = stream_served_within(session, 30)
    observed = "%d streams held %.0f s; state %s; e-stop HTTP %s active %s in %.2f s; new stream %s" % (
        len(socks), hold_s, "answered" if state else "unanswered", status, active, seconds,
        "served after %.1f s" % freed if freed is not None else "not served within 30 s")
    if not state or status is None:
        return "hang", "state or e-stop unanswered while event streams stall", observed
    if not active or seconds > 1.0:
        return "other", "the e-stop was not acted on within 1 s", observed
    if freed is None:
        return "other", "no new event stream served within 30 s of the stalled ones closing", observed
    return "handled", "", observed


def attack_still_answers(session):
    """After every case: /api/state and the e-stop answer, nothing outside the captures changed."""
    state = session.state_answers()
    status, active, seconds = session.press_estop()
    session.release_estop()
    changed = tree_changes(session.outside_before, tree_state(session.c.global_outside))
    observed = "state %s; e-stop HTTP %s active %s in %.2f s; console started %d time(s)" % (
        "answered" if state else "unanswered", status, active, seconds, session.starts)
    if not state or status is None:
        return "hang", "state or e-stop unanswered", observed
    if changed:
        return "silent", "changed outside its captures: %s" % compact_list(changed), observed
    if not active or seconds > 1.0:
        return "other", "the e-stop was not acted on within 1 s", observed
    if session.starts > 1:
        return "other", "answers, but only since it was started again after a crash or a hang", observed
    return "handled", "", observed


def console_variants(c):
    cap = CONSOLE_CAPTURE_ID
    secret = "..%2f..%2foutside%2fsecret.txt"  # from the console's captures/cap1 to the campaign's secret
    cases = [
        ("2000 idle + 200 slow-header connections, e-stop x20", attack_flood),
        ("100 KB of headers", refused_case(lambda s: http_bytes(
            "GET", "/api/state", ["X-Pad-%03d: %s" % (k, "a" * 1000) for k in range(100)]))),
        ("10 MB body with its Content-Length", refused_case(lambda s: http_bytes(
            "POST", "/api/estop", ["Content-Type: application/json", "Content-Length: %d" % (10 << 20)],
            b"{" + b" " * ((10 << 20) - 2) + b"}"))),
        ("Content-Length larger than the body, then silence", attack_stalled_body),
        ("chunked body", attack_chunked),
        ("5000 pipelined GET /api/state on one connection", attack_pipelined),
        ("64 event streams never read", attack_event_streams),
        ("1 MB request line", refused_case(lambda s: http_bytes("GET", "/api/state?pad=" + "a" * (1 << 20)))),
        ("NUL byte in the path", refused_case(lambda s: http_bytes("GET", "/api/captures/%s\x00/../../x" % cap))),
        ("%00 in a capture file's path", refused_case(lambda s: http_bytes(
            "GET", "/api/captures/%s/files/manifest.json%%00.png" % cap))),
        ("..%2f in a capture id", refused_case(lambda s: http_bytes(
            "GET", "/api/captures/..%2f..%2f..%2fetc%2fpasswd"))),
        ("capture id %2e%2e, a file outside", refused_case(lambda s: http_bytes(
            "GET", "/api/captures/%2e%2e/files/outside%2fsecret.txt"))),
        ("..%2f in a capture's file path", refused_case(lambda s: http_bytes(
            "GET", "/api/captures/%s/files/%s" % (cap, secret)))),
        ("..%2f in a capture's file path, /etc/passwd", refused_case(lambda s: http_bytes(
            "GET", "/api/captures/%s/files/..%%2f..%%2f..%%2f..%%2f..%%2f..%%2fetc%%2fpasswd" % cap))),
        ("..%2f in the capture id of a resume", refused_case(lambda s: http_bytes(
            "POST", "/api/captures/..%2f..%2fx/resume", ["X-Hairrig-Lease: " + s.lease,
                                                         "Content-Type: application/json", "Content-Length: 2"],
            b"{}"))),
        ("capture id %2e%2e in a resume", refused_case(lambda s: http_bytes(
            "POST", "/api/captures/%2e%2e/resume", ["X-Hairrig-Lease: " + s.lease,
                                                    "Content-Type: application/json", "Content-Length: 2"],
            b"{}"))),
        ("still answers /api/state and the e-stop after every case", attack_still_answers),
    ]
    return [Variant("console load", name, lambda ctx: None,
                    [Probe("console", lambda ctx, name=name: ["serve", "#", name])], core=True, attack=attack)
            for name, attack in cases]


# ---------------------------------------------------------------------------
# Selection, report


QUICK_QUOTA = {"journal records": 18, "dataset files": 12, "config files": 20, "calibration": 6,
               "strand files": 20, "helix models": 15, "path escapes": 10, "colmap input": 36,
               "stage inputs": 14, "console load": 17}


def build_variants(c, args):
    full = not args.quick
    seed = args.seed
    groups = [
        journal_variants(c, random.Random(seed + 1), 2 if full else 1),
        dataset_variants(c, random.Random(seed + 2), 4 if full else 1),
        config_variants(c, random.Random(seed + 3), 25 if full else 3, full),
        calibration_variants(c, random.Random(seed + 4), 8 if full else 1),
        strand_variants(c, random.Random(seed + 5), 150 if full else 10),
        helix_variants(c, random.Random(seed + 6), 120 if full else 10),
        escape_variants(c),
        colmap_variants(c, random.Random(seed + 7)),
        stage_variants(c),
        console_variants(c),
    ]
    selected = []
    for k, group in enumerate(groups):
        if not full:
            group = quick_selection(group, QUICK_QUOTA[group[0].category], random.Random(seed + 100 + k))
        selected.extend(group)
    if args.only:
        selected = [v for v in selected if args.only in "%s/%s" % (v.category, v.name)]
    return selected


def quick_selection(group, quota, rng):
    core = [v for v in group if v.core]
    rest = [v for v in group if not v.core and not v.slow]
    extra = rng.sample(range(len(rest)), max(0, min(len(rest), quota - len(core))))
    chosen = set(id(v) for v in core) | set(id(rest[i]) for i in extra)
    return [v for v in group if id(v) in chosen]


def table(results):
    categories = []
    for r in results:
        if r["category"] not in categories:
            categories.append(r["category"])
    rows = []
    for category in categories + ["total"]:
        rs = [r for r in results if category in ("total", r["category"])]
        rows.append([category, len(rs)] + [sum(1 for r in rs if r["outcome"] == o) for o in OUTCOMES])
    return rows


def print_report(c, runtime):
    headers = ["category", "runs", "crashes", "hangs", "silent", "clean errors", "handled", "other"]
    rows = table(c.results)
    widths = [max(len(str(x)) for x in column) for column in zip(headers, *rows)]
    line = lambda cells: "  ".join(str(x).ljust(w) if i == 0 else str(x).rjust(w)
                                   for i, (x, w) in enumerate(zip(cells, widths)))
    print()
    print(line(headers))
    print(line(["-" * w for w in widths]))
    for row in rows:
        if row[0] == "total":
            print(line(["-" * w for w in widths]))
        print(line(row))
    print("\nsilent: silent successes (exit 0 where an error was due, a damaged result, a write outside);"
          "\nhandled: a correct non-error outcome (valid input, a repair, a rightly incomplete run), checked."
          "\nconsole load: clean = refused with a 4xx status or a close; handled = served as it should be.")
    if not c.atime_works:
        print("reads outside were not checked: this file system does not record access times.")
    bad = [r for r in c.results if r["outcome"] in NOT_CLEAN]
    print("\n%d cases that are not clean (rerun one with the same options and --only 'CATEGORY/VARIANT' --keep):"
          % len(bad))
    for r in bad:
        print("- [%s] %s / %s (%s): exit %s; %s" % (r["outcome"], r["category"], r["variant"], r["probe"],
                                                     r["exit"], r["reason"]))
        print("    $ %s" % r["command"])
        print("    > %s" % r["first_line"])
        if "kept" in r:
            print("    kept: %s" % r["kept"])
    refused = [r for r in c.results if r["outcome"] == "clean" and r["expected_success"]]
    if refused:
        print("\n%d clean refusals of input that is valid or that the command could repair (safe, listed for"
              " information):" % len(refused))
        for r in refused:
            print("- %s / %s (%s): %s" % (r["category"], r["variant"], r["probe"], r["first_line"][:160]))
    print("\n%d runs in %.0f s (%s mode, seed %d, timeout %.0f s, %s)" % (
        len(c.results), runtime, "quick" if c.args.quick else "full", c.args.seed, c.args.timeout, c.hairrig))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hairrig", default="build/cli/hairrig")
    parser.add_argument("--quick", action="store_true", help="about 220 runs, the slow stages left out")
    parser.add_argument("--seed", type=int, default=20261124)
    parser.add_argument("--json", help="write every run and the table to this file")
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds per run")
    parser.add_argument("--only", help="run only variants whose 'category/variant' contains this")
    parser.add_argument("--keep", action="store_true", help="keep the work folder of every case not clean")
    parser.add_argument("--verbose", action="store_true", help="print each run as it ends")
    parser.add_argument("--list", action="store_true", help="list the variants and their runs, run nothing")
    args = parser.parse_args()
    start = time.monotonic()
    c = Campaign(args)
    try:
        if not os.access(c.hairrig, os.X_OK):
            raise RuntimeError("%s is not an executable (build it, or give --hairrig)" % c.hairrig)
        print("hostile campaign: work folder %s" % c.root, flush=True)
        c.setup()
        variants = build_variants(c, args)
        print("%d variants, %d runs" % (len(variants), sum(len(v.probes) for v in variants)), flush=True)
        if args.list:
            for v in variants:
                print("  %-16s %-60s %s" % (v.category, v.name[:60], ",".join(p.label for p in v.probes)))
            variants = []
        for k, variant in enumerate(variants):
            c.run_variant(variant)
            if not args.verbose and (k + 1) % 50 == 0:
                print("  %d of %d variants (%.0f s)" % (k + 1, len(variants), time.monotonic() - start), flush=True)
    except (RuntimeError, OSError) as e:
        print("hostile campaign stopped: %s" % e)
    finally:
        c.stop_console()
    runtime = time.monotonic() - start
    print_report(c, runtime)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"mode": "quick" if args.quick else "full", "seed": args.seed, "hairrig": c.hairrig,
                       "timeout_s": args.timeout, "runtime_s": round(runtime, 1),
                       "columns": ["category", "runs"] + OUTCOMES, "table": table(c.results),
                       "runs": c.results}, f, indent=1)
    if args.keep and any("kept" in r for r in c.results):
        print("kept cases in %s" % c.kept_dir)
    else:
        shutil.rmtree(c.root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
