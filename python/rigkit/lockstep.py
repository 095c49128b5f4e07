"""A driver for any simulator, in lockstep (docs/driver.md, "Lockstep"), over the official
iceoryx2 bindings: give it a task (task.py) and a simulation, and the rig can learn on it.

    from rigkit.lockstep import Services, serve
    serve(Services(driver_id), task, simulation)

The simulation is any object with

    place(x0)        put the system at rest at state x0 (a list of n floats)
    step(u, dt)      integrate dt seconds with the action u (m floats, within the bounds)
    state()          the state, n floats, angles wrapped to [-pi, pi)

and, if it computes the reward and the trial's endings itself (a Gymnasium environment),

    provides_reward  True: the info says so (PROVIDES_REWARD) and each sample that
                     closes a step carries them
    outcome()        (reward, terminated, truncated) of the last step: a finite float
                     and two bools (terminated wins if both are set)

A RESET places it at x0 and is answered by a READY sample there; an ACTION answering
the newest sample while READY is clamped to the task's bounds (or, non-finite or of the
wrong size, rejected: zero) and moves the simulation one sample period, answered by the
sample that closes it; any other action is only counted as rejected. The info goes out
at start, every second, and at once when a rig subscribes to it. `examples/acrobot/`, `examples/furuta/` and the
Gymnasium adapter (rigkit.adapter) are built on it.

Within a second of its last command the driver polls for the next one, handing the CPU
on between polls (os.sched_yield), as a lockstep run's processes do: a command reaches it
within microseconds instead of an operating-system wake-up. After a second without one
(the rig stopped, or went away) it sleeps until the rig wakes it. Each step reuses one
command and one sample structure: nothing is built, formatted or logged per step.
"""

from __future__ import annotations

import ctypes
import math
import os
import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import iceoryx2 as iox2

from .messages import (
    ACTION,
    LOCKSTEP,
    PROVIDES_REWARD,
    READY,
    RESET,
    TERMINATED,
    TRUNCATED,
    VERSION,
    DriverCommand,
    DriverInfo,
    DriverSample,
)
from .task import Task


# How long after a command the driver polls for the next one before it sleeps [ns].
POLL_AFTER_COMMAND_NS = 1_000_000_000

# (reward, terminated, truncated) of a step, from a simulation that provides them.
Outcome = tuple[float, bool, bool]


class Simulation(Protocol):
    """What `serve` drives (see above); `provides_reward` and `outcome()` optional."""

    def place(self, x0: list[float]) -> None: ...

    def step(self, u: list[float], dt: float) -> None: ...

    def state(self) -> Sequence[float]: ...



