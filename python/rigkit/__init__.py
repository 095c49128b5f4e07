"""rigkit: the rig's Python side.

Modules, each importable on its own (only those that talk to the rig need iceoryx2):

* `angle` — angles wrapped to [-pi, pi) as the rig wraps them;
* `messages` — the driver contract's messages as ctypes structures (docs/driver.md);
* `reward`, `task` — task files (docs/tasks.md): the reader, the hash a driver
  advertises and the reward rho(x, u), the rig's numbers bit for bit;
* `lockstep` — serves any simulation as a driver in lockstep, over iceoryx2;
* `clocked` — serves the same simulation on the realtime clock (`serve_realtime`);
* `realtime` — a driver on real hardware: its id, real-time priority, CPU wake-ups;
* `model_driver` — the command line of a driver for one simulated model, lockstep or realtime;
* `adapter` — a Gymnasium environment served as a lockstep driver;
* `returns` — a run's returns.csv (and `rig learn`'s runs.csv);
* `recording` — a run's recording, run.mcap, with the official `mcap` reader;
* `seeds` — the folder of a seeds experiment (examples/python_driver/seeds.sh) judged
  seed by seed;
* `plots` — learning curves as the bench scripts draw them;
* `processes`, `script`, `hosts` — for scripts: child processes stopped as Ctrl-C stops
  them, what a script needs checked before it starts, helper threads whose failure ends
  it; hosts in network namespaces for the benchmarks across hosts.
"""
