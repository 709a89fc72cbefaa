#!/usr/bin/env bash
# `hairrig batch` timings. Run from the repository root after building:
#   bench/batch_bench.sh [CAPTURES] [JOBS]
#
# 1. The local engine's archive throughput: CAPTURES fresh captures of the
#    batch tests' rig (tests/data/batch_rig.yaml: 16 views of 300 x 400, a
#    4,000-strand wig) through every stage with the local engine, 2 captures
#    at once, with the stage options of bench/batch_bench_options.json;
#    captures per hour on this machine. Give HAIRRIG_BENCH_RIG=etc/sim-rig.yaml
#    and HAIRRIG_BENCH_OPTIONS=<file> for full-size captures.
# 2. Slurm's overhead per stage job, on a private single-node cluster on
#    127.0.0.1 (tests/support/private_slurm.sh; needs root and the Slurm
#    packages, else this part is skipped): JOBS trivial stage jobs (`hairrig
#    stage fit` on copies of a processed capture: unchanged inputs, so the stage
#    only hashes them and skips) run directly one after another, then as one
#    job array through Slurm one element at a time (--max-parallel 1), then all
#    four stages as four arrays chained by aftercorr. The difference per job is
#    what Slurm adds: submission, scheduling, launch, and the batch's polling.
set -euo pipefail
captures="${1:-4}"
jobs="${2:-10}"
hairrig="${HAIRRIG:-build/cli/hairrig}"
rig="${HAIRRIG_BENCH_RIG:-tests/data/batch_rig.yaml}"
options="${HAIRRIG_BENCH_OPTIONS:-bench/batch_bench_options.json}"
hairrig="$(cd "$(dirname "$hairrig")" && pwd)/$(basename "$hairrig")"
work="$(mktemp -d /tmp/hairrig_batch_bench_XXXXXX)"
chmod 0755 "$work"  # munged wants every folder above its socket searchable by all
cluster=""
cleanup() {
  if [ -n "$cluster" ]; then bash tests/support/private_slurm.sh stop "$cluster" || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

now() { date +%s.%N; }
# awk arithmetic: calc 'expression' (with a, b, c, d set from the arguments after it)
calc() { awk -v a="${2:-0}" -v b="${3:-0}" -v c="${4:-0}" -v d="${5:-0}" "BEGIN { printf \"%.3f\", $1 }"; }

echo "batch_bench: $captures captures of $rig, stage options $options, $(nproc) cores"
for k in $(seq 1 "$captures"); do
  "$hairrig" --log-level warning capture --config "$rig" --out "$work/archive/cap$k" >/dev/null
done
start=$(now)
"$hairrig" --log-level warning batch submit --batch "$work/local_batch" --captures "$work/archive" \
  --engine local --max-parallel 2 --stage-options "$options" >/dev/null
local_s=$(calc 'b - a' "$start" "$(now)")
echo "local engine: $captures captures through every stage in $local_s s:" \
  "$(calc '3600 * a / b' "$captures" "$local_s") captures per hour (2 at once)"
"$hairrig" batch report --batch "$work/local_batch" | tail -n 1

mkdir -p "$work/copies"
for k in $(seq 1 "$jobs"); do cp -r "$work/archive/cap1" "$work/copies/cap$k"; done
start=$(now)
for k in $(seq 1 "$jobs"); do
  "$hairrig" --log-level warning stage fit --capture "$work/copies/cap$k" --options "$options" >/dev/null
done
direct_s=$(calc '(b - a) / c' "$start" "$(now)" "$jobs")
start=$(now)
for k in $(seq 1 "$jobs"); do
  for stage in calibrate reconstruct fit simulate; do
    "$hairrig" --log-level warning stage "$stage" --capture "$work/copies/cap$k" --options "$options" >/dev/null
  done
done
direct_chain_s=$(calc '(b - a) / c' "$start" "$(now)" "$jobs")
echo "directly: a skipped fit stage $direct_s s per job; the four skipped stages $direct_chain_s s per capture"

set +e
started=$(bash tests/support/private_slurm.sh start "$work/cluster")
status=$?
set -e
if [ $status -eq 77 ]; then
  echo "Slurm part skipped (see above)"
  exit 0
fi
[ $status -eq 0 ] || exit $status
cluster="$work/cluster"
export "${started?}"
start=$(now)
"$hairrig" --log-level warning batch submit --batch "$work/slurm_fit" --captures "$work/copies" --engine slurm \
  --stages fit --max-parallel 1 --stage-options "$options" >/dev/null
"$hairrig" --log-level warning batch wait --batch "$work/slurm_fit" --poll 0.2 >/dev/null
slurm_s=$(calc '(b - a) / c' "$start" "$(now)" "$jobs")
echo "through Slurm, one element at a time: $slurm_s s per job: Slurm adds $(calc 'a - b' "$slurm_s" "$direct_s") s per job"
start=$(now)
"$hairrig" --log-level warning batch submit --batch "$work/slurm_chain" --captures "$work/copies" --engine slurm \
  --max-parallel 1 --stage-options "$options" >/dev/null
"$hairrig" --log-level warning batch wait --batch "$work/slurm_chain" --poll 0.2 >/dev/null
chain_s=$(calc '(b - a) / c' "$start" "$(now)" "$jobs")
echo "through Slurm, four arrays chained by aftercorr, one element of each at a time (so the stages of" \
  "successive captures overlap): $chain_s s per capture against $direct_chain_s s directly"
"$hairrig" batch report --batch "$work/slurm_chain" | tail -n 1
