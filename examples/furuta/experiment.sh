#!/usr/bin/env bash
# Learns the Furuta pendulum against its driver (examples/furuta/driver.py, lockstep):
# one `rig run --plant external` per seed, seeds 1..RUNS, each against a driver of its
# own. Writes OUT/seed-K/ (each run's directory), OUT/runs.csv (all returns, `run` =
# seed - 1, as `rig learn` writes them) and OUT/wall.csv (each run's wall time).
#
#   examples/furuta/experiment.sh OUT RUNS TRIALS [rig run flags...]
#   examples/furuta/experiment.sh out/furuta-mlac 5 400 --algo mlac --approx llr
#
# PYTHON (default python3) must import iceoryx2 0.10.0; RIG (default the release build)
# is the rig; TASK (default furuta.toml next to this script) the task file; DAMPING
# (default the driver's, gym-brt) the model's damping set (furuta.py); SEEDS (default
# 1..RUNS) the seeds to run, so that several experiment.sh can share the seeds of one.
set -euo pipefail
out=$1 runs=$2 trials=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
python=${PYTHON:-python3}
rig=${RIG:-$here/../../target/release/rig}
task=${TASK:-$here/furuta.toml}
mkdir -p "$out"
echo "run,trial,sim_time_s,return,greedy_return" > "$out/runs.csv"
echo "seed,wall_s" > "$out/wall.csv"
for seed in ${SEEDS:-$(seq 1 "$runs")}; do
  id="furuta-$$-$seed"
  "$python" "$here/driver.py" --driver-id "$id" --task "$task" ${DAMPING:+--damping "$DAMPING"} &
  driver=$!
  t0=$(date +%s%N)
  "$rig" run --plant external --driver "$id" --task "$task" --seed "$seed" \
    --trials "$trials" --quiet --out "$out/seed-$seed" "$@"
  t1=$(date +%s%N)
  kill "$driver"; wait "$driver" || true
  echo "$seed,$(( (t1 - t0) / 1000000 ))e-3" >> "$out/wall.csv"
  tail -n +2 "$out/seed-$seed/returns.csv" | sed "s/^0,/$((seed - 1)),/" >> "$out/runs.csv"
  echo "seed $seed: $(tail -n 1 "$out/seed-$seed/returns.csv")"
done
