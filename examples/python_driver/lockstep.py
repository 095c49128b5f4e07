"""A driver for any simulator, in lockstep (docs/driver.md, "Lockstep"), over the official
iceoryx2 bindings: give it a task (task.py) and a simulation, and the rig can learn on it.

    from lockstep import Services, serve
    serve(Services(driver_id), task, simulation)

The simulation is any object with

    place(x0)        put the system at rest at state x0 (a list of n floats)
    step(u, dt)      integrate dt seconds with the action u (m floats, within the bounds)
    state()          the state, n floats, angles wrapped to [-pi, pi)

A RESET places it at x0 and is answered by a READY sample there; an ACTION answering
the newest sample while READY is clamped to the task's bounds (or, non-finite or of the
wrong size, rejected: zero) and moves the simulation one sample period, answered by the
sample that closes it; any other action is only counted as rejected. The info goes out
at start and every second. `examples/furuta/` and `examples/gymnasium/` are built on it.
"""

import math
import signal
import sys
import time

import iceoryx2 as iox2

from messages import (
    ACTION,
    LOCKSTEP,
    READY,
    RESET,
    VERSION,
    DriverCommand,
    DriverInfo,
    DriverSample,
)


class Services:
    """A driver's three services with the settings of docs/driver.md, and its events."""

    def __init__(self, driver_id: str, sample_type=DriverSample):
        self.driver_id = driver_id
        iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
        self.node = (
            iox2.NodeBuilder.new()
            .name(iox2.NodeName.new(f"rig-driver-{driver_id}"))
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        self.info_pub, self.info_note = self.publisher("info", DriverInfo)
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

    def name(self, topic):
        return iox2.ServiceName.new(f"rig/driver/{self.driver_id}/{topic}")

    def pubsub(self, topic, payload):
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

    def publisher(self, topic, payload):
        pub = self.pubsub(topic, payload).publisher_builder().create()
        notifier = (
            self.node.service_builder(self.name(topic))
            .event()
            .open_or_create()
            .notifier_builder()
            .create()
        )
        return pub, notifier

    def publish_info(self, info):
        self.info_pub.loan_uninit().write_payload(info).send()
        self.info_note.notify()

    def publish_sample(self, sample):
        self.sample_pub.loan_uninit().write_payload(sample).send()
        self.sample_note.notify()

    def receive(self, timeout_ms: int):
        """The next command, or None after waiting up to `timeout_ms` for one."""
        c = self.commands.receive()
        if c is None:
            self.waitset.wait_and_process_with_timeout(iox2.Duration.from_millis(timeout_ms))
            self.command_events.try_wait()  # consume the wake-up
            c = self.commands.receive()
            if c is None:
                return None
        cmd = DriverCommand.from_buffer_copy(c.payload().contents)
        del c  # returns the slot
        return cmd


def info(task, clock: int, t_start: int, speed: float = 1.0) -> DriverInfo:
    """The DriverInfo of a driver of `task`, `speed` times faster than real time."""
    i = DriverInfo(
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
    )
    for j in range(task.m):
        i.u_min[j], i.u_max[j] = task.low[j], task.high[j]
    return i


class Counters:
    """What the samples report besides the state."""

    def __init__(self, m: int):
        self.status = 0  # no reset yet
        self.reset_id = 0
        self.last_command = 0
        self.u = [0.0] * m
        self.clamped = 0
        self.rejected = 0

    def admit(self, task, c: DriverCommand) -> None:
        """An action answering the newest sample while READY: clamped, or rejected."""
        u = [c.u[j] for j in range(task.m)]
        if c.n_u != task.m or not all(math.isfinite(v) for v in u):
            self.rejected += 1
            self.u = [0.0] * task.m  # the safe action
            return
        clamped = [min(max(v, lo), hi) for v, lo, hi in zip(u, task.low, task.high)]
        self.clamped += clamped != u
        self.u = clamped
        self.last_command = c.seq


def sample(task, counters: Counters, seq: int, x) -> DriverSample:
    s = DriverSample(
        seq=seq,
        t_sample_ns=time.monotonic_ns(),
        status=counters.status,
        reset_id=counters.reset_id,
        last_command=counters.last_command,
        n_x=task.n,
        n_u=task.m,
        clamped=counters.clamped,
        rejected=counters.rejected,
    )
    for i, v in enumerate(x):
        s.x[i] = v
    for j, v in enumerate(counters.u):
        s.u_applied[j] = v
    s.t_publish_ns = time.monotonic_ns()
    return s


def serve(services: Services, task, simulation, stopping=lambda: False, log=lambda text: None):
    """Serves `simulation` as the driver of `task` in lockstep until `stopping()`."""
    t_start = time.monotonic_ns()
    counters = Counters(task.m)
    newest = None
    next_info = 0
    while not stopping():
        if time.monotonic_ns() >= next_info:
            services.publish_info(info(task, LOCKSTEP, t_start))
            next_info = time.monotonic_ns() + 1_000_000_000
        c = services.receive(200)
        if c is None:
            continue
        if c.kind == RESET:
            x0 = [c.x0[i] for i in range(task.n)]
            if c.n_x != task.n or not all(math.isfinite(v) for v in x0):
                counters.rejected += 1
                log(f"rejected reset {c.seq}: n_x {c.n_x}, x0 {x0}")
                continue
            simulation.place(x0)
            counters.status, counters.reset_id = READY, c.seq
            counters.u = [0.0] * task.m
            log(f"reset {c.seq}: placed at {x0}")
        elif c.kind == ACTION and counters.status & READY and c.sample_seq == newest:
            counters.admit(task, c)
            simulation.step(counters.u, task.ts)
        else:
            counters.rejected += 1  # before a reset, for an older sample, or unknown
            continue
        newest = 0 if newest is None else newest + 1
        services.publish_sample(sample(task, counters, newest, simulation.state()))


def serve_until_signalled(services: Services, task, simulation, who: str, verbose: bool):
    """serve() until SIGTERM or Ctrl-C, logging resets to stderr as `who` if `verbose`."""
    stopping = []
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stopping.append(True))

    def log(text):
        if verbose:
            print(f"{who}: {text}", file=sys.stderr, flush=True)

    serve(services, task, simulation, lambda: bool(stopping), log)
    print(f"{who}: stopped", file=sys.stderr)
