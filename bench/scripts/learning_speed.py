#!/usr/bin/env python3
"""How fast learning curves reach their final level, from `rig learn` output directories.

Usage: learning_speed.py DIR [DIR ...] [--levels L1,L2,...]

For each DIR (holding runs.csv) the learning curve is the mean over runs of each trial's
return (with exploration, as the thesis's Figures 5.5 and 5.9 plot it), smoothed by a
10-trial moving mean. Printed per DIR:

* final level: the mean of the curve over the last 10 % of trials;
* reaches: the first trial at which the smoothed curve is within 10 % of the final level,
  in trials and in simulated minutes;
* stays: the first trial from which it stays within 10 % until the end;
* with --levels: the simulated minutes until the smoothed curve first reaches each
  common level (the same levels for every DIR, to compare learners on equal terms).
"""
import importlib.util
import statistics as st
import sys
from collections import defaultdict

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: learning_speed.py needs the rig's Python package rigkit: pip install ./python")

from rigkit import returns  # noqa: E402
from rigkit.script import fail  # noqa: E402


def curve(d):
    ret, sim_end = defaultdict(list), defaultdict(list)
    for row in returns.read(f"{d}/runs.csv"):
        ret[row.trial].append(row.ret)
        sim_end[row.trial].append(row.sim_time_s)
    trials = sorted(ret)
    mean = [st.mean(ret[t]) for t in trials]
    smooth = [st.mean(mean[max(0, i - 9) : i + 1]) for i in range(len(mean))]
    minutes = [st.mean(sim_end[t]) / 60 for t in trials]
    return trials, mean, smooth, minutes


def main(argv):
    levels = []
    dirs = []
    it = iter(argv)
    for a in it:
        if a == "--levels":
            levels = [float(v) for v in next(it).split(",")]
        else:
            dirs.append(a)
    if not dirs or "-h" in dirs or "--help" in dirs:
        sys.exit(__doc__)
    for d in dirs:
        try:
            trials, mean, smooth, minutes = curve(d)
        except returns.ReturnsError as e:
            fail("learning_speed.py", str(e))
        n = len(trials)
        final = st.mean(mean[-max(1, n // 10) :])
        tol = 0.1 * abs(final)
        reach = next(i for i in range(n) if abs(smooth[i] - final) <= tol)
        stay = next(i for i in range(n) if all(abs(v - final) <= tol for v in smooth[i:]))
        line = (
            f"{d}: final {final:.0f}; reaches at trial {trials[reach]} "
            f"({minutes[reach]:.1f} min); stays from trial {trials[stay]} ({minutes[stay]:.1f} min)"
        )
        for level in levels:
            i = next((i for i, v in enumerate(smooth) if v >= level), None)
            line += f"; {level:.0f}: " + ("never" if i is None else f"{minutes[i]:.1f} min")
        print(line)


if __name__ == "__main__":
    main(sys.argv[1:])
