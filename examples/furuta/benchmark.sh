#!/usr/bin/env bash
# Reproduces the tables of docs/results/furuta.md's "Balance, 5 seeds per configuration"
# in one command: MLAC/LLR on furuta-balance.toml with mlac-llr.toml, two variants of it
# (learning rates halved; and exploration sigma 1 V), mlac-llr-decay.toml (its rates
# decaying over the trials) and mlac-llr-two-timescale.toml (the actor's rate decaying
# faster, the critic's more slowly), RUNS seeds each (default 5),
# each seed against a driver of its own (experiment.sh), TRIALS trials (default 800); then
# bench/python/furuta_report.py's per-seed tables and verdicts into OUT/report.md. Flags
# after `--` go to every `rig run` (a short look: `OUT 1 4 -- --eval-every 2`).
#
#   examples/furuta/benchmark.sh OUT [RUNS] [TRIALS] [-- rig run flags...]
#
# PYTHON (default python3) must import rigkit (pip install "./python[driver,recording]"),
# iceoryx2 0.10.0, mcap and matplotlib; RIG (default the release build) is the rig.
set -euo pipefail
usage="usage: benchmark.sh OUT [RUNS] [TRIALS] [-- rig run flags...]"
out=${1:?$usage} runs=${2:-5} trials=${3:-800}
shift $(( $# < 3 ? $# : 3 ))
[ "${1:-}" = "--" ] && shift
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
python=${PYTHON:-python3}
e=$here/experiment.sh
mkdir -p "$out"
# The variants: mlac-llr.toml with the values named.
halved=$out/mlac-llr-halved.toml sigma1=$out/mlac-llr-halved-sigma1.toml
sed -e 's/^alpha = 0.02$/alpha = 0.01/' -e 's/^alpha = 0.15$/alpha = 0.1/' "$here/mlac-llr.toml" > "$halved"
sed -e 's/^gamma = 0.99$/gamma = 0.99\nsigma = 1.0/' "$halved" > "$sigma1"
bal=$here/furuta-balance.toml
TASK=$bal "$e" "$out/bal-mlac-llr" "$runs" "$trials" --config "$here/mlac-llr.toml" "$@"
TASK=$bal "$e" "$out/bal-halved" "$runs" "$trials" --config "$halved" "$@"
TASK=$bal "$e" "$out/bal-halved-sigma1" "$runs" "$trials" --config "$sigma1" "$@"
TASK=$bal "$e" "$out/bal-decay" "$runs" "$trials" --config "$here/mlac-llr-decay.toml" "$@"
TASK=$bal "$e" "$out/bal-two-timescale" "$runs" "$trials" --config "$here/mlac-llr-two-timescale.toml" "$@"
{
  echo "## balance (furuta-balance.toml)"
  "$python" "$root/bench/python/furuta_report.py" "$out/bal" mlac-llr="$out/bal-mlac-llr" \
    halved="$out/bal-halved" halved-sigma1="$out/bal-halved-sigma1" decay="$out/bal-decay" \
    two-timescale="$out/bal-two-timescale"
} | tee "$out/report.md"
