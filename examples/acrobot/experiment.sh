#!/usr/bin/env bash
# The acrobot learned against its driver (driver.py, lockstep): RUNS seeds (default 5) of
# TRIALS trials (default the preset's), one `rig run --plant external` each
# (examples/python_driver/seeds.sh), then the per-seed table of docs/results/acrobot.md
# (bench/python/seeds_report.py: a seed succeeds if its last greedy trial, from each
# start state, runs its full length and its last 1.5 s keep both angles within 0.3 rad of
# upright).
#
#   examples/acrobot/experiment.sh OUT TASK [RUNS] [TRIALS] [-- rig run flags...]
#   examples/acrobot/experiment.sh out/acrobot examples/acrobot/acrobot.toml 5 400 -- --algo mlac
#
# PYTHON (default python3) must import rigkit with iceoryx2 0.10.0 and mcap
# (pip install "./python[driver,recording]").
set -euo pipefail
usage="usage: experiment.sh OUT TASK [RUNS] [TRIALS] [-- rig run flags...]"
out=${1:?$usage} task=${2:?$usage}
runs=${3:-5} trials=${4:-400}
shift $(( $# < 4 ? $# : 4 ))
[ "${1:-}" = "--" ] && shift
here=$(cd "$(dirname "$0")" && pwd)
"$here/../python_driver/seeds.sh" "$out" "$runs" "$trials" "$task" "$here/driver.py" -- "$@"
"${PYTHON:-python3}" "$here/../../bench/python/seeds_report.py" "$out" --upright 0.3 --hold 1.5 | tee "$out/table.md"
