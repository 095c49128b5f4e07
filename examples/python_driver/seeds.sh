#!/usr/bin/env bash
# One `rig run --plant external` per seed, seeds FIRST..FIRST+RUNS-1, each against a
# lockstep Python driver of its own, started as
# `PYTHON DRIVER DRIVER_ARGS... --task TASK --driver-id ID`
# (examples/acrobot/driver.py, examples/gymnasium/adapter.py --mapping M, ...). Writes
# OUT/seed-K/ (each run's directory), OUT/runs.csv (all returns, `run` = seed - 1, as
# `rig learn` writes them) and OUT/wall.csv (each run's wall time).
#
#   examples/python_driver/seeds.sh OUT RUNS TRIALS TASK DRIVER [DRIVER_ARGS...] [-- rig run flags...]
#   examples/python_driver/seeds.sh out/acrobot 5 400 examples/acrobot/acrobot.toml \
#     examples/acrobot/driver.py -- --algo mlac
#
# PYTHON (default python3) must import rigkit with iceoryx2 0.10.0 (pip install
# "./python[driver]"; and what the driver needs); RIG
# (default the release build) is the rig; FIRST (default 1) the first seed. OUT's
# runs.csv and wall.csv are appended to when they exist. A run that fails stops the
# script, and its driver with it.
set -euo pipefail
if [ $# -lt 5 ]; then
  sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
out=$1 runs=$2 trials=$3 task=$4
shift 4
driver=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do driver+=("$1"); shift; done
[ $# -gt 0 ] && shift # the "--"
here=$(cd "$(dirname "$0")" && pwd)
python=${PYTHON:-python3}
rig=${RIG:-$here/../../target/release/rig}
mkdir -p "$out"
[ -f "$out/runs.csv" ] || echo "run,trial,sim_time_s,return,greedy_return" > "$out/runs.csv"
[ -f "$out/wall.csv" ] || echo "seed,wall_s" > "$out/wall.csv"
first=${FIRST:-1}
pid=
trap '[ -z "$pid" ] || { kill "$pid"; wait "$pid"; } 2>/dev/null || true' EXIT
for seed in $(seq "$first" $((first + runs - 1))); do
  id="seeds-$$-$seed"
  "$python" "${driver[@]}" --task "$task" --driver-id "$id" &
  pid=$!
  start=$(date +%s%N)
  "$rig" run --plant external --driver "$id" --task "$task" --seed "$seed" \
    --trials "$trials" --quiet --out "$out/seed-$seed" "$@"
  end=$(date +%s%N)
  kill "$pid"; wait "$pid" || true
  pid=
  echo "$seed,$(( (end - start) / 1000000 ))e-3" >> "$out/wall.csv"
  tail -n +2 "$out/seed-$seed/returns.csv" | sed "s/^0,/$((seed - 1)),/" >> "$out/runs.csv"
  echo "seed $seed: $(tail -n 1 "$out/seed-$seed/returns.csv")"
done
