"""A driver for any simulator on the realtime clock (docs/driver.md, "What the driver
does"): the same simulation as rigkit.lockstep's, sampled every period of wall time
whether or not actions arrive, as a stand-in for hardware.

    from rigkit.clocked import serve_realtime
    serve_realtime(Services(driver_id), task, simulation, speed=1.0)

At every sample instant `t_k = t_start + k * period` of the monotonic clock (period =
Ts / speed; late if it must, never early; periods woken a whole period late are
skipped, the gap in `seq` showing the miss) it integrates the simulation up to now
with the action in effect, publishes the sample, then decides:

- resetting: the simulation has no brake of its own, so a RESET is completed at the
  first sample instant after it arrives by placing the system at rest at x0 (`place`):
  that sample is READY at x0, the action zero from then on;
- ready: the watchdog of docs/driver.md (no accepted action during a whole period,
  after at least one since the reset: zero from this instant on, WATCHDOG, one trip).

Between instants each command is handled at its arrival, the simulation integrated up
to it with the old action first (`step(u, dt)` piecewise): an ACTION while READY is
clamped to the task's bounds and applied from then on, or, non-finite or of the wrong
size, rejected (zero at once, not an action for the watchdog); a RESET (n_x, finite x0)
starts a reset and keeps the old action until the next instant; anything else is
counted as rejected. A simulation that provides its own reward is served in lockstep
only (its outcome is one step's, and a period here is several steps).

A driver of its own subclasses Clocked (`serve_realtime(..., clocked=...)`) where it
differs: `reset` (a brake to rest at x0 instead of placing), `admit`, `watchdog_due`,
`next_instant` — examples/python_driver/driver.py's Motor brakes the pendulum and
misbehaves on purpose (--inject-fault) through them.
"""

from __future__ import annotations

import ctypes
import gc
import math
import time
from collections.abc import Callable
from typing import Protocol

from .lockstep import Counters, Samples, Simulation, info
from .messages import ACTION, READY, REALTIME, RESET, RESETTING, WATCHDOG, DriverCommand, DriverSample
from .task import Task

# How often the info's subscribers are counted, to tell a new rig the info at once [ns].
READERS_EVERY_NS = 50_000_000


class Clocked:
    """The driver's state between sample instants: the simulation, the action in effect,
    the reset and the watchdog. Times are monotonic nanoseconds; `speed` simulated
    seconds pass per second of them."""

    def __init__(self, task: Task, simulation: Simulation, speed: float, t_start: int) -> None:
        if getattr(simulation, "provides_reward", False):
            raise ValueError("a simulation that provides its own reward is served in lockstep only")
        self.task, self.simulation, self.speed = task, simulation, speed
        self.period_ns = round(task.ts / speed * 1e9)
        self.counters = Counters(task.m)
        self.samples = Samples(task)
        self.t_sim = t_start  # the monotonic time the simulation has reached
        self.reset_to: list[float] | None = None  # x0 of the reset in progress
        self.acted = False  # an action was accepted during this period
        self.acted_since_reset = False
        self.watchdog_trips = 0

    def advance(self, t: int) -> None:
        """Integrates the simulation up to monotonic time `t` with the action in effect."""
        if t > self.t_sim:
            self.simulation.step(self.counters.u, (t - self.t_sim) * 1e-9 * self.speed)
            self.t_sim = t

    def command(self, c: DriverCommand, t: int) -> str | None:
        """Handles command `c` arriving at monotonic time `t`; what to log, if anything."""
        self.advance(t)
        counters, task = self.counters, self.task
        if c.kind == ACTION and counters.status & READY:
            before = counters.rejected
            self.admit(c)
            if counters.rejected != before:
                return f"rejected action {c.seq}: n_u {c.n_u}, u {list(c.u[: task.m])}"
            if counters.last_command == c.seq:
                self.acted = self.acted_since_reset = True
                counters.status &= ~WATCHDOG
            return None
        if c.kind == RESET:
            x0 = list(c.x0[: task.n])
            if c.n_x != task.n or not all(map(math.isfinite, x0)):
                counters.rejected += 1
                return f"rejected reset {c.seq}: n_x {c.n_x}, x0 {x0}"
            counters.status, counters.reset_id = RESETTING, c.seq
            self.reset_to = x0
            return f"reset {c.seq} to {x0}"
        counters.rejected += 1  # an action before a reset or while resetting, or unknown
        return None

    def sample(self, seq: int, t: int) -> DriverSample:
        """Sample `seq` at monotonic time `t`: the state and the action in effect until
        `t`, with the status after this instant's decisions (valid until the next one)."""
        self.advance(t)
        u_before = list(self.counters.u)
        self.decide()
        s = self.samples.fill(self.counters, seq, self.simulation.state())
        s.u_applied[: self.task.m] = u_before
        s.watchdog_trips = self.watchdog_trips
        s.t_sample_ns = t
        return s

    def decide(self) -> None:
        """A sample instant's decisions: the reset's progress, or the watchdog."""
        counters = self.counters
        if counters.status & RESETTING and self.reset_to is not None:
            if self.reset(self.reset_to):
                counters.status, counters.u = READY, [0.0] * self.task.m
                self.reset_to, self.acted, self.acted_since_reset = None, False, False
            return
        if counters.status & READY:
            engage = self.watchdog_due() and not counters.status & WATCHDOG
            self.acted = False
            if engage:
                counters.status |= WATCHDOG
                counters.u = [0.0] * self.task.m
                self.watchdog_trips += 1

    # What a driver of its own (examples/python_driver/driver.py: a brake, and faults to
    # show `rig check-driver` failing) may do otherwise.

    def admit(self, c: DriverCommand) -> None:
        """An ACTION while READY: clamped to the bounds and applied (`last_command` its
        seq), or rejected (zero, counted)."""
        self.counters.admit(self.task, c)

    def reset(self, x0: list[float]) -> bool:
        """A sample instant of the reset to `x0`: True once it is done (READY from this
        instant, the action zero). Without a brake, the model is placed at x0 at once; a
        driver with one sets the braking action (`counters.u`) until the system rests."""
        self.simulation.place(x0)
        return True

    def watchdog_due(self) -> bool:
        """Whether the watchdog engages at this instant: an action accepted since the
        reset, none during the period this instant closes (`watchdog_periods` 1)."""
        return self.acted_since_reset and not self.acted

    def next_instant(self, seq: int, t_sample: int) -> int | None:
        """The instant to wait for after sample `seq` taken at `t_sample`; None: the
        next instant of the absolute grid, `t_start + (seq + 1) * period`, skipping
        the periods woken too late for."""
        return None