class Services:
    """A driver's three services with the settings of docs/driver.md, and its events.
    `sample_type` and `info_type` are the messages' ctypes structures (another layout
    only to test how a rig refuses it)."""

    def __init__(
        self, driver_id: str, sample_type: type[ctypes.Structure] = DriverSample,
        info_type: type[ctypes.Structure] = DriverInfo,
    ) -> None:
        self.driver_id = driver_id
        self.info_type = info_type
        self.command = DriverCommand()  # the command received last, overwritten by the next
        self.command_at = ctypes.addressof(self.command), ctypes.sizeof(DriverCommand)
        self.poll_until = 0  # monotonic time until which receive() polls [ns]
        iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
        self.node = (
            iox2.NodeBuilder.new()
            .name(iox2.NodeName.new(f"rig-driver-{driver_id}"))
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        self.info_service = self.pubsub("info", info_type)
        self.info_pub, self.info_note = self.publisher("info", info_type)
        self.sample_pub, self.sample_note = self.publisher("sample", sample_type)
        self.commands = self.pubsub("command", DriverCommand).subscriber_builder().create()
        self.command_events = (
            self.node.service_builder(self.name("command"))
            .event()
            .open_or_create()
            .listener_builder()
            .create()
        )
        self.waitset = (
            iox2.WaitSetBuilder.new()
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        self.command_guard = self.waitset.attach_notification(self.command_events)

    def name(self, topic: str) -> Any:
        return iox2.ServiceName.new(f"rig/driver/{self.driver_id}/{topic}")

    def pubsub(self, topic: str, payload: type[ctypes.Structure]) -> Any:
        # The settings every driver service uses (docs/driver.md, "Connecting").
        return (
            self.node.service_builder(self.name(topic))
            .publish_subscribe(payload)
            .max_publishers(1)
            .max_subscribers(8)
            .subscriber_max_buffer_size(256)
            .enable_safe_overflow(True)
            .open_or_create()
        )

    def publisher(self, topic: str, payload: type[ctypes.Structure]) -> tuple[Any, Any]:
        pub = self.pubsub(topic, payload).publisher_builder().create()
        notifier = (
            self.node.service_builder(self.name(topic))
            .event()
            .open_or_create()
            .notifier_builder()
            .create()
        )
        return pub, notifier

    def info_readers(self) -> int:
        """Subscribers to the info: a new one (a rig starting) is told the info at once."""
        return int(self.info_service.dynamic_config.number_of_subscribers)

    def publish_info(self, info: ctypes.Structure) -> None:
        self.info_pub.loan_uninit().write_payload(info).send()
        self.info_note.notify()

    def publish_sample(self, sample: ctypes.Structure) -> None:
        self.sample_pub.send_copy(sample)
        self.sample_note.notify()

    def receive(self, timeout_ms: int) -> DriverCommand | None:
        """The next command, or None after waiting up to `timeout_ms` for one: polled for
        within POLL_AFTER_COMMAND_NS of the last command, else waited for asleep. The
        command returned is `self.command`, overwritten by the next call."""
        c = self.commands.receive()
        if c is None:
            c = self.wait(time.monotonic_ns() + timeout_ms * 1_000_000)
            if c is None:
                return None
        self.poll_until = time.monotonic_ns() + POLL_AFTER_COMMAND_NS
        return self.copy(c)

    def take(self) -> DriverCommand | None:
        """The next command waiting, or None at once: `self.command`, overwritten by the
        next call (for a driver on its own clock, between its sample instants)."""
        c = self.commands.receive()
        return None if c is None else self.copy(c)

    def copy(self, c: Any) -> DriverCommand:
        """The received command `c` copied into `self.command`, its slot returned."""
        ctypes.memmove(self.command_at[0], c.payload_ptr, self.command_at[1])
        del c  # returns the slot
        return self.command

    def sleep_until(
        self, deadline: int, on_wake: Callable[[], None], stopping: Callable[[], bool] = lambda: False
    ) -> None:
        """Waits until monotonic time `deadline` [ns] (or `stopping()`), calling
        `on_wake()` each time a command may have arrived: for a driver on its own clock.

        The WaitSet wakes on a command within ~0.2 ms, but its timeout overshoots by up
        to several ms on a loaded machine (Listener.timed_wait's by ~8 ms always): the
        last 12 ms are slept in steps of 0.2 ms instead, polling between them."""
        while not stopping():
            now = time.monotonic_ns()
            if now >= deadline:
                return
            left = deadline - now
            if left > 13_000_000:
                self.waitset.wait_and_process_with_timeout(iox2.Duration.from_nanos(left - 12_000_000))
                self.command_events.try_wait()  # consume the wake-up
            else:
                time.sleep(min(left, 200_000) * 1e-9)
            on_wake()

    def wait(self, deadline: int) -> Any:
        """The next command's sample, or None at monotonic time `deadline` [ns]: polled
        for until `self.poll_until`, then waited for asleep until the rig wakes us."""
        receive, clock, pause = self.commands.receive, time.monotonic_ns, os.sched_yield
        now = clock()
        poll_end = min(self.poll_until, deadline)
        while now < poll_end:
            pause()
            c = receive()
            if c is not None:
                return c
            now = clock()
        if now >= deadline:
            return None
        self.waitset.wait_and_process_with_timeout(iox2.Duration.from_nanos(deadline - now))
        self.command_events.try_wait()  # consume the wake-up
        return receive()


def info(
    task: Task, clock: int, t_start: int, speed: float = 1.0, provides: int = 0,
    info_type: type[ctypes.Structure] = DriverInfo,
) -> Any:
    """The DriverInfo of a driver of `task`, `speed` times faster than real time,
    `provides` PROVIDES_REWARD or not (0)."""
    i = info_type(
        version=VERSION,
        task=task.name.encode(),
        task_hash=task.hash(),
        clock=clock,
        n_x=task.n,
        n_u=task.m,
        period_ns=round(task.ts / speed * 1e9),
        time_scale=speed,
        watchdog_periods=1,
        t_start_ns=t_start,
        t_publish_ns=time.monotonic_ns(),
        provides=provides,
    )
    for j in range(task.m):
        i.u_min[j], i.u_max[j] = task.low[j], task.high[j]
    return i


class Counters:
    """What the samples report besides the state."""

    def __init__(self, m: int) -> None:
        self.status = 0  # no reset yet
        self.reset_id = 0
        self.last_command = 0
        self.u = [0.0] * m
        self.clamped = 0
        self.rejected = 0

    def admit(self, task: Task, c: DriverCommand) -> None:
        """An action answering the newest sample while READY: clamped, or rejected."""
        u = c.u[: task.m]
        if c.n_u != task.m or not all(map(math.isfinite, u)):
            self.rejected += 1
            self.u = [0.0] * task.m  # the safe action
            return
        clamped = [min(max(v, lo), hi) for v, lo, hi in zip(u, task.low, task.high)]
        self.clamped += int(clamped != u)
        self.u = clamped
        self.last_command = c.seq


class Samples:
    """The samples of a driver of `task`: one structure, filled in for each."""

    def __init__(self, task: Task) -> None:
        self.n, self.m = task.n, task.m
        self.s = DriverSample(n_x=task.n, n_u=task.m)

    def fill(
        self, counters: Counters, seq: int, x: Sequence[float], outcome: Outcome | None = None
    ) -> DriverSample:
        """Sample `seq` at state `x`, stamped now (valid until the next fill), with
        `outcome` (reward, terminated, truncated) of the step it closes, if given."""
        s = self.s
        s.reward, s.ending = 0.0, 0
        if outcome is not None:
            reward, terminated, truncated = outcome
            s.reward = float(reward)
            s.ending = TERMINATED if terminated else TRUNCATED if truncated else 0
        s.seq = seq
        s.t_sample_ns = time.monotonic_ns()
        s.status = counters.status
        s.reset_id = counters.reset_id
        s.last_command = counters.last_command
        s.clamped = counters.clamped
        s.rejected = counters.rejected
        s.x[: self.n] = x
        s.u_applied[: self.m] = counters.u
        s.t_publish_ns = time.monotonic_ns()
        return s


def serve(
    services: Services,
    task: Task,
    simulation: Simulation,
    stopping: Callable[[], bool] = lambda: False,
    log: Callable[[str], None] | None = None,
) -> None:
    """Serves `simulation` as the driver of `task` in lockstep until `stopping()`;
    `log(text)`, if given, is told of resets."""
    t_start = time.monotonic_ns()
    provides = getattr(simulation, "provides_reward", False)
    advertised = info(
        task, LOCKSTEP, t_start, provides=PROVIDES_REWARD if provides else 0,
        info_type=services.info_type,
    )
    outcome: Outcome | None
    counters = Counters(task.m)
    samples = Samples(task)
    newest: int | None = None
    next_info = 0
    readers = services.info_readers()
    while not stopping():
        if time.monotonic_ns() >= next_info:
            advertised.t_publish_ns = time.monotonic_ns()
            services.publish_info(advertised)
            next_info = time.monotonic_ns() + 1_000_000_000
        c = services.receive(50)
        if c is None:
            now_readers = services.info_readers()
            if now_readers != readers:
                next_info = 0  # a rig subscribed (or left, maybe for another): info at once
            readers = now_readers
            continue
        if c.kind == RESET:
            x0 = c.x0[: task.n]
            if c.n_x != task.n or not all(map(math.isfinite, x0)):
                counters.rejected += 1
                if log:
                    log(f"rejected reset {c.seq}: n_x {c.n_x}, x0 {x0}")
                continue
            simulation.place(x0)
            counters.status, counters.reset_id = READY, c.seq
            counters.u = [0.0] * task.m
            if log:
                log(f"reset {c.seq}: placed at {x0}")
            outcome = None
        elif c.kind == ACTION and counters.status & READY and c.sample_seq == newest:
            counters.admit(task, c)
            simulation.step(counters.u, task.ts)
            outcome = simulation.outcome() if provides else None  # type: ignore[attr-defined]
        else:
            counters.rejected += 1  # before a reset, for an older sample, or unknown
            continue
        newest = 0 if newest is None else newest + 1
        services.publish_sample(samples.fill(counters, newest, simulation.state(), outcome))
