#!/usr/bin/env bash
# Learns the Furuta pendulum against its driver (examples/furuta/driver.py, lockstep):
# one `rig run --plant external` per seed, seeds FIRST..FIRST+RUNS-1, each against a
# driver of its own (examples/python_driver/seeds.sh). Writes OUT/seed-K/ (each run's
# directory), OUT/runs.csv (all returns, `run` = seed - 1, as `rig learn` writes them)
# and OUT/wall.csv (each run's wall time).
#
#   examples/furuta/experiment.sh OUT RUNS TRIALS [rig run flags...]
#   examples/furuta/experiment.sh out/furuta-mlac 5 600 --config examples/furuta/mlac-llr.toml
#
# PYTHON (default python3) must import rigkit with iceoryx2 0.10.0 (pip install
# "./python[driver]"); RIG (default the release build)
# is the rig; TASK (default furuta.toml next to this script) the task file; DAMPING
# (default the driver's, gym-brt) the model's damping set (furuta.py); FIRST (default 1)
# the first seed, so that several experiment.sh can share the seeds of one OUT.
set -euo pipefail
usage="usage: experiment.sh OUT RUNS TRIALS [rig run flags...]"
out=${1:?$usage} runs=${2:?$usage} trials=${3:?$usage}
shift 3
here=$(cd "$(dirname "$0")" && pwd)
"$here/../python_driver/seeds.sh" "$out" "$runs" "$trials" "${TASK:-$here/furuta.toml}" \
  "$here/driver.py" ${DAMPING:+--damping "$DAMPING"} -- "$@"
