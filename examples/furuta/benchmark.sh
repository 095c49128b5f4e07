#!/usr/bin/env bash
# Reproduces the tables of docs/results/furuta.md's "Planning with the learned model"
# section in one command: each learner on each Furuta task, RUNS seeds (default 5)
# against drivers of their own (experiment.sh), then bench/python/furuta_report.py's
# tables and per-run verdicts ("swings up and balances") into OUT/report.md.
#
#   examples/furuta/benchmark.sh OUT [RUNS]
#
# PYTHON (default python3) must import iceoryx2 0.10.0, mcap and matplotlib; RIG
# (default the release build) is the rig.
set -euo pipefail
out=$1 runs=${2:-5}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
python=${PYTHON:-python3}
e=$here/experiment.sh
mkdir -p "$out"
bal=$here/furuta-balance.toml
swing=$here/furuta.toml
TASK=$bal "$e" "$out/bal-mlac" "$runs" 800 --config "$here/mlac-llr.toml"
TASK=$bal "$e" "$out/bal-plan" "$runs" 60 --config "$here/mlac-plan.toml"
TASK=$swing "$e" "$out/swing-plan" "$runs" 150 --config "$here/mlac-plan.toml"
{
  echo "## balance (furuta-balance.toml)"
  "$python" "$root/bench/python/furuta_report.py" "$out/bal" \
    mlac-llr="$out/bal-mlac" mlac-plan="$out/bal-plan"
  echo "## swing-up and balance (furuta.toml)"
  "$python" "$root/bench/python/furuta_report.py" "$out/swing" mlac-plan="$out/swing-plan"
} | tee "$out/report.md"
