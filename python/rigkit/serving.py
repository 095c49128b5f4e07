"""A driver served until it is told to stop: in lockstep (rigkit.lockstep.serve) or, with
a speed, on the realtime clock (rigkit.clocked.serve_realtime), until SIGTERM or Ctrl-C.

    from rigkit.lockstep import Services
    from rigkit.serving import serve_until_signalled
    serve_until_signalled(Services(driver_id), task, simulation, "cart", verbose=True)
"""

from __future__ import annotations

import signal
import sys

from .clocked import serve_realtime
from .lockstep import Services, Simulation, serve
from .task import Task


def serve_until_signalled(
    services: Services, task: Task, simulation: Simulation, who: str, verbose: bool,
    speed: float | None = None,
) -> None:
    """serve() until SIGTERM or Ctrl-C, logging resets to stderr as `who` if `verbose`;
    with a `speed`, rigkit.clocked.serve_realtime at that speed instead."""
    stopping: list[bool] = []
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stopping.append(True))

    def log(text: str) -> None:
        print(f"{who}: {text}", file=sys.stderr, flush=True)

    told = log if verbose else None
    if speed is None:
        serve(services, task, simulation, lambda: bool(stopping), told)
    else:
        serve_realtime(services, task, simulation, speed, lambda: bool(stopping), told)
    print(f"{who}: stopped", file=sys.stderr)
