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
"""

from __future__ import annotations

import ctypes
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
            counters.admit(task, c)
            if counters.rejected != before:
                return f"rejected action {c.seq}: n_u {c.n_u}, u {list(c.u[: task.m])}"
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
        """A sample instant's decisions: the reset completed, or the watchdog."""
        counters = self.counters
        if counters.status & RESETTING and self.reset_to is not None:
            self.simulation.place(self.reset_to)
            counters.status, counters.u = READY, [0.0] * self.task.m
            self.reset_to, self.acted, self.acted_since_reset = None, False, False
            return
        if counters.status & READY:
            engage = self.acted_since_reset and not self.acted and not counters.status & WATCHDOG
            self.acted = False
            if engage:
                counters.status |= WATCHDOG
                counters.u = [0.0] * self.task.m
                self.watchdog_trips += 1


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
) -> None:
    """Serves `simulation` as the driver of `task` on the realtime clock, `speed` times
    faster than real time, until `stopping()`; `log(text)`, if given, is told of resets,
    rejected commands, watchdog trips and missed periods. `clock` is the monotonic clock
    (another only to test the timing)."""
    if not (math.isfinite(speed) and 0.0 < speed <= 1000.0):
        raise ValueError(f"speed {speed}: must be in (0, 1000]")
    t_start = clock()
    period = round(task.ts / speed * 1e9)
    driver = Clocked(task, simulation, speed, t_start)
    advertised = info(task, REALTIME, t_start, speed)

    def drain() -> None:
        while (c := services.take()) is not None:
            said = driver.command(c, clock())
            if said and log:
                log(said)

    seq, next_info, next_count, readers = 0, t_start, t_start, services.info_readers()
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
        seq += 1
        services.sleep_until(t_start + seq * period, drain, stopping)
        late = (clock() - (t_start + seq * period)) // period
        if late > 0:  # woken a period late or more: those periods were missed
            seq += late
            if log:
                log(f"missed {late} period(s)")
