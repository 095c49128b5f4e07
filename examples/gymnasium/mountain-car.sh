#!/usr/bin/env bash
# MountainCarContinuous-v0 learned through the adapter, the environment's own reward and
# endings, with the rules' MLAC/LLR preset (no configuration file): RUNS seeds (default 5)
# of TRIALS trials (default the preset's 400), one `rig run --plant external` each
# (examples/python_driver/seeds.sh), then the per-seed table of
# docs/results/gymnasium.md (bench/python/seeds_report.py: a seed succeeds if its last
# greedy return, the mean over the task's three start states, is at least Gymnasium's
# reward threshold, 90).
#
#   examples/gymnasium/mountain-car.sh OUT [RUNS] [TRIALS] [-- rig run flags...]
#
# PYTHON (default python3) must import rigkit with iceoryx2 0.10.0, gymnasium 1.4.0 and
# mcap (pip install "./python[gymnasium,recording]").
set -euo pipefail
out=${1:?usage: mountain-car.sh OUT [RUNS] [TRIALS] [-- rig run flags...]}
runs=${2:-5} trials=${3:-400}
shift $(( $# < 3 ? $# : 3 ))
[ "${1:-}" = "--" ] && shift
here=$(cd "$(dirname "$0")" && pwd)
"$here/../python_driver/seeds.sh" "$out" "$runs" "$trials" "$here/mountain-car-continuous.toml" \
  "$here/adapter.py" --mapping "$here/mountain_car_continuous.py" -- "$@"
"${PYTHON:-python3}" "$here/../../bench/python/seeds_report.py" "$out" --return-at-least 90 | tee "$out/table.md"
