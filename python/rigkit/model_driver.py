"""The command line of a driver for one simulated model (examples/acrobot/,
examples/furuta/): the driver id, the task file (checked for the model's shape), the
clock — lockstep (lockstep.serve, the default) or realtime (clocked.serve_realtime,
`--speed`, `--realtime-priority`, `--cpu-wakeup-us`) —, --verbose and the model's own
options; it serves until SIGTERM or Ctrl-C.

    from rigkit.model_driver import run
    run(__doc__, lambda args: Acrobot(), default_task=HERE / "acrobot.toml", shape=(4, 1), what="acrobot")
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import script
from .realtime import MAX_WAKEUP_US, check_driver_id, timing
from .task import Task, TaskError

if TYPE_CHECKING:
    from .lockstep import Simulation


def run(
    doc: str,
    simulation: Callable[[argparse.Namespace], Simulation],
    default_task: Path,
    shape: tuple[int, int],
    what: str | Callable[[argparse.Namespace], str],
    options: Sequence[tuple[str, dict[str, Any]]] = (),
) -> int:
    """Parses the command line described by `doc` and serves the model `simulation(args)`
    makes from the parsed arguments (n states and m actions, `shape`) for the task file
    given, until a signal. `options` are the model's own flags, `(flag, keywords of
    argparse's add_argument)` pairs; `what` names the model, a string or a function of
    the parsed arguments. Ends in one line if iceoryx2 is not installed."""
    script.need(Path(sys.argv[0]).name, modules=["iceoryx2"])
    from .lockstep import Services
    from .serving import serve_until_signalled

    p = parser(doc, default_task, shape)
    for flag, keywords in options:
        p.add_argument(flag, **keywords)
    p.add_argument("--verbose", action="store_true", help="log resets (realtime: and rejected commands, watchdog trips, missed periods) to stderr")
    args = p.parse_args()
    task, driver_id = task_and_driver_id(p, args.task, args.driver_id)
    if (task.n, task.m) != tuple(shape):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not {shape[0]} and {shape[1]}")
    check_clock(p, args)
    name = what(args) if callable(what) else what
    clock = "lockstep" if args.clock == "lockstep" else f"realtime, a sample every {task.ts / args.speed * 1e3:g} ms of wall time (speed {args.speed:g})"
    print(f"driver {driver_id!r}: task {task.name} ({name}), Ts {task.ts * 1e3:g} ms, {clock}", file=sys.stderr, flush=True)
    try:
        limit = timing(args.realtime_priority, args.cpu_wakeup_us)
    except RuntimeError as e:
        print(f"driver: {e}", file=sys.stderr)
        return 1
    speed = args.speed if args.clock == "realtime" else None
    serve_until_signalled(Services(driver_id), task, simulation(args), "driver", args.verbose, speed)
    if limit is not None:
        limit.close()
    return 0


def parser(doc: str, default_task: Path, shape: tuple[int, int]) -> argparse.ArgumentParser:
    """The flags every model driver has: the driver id, the task file, the clock."""
    p = argparse.ArgumentParser(description=" ".join(doc.split("\n\n")[0].split()))
    p.add_argument(
        "--driver-id",
        help="services rig/driver/ID/...; letters, digits, '-' and '_' [default: the task's name]",
    )
    p.add_argument(
        "--task",
        default=str(default_task),
        help=f"the task file served: {shape[0]} states and {shape[1]} action(s) [default: {default_task.name} next to the driver]",
    )
    p.add_argument(
        "--clock",
        choices=["lockstep", "realtime"],
        default="lockstep",
        help="lockstep: sample k+1 only once the action for sample k arrived, as fast as the rig "
        "answers, the same samples every time; realtime: a sample every Ts / S of wall time "
        "whether or not actions arrive, each action applied from its arrival, the watchdog, a "
        "reset placing the model at its start state at the next sample instant, as a stand-in "
        "for hardware [default: lockstep]",
    )
    p.add_argument(
        "--speed",
        type=float,
        metavar="S",
        default=1.0,
        help="realtime: S times faster than real time, in (0, 1000], advertised as time_scale S [default: 1]",
    )
    p.add_argument(
        "--realtime-priority",
        type=int,
        metavar="N",
        help="run with SCHED_FIFO priority N (1-99), so that a loaded machine does not delay the "
        "sample instants by milliseconds; needs CAP_SYS_NICE (or root) [default: normal scheduling]",
    )
    p.add_argument(
        "--cpu-wakeup-us",
        type=int,
        metavar="US",
        help="hold the machine's CPU wake-up latency limit at US microseconds while the driver "
        "runs (Linux PM QoS, /dev/cpu_dma_latency; 0 keeps idle CPUs polling); needs root "
        "[default: the operating system's choice]",
    )
    return p


def check_clock(p: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """The parser's error for a speed out of range, or given in lockstep."""
    if not (math.isfinite(args.speed) and 0.0 < args.speed <= 1000.0):
        p.error(f"--speed {args.speed}: must be in (0, 1000]")
    if args.clock == "lockstep" and args.speed != 1.0:
        p.error("--speed applies to the realtime clock only (--clock realtime)")
    if args.cpu_wakeup_us is not None and not 0 <= args.cpu_wakeup_us <= MAX_WAKEUP_US:
        p.error(f"--cpu-wakeup-us {args.cpu_wakeup_us}: must be in [0, {MAX_WAKEUP_US}]")


def task_and_driver_id(p: argparse.ArgumentParser, path: str, driver_id: str | None) -> tuple[Task, str]:
    """The task file at `path` (`--task`) and the driver id, `driver_id` (`--driver-id`)
    or else the task's name; the parser's error if either is bad."""
    try:
        task = Task.read(path)
    except TaskError as e:
        p.error(f"--task: {e}")
    chosen = driver_id or task.name.replace(".", "-")
    try:
        check_driver_id(chosen)
    except ValueError as e:
        p.error(f"--driver-id {e}")
    return task, chosen