class Link(Protocol):
    """What serve_realtime needs of the services (rigkit.lockstep.Services)."""

    def publish_sample(self, sample: DriverSample) -> None: ...

    def publish_info(self, info: ctypes.Structure) -> None: ...

    def info_readers(self) -> int: ...

    def take(self) -> DriverCommand | None: ...

    def sleep_until(
        self, deadline: int, on_wake: Callable[[], None], stopping: Callable[[], bool] = ...
    ) -> None: ...


def serve_realtime(
    services: Link,
    task: Task,
    simulation: Simulation,
    speed: float = 1.0,
    stopping: Callable[[], bool] = lambda: False,
    log: Callable[[str], None] | None = None,
    clock: Callable[[], int] = time.monotonic_ns,
    clocked: Callable[[Task, Simulation, float, int], Clocked] = Clocked,
) -> None:
    """Serves `simulation` as the driver of `task` on the realtime clock, `speed` times
    faster than real time, until `stopping()`; `log(text)`, if given, is told of resets,
    rejected commands, watchdog trips and missed periods. `clock` is the monotonic clock
    (another only to test the timing); `clocked(task, simulation, speed, t_start)` makes
    the driver's state (a subclass of Clocked for a driver of its own).

    The objects alive when serving begins (the imports, the simulation, the services) are
    moved out of the garbage collector's reach (`gc.freeze`): a full collection would
    otherwise scan all of them, milliseconds within some period."""
    if not (math.isfinite(speed) and 0.0 < speed <= 1000.0):
        raise ValueError(f"speed {speed}: must be in (0, 1000]")
    t_start = clock()
    driver = clocked(task, simulation, speed, t_start)
    period = driver.period_ns
    advertised = info(task, REALTIME, t_start, speed)

    def drain() -> None:
        while (c := services.take()) is not None:
            said = driver.command(c, clock())
            if said and log:
                log(said)

    seq, next_info, next_count, readers = 0, t_start, t_start, services.info_readers()
    gc.collect()
    gc.freeze()  # the heap built so far is never scanned again: no long collection in a period
    while not stopping():
        now = clock()
        trips = driver.watchdog_trips
        services.publish_sample(driver.sample(seq, now))
        if log and driver.watchdog_trips != trips:
            log("watchdog: no action for a period, applying zero")
        if now >= next_count:
            counted, next_count = services.info_readers(), now + READERS_EVERY_NS
            if counted != readers:
                next_info = now  # a rig subscribed (or left): the info at once
            readers = counted
        if now >= next_info:
            advertised.t_publish_ns = clock()
            services.publish_info(advertised)
            next_info = now + 1_000_000_000
        chosen = driver.next_instant(seq, now)
        seq += 1
        if chosen is not None:
            services.sleep_until(chosen, drain, stopping)
            continue
        services.sleep_until(t_start + seq * period, drain, stopping)
        late = (clock() - (t_start + seq * period)) // period
        if late > 0:  # woken a period late or more: those periods were missed
            seq += late
            if log:
                log(f"missed {late} period(s)")
