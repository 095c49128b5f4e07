#!/usr/bin/env python3
"""Example motor driver for the rig: the pendulum of Appendix A.1, simulated.

It speaks the driver contract of docs/driver.md over iceoryx2 (the official Python
bindings, pinned to the Rust crate's version 0.10.0) exactly as a driver for the real
motor would: it is the clock (a sample every Ts = 30 ms on CLOCK_MONOTONIC, whether or
not actions arrive), applies each action from the moment it arrives (clamped to
[-3, 3] V; a non-finite action is rejected and zero applied), falls back to zero when
no action arrives for a whole period (the watchdog), and resets by bringing the
pendulum to rest at the bottom with a PD controller, then reports READY. The physics is
Table A.1's model integrated with RK4 (steps of at most 1.5 ms) over the real elapsed
time, piecewise between action arrivals.

    python3 driver.py [--driver-id pendulum] [--speed 1] [--clock lockstep] [--task FILE]

It advertises the task it serves — by default the rig's shipped pendulum task,
plant/tasks/pendulum.toml; `--task FILE` another task file of the pendulum's shape, whose
sampling time and action bounds it then keeps — with the task's hash (rigkit.task). With
`--clock lockstep` it is a simulator rather than a stand-in for hardware: it publishes
sample k+1 only after the action for sample k arrived, integrating exactly one period,
and resets by placing the pendulum at the start state (docs/driver.md, "Lockstep").

Stop it with Ctrl-C or SIGTERM (it finishes the current period and exits).
"""

import argparse
import ctypes
import importlib.util
import math
import random
import signal
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("driver.py", modules=["iceoryx2"])

import iceoryx2 as iox2  # noqa: E402

from rigkit import realtime  # noqa: E402
from rigkit.angle import wrap  # noqa: E402
from rigkit.clocked import Clocked, serve_realtime  # noqa: E402
from rigkit.lockstep import Services, serve  # noqa: E402
from rigkit.messages import DriverCommand, DriverSample  # noqa: E402
from rigkit.task import Task, TaskError  # noqa: E402

# The rig's pendulum task, shipped with it.
PENDULUM_TASK = Path(__file__).resolve().parents[2] / "plant" / "tasks" / "pendulum.toml"


class BadSample(ctypes.Structure):
    """--inject-fault layout: the right type name with a wrong layout (no counters, no reward)."""

    _fields_ = DriverSample._fields_[:-5]

    @staticmethod
    def type_name() -> str:
        return DriverSample.type_name()


class Pendulum:
    """Appendix A.1: J φ̈ = M g l sin φ − (b + K²/R) φ̇ + (K/R) u, φ from upright."""

    J, M, G, L, B, K, R = 1.91e-4, 5.50e-2, 9.81, 4.20e-2, 3e-6, 5.36e-2, 9.50
    H_MAX = 0.0015  # longest RK4 step [s] (20 per 30 ms sample, as the rig's simulation)

    def __init__(self):
        self.x = [-math.pi, 0.0]  # hanging at rest

    def derivative(self, phi, omega, u):
        k_r = self.K / self.R
        return omega, (
            self.M * self.G * self.L * math.sin(phi)
            - (self.B + self.K * k_r) * omega
            + k_r * u
        ) / self.J

    def advance(self, u, seconds):
        """Integrates `seconds` of simulated time with the action `u` held."""
        if seconds <= 0.0:
            return
        n = max(1, math.ceil(seconds / self.H_MAX))
        h = seconds / n
        p, w = self.x
        f = self.derivative
        for _ in range(n):
            a1, b1 = f(p, w, u)
            a2, b2 = f(p + 0.5 * h * a1, w + 0.5 * h * b1, u)
            a3, b3 = f(p + 0.5 * h * a2, w + 0.5 * h * b2, u)
            a4, b4 = f(p + h * a3, w + h * b3, u)
            p += h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
            w += h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4)
        self.x = [wrap(p), w]


# Counts per revolution of the simulated encoder (--sensor angle), as `rig sim-driver`'s.
ENCODER_COUNTS = 4096


class Simulated:
    """The pendulum as rigkit serves a simulation (place, step, state): its samples an
    encoder's with --sensor angle."""

    def __init__(self, sensor):
        self.plant = Pendulum()
        self.sensor = sensor

    def place(self, x0):
        self.plant.x = [wrap(x0[0]), x0[1]]

    def step(self, u, dt):
        self.plant.advance(u[0], dt)

    def state(self):
        """The state as the samples report it (an encoder's counts with --sensor angle)."""
        x = list(self.plant.x)
        if self.sensor == "angle":
            # An encoder: the angle in whole counts, the velocity not measured (NaN);
            # the rig's observer estimates it (docs/driver.md, "Positions only").
            q = 2.0 * math.pi / ENCODER_COUNTS
            x = [wrap(round(x[0] / q) * q), math.nan]
        return x


class Motor(Clocked):
    """The realtime clock of rigkit.clocked as a motor driver keeps it: resets by a PD
    brake to rest at the target, as hardware must, and the --inject-fault misbehaviours."""

    KP, KD = 1.0, 0.7  # reset controller [V/rad], [V s/rad]
    REST_ANGLE, REST_SPEED = 0.02, 0.05  # "at rest" tolerance [rad], [rad/s]
    REST_SAMPLES = 3  # consecutive samples at rest before READY

    def __init__(self, task, simulation, speed, t_start, fault, log):
        super().__init__(task, simulation, speed, t_start)
        self.fault, self.log = fault, log
        self.at_rest = 0
        self.braking_for = None  # the reset_id the brake is at
        self.silent = 0  # periods without an accepted action
        self.held = []  # --inject-fault late: commands kept for the next sample instant
        self.clock_error = random.Random(1)  # --inject-fault clock

    def command(self, c, t):
        if self.fault == "late":  # the fault: handled at the next sample instant
            self.held.append(DriverCommand.from_buffer_copy(c))
            return None
        return super().command(c, t)

    def sample(self, seq, t):
        s = super().sample(seq, t)
        held, self.held = self.held, []
        for c in held:  # --inject-fault late: last period's commands, now
            super().command(c, t)
        return s

    def admit(self, c):
        if self.fault != "limits":
            return super().admit(c)
        # The fault: out-of-range actions applied as they are, non-finite ones ignored.
        if c.n_u == 1 and math.isfinite(c.u[0]):
            self.counters.u, self.counters.last_command = [c.u[0]], c.seq
        elif c.n_u != 1:
            self.counters.rejected += 1
            self.counters.u = [0.0]

    def reset(self, x0):
        """The PD brake toward x0 until at rest there for REST_SAMPLES samples."""
        if self.braking_for != self.counters.reset_id:
            self.braking_for, self.at_rest = self.counters.reset_id, 0
        phi, omega = self.simulation.plant.x
        e_phi, e_omega = wrap(x0[0] - phi), x0[1] - omega
        rest = abs(e_phi) < self.REST_ANGLE and abs(e_omega) < self.REST_SPEED
        self.at_rest = self.at_rest + 1 if rest else 0
        if self.at_rest >= self.REST_SAMPLES:
            self.silent, self.braking_for = 0, None
            if self.log:
                self.log(f"reset {self.counters.reset_id} done at {self.simulation.plant.x}")
            return True
        u = self.KP * e_phi + self.KD * e_omega
        self.counters.u = [min(max(u, self.task.low[0]), self.task.high[0])]
        return False

    def watchdog_due(self):
        self.silent = 0 if self.acted else self.silent + 1
        if self.fault == "watchdog":
            return False
        # --inject-fault slow-watchdog: a period too late.
        return self.acted_since_reset and self.silent >= (2 if self.fault == "slow-watchdog" else 1)

    def next_instant(self, seq, t_sample):
        if self.fault != "clock":
            return None
        # The fault: a relative wait, each off by up to ±2 ms (a fixed seed).
        return t_sample + self.period_ns + self.clock_error.randint(-2_000_000, 2_000_000)


class BadLayout(Services):
    """--inject-fault layout: the samples published in BadSample's layout."""

    def __init__(self, driver_id):
        super().__init__(driver_id, BadSample)

    def publish_sample(self, sample):
        super().publish_sample(BadSample.from_buffer_copy(bytes(sample)[: ctypes.sizeof(BadSample)]))


def serve_pendulum(args, task, io, stopping):
    """The pendulum served on the clock `args.clock` until `stopping()`."""
    simulation = Simulated(args.sensor)
    log = (lambda text: print(f"driver: {text}", file=sys.stderr, flush=True)) if args.verbose else None
    if args.clock == "lockstep":
        # lockstep.serve: resets place the pendulum, each action integrates one period.
        return serve(io, task, simulation, stopping, log)
    serve_realtime(io, task, simulation, args.speed, stopping, log,
                   clocked=lambda *a: Motor(*a, args.inject_fault, log))


def main():
    p = argparse.ArgumentParser(
        description="Example rig driver: simulates the pendulum of Appendix A.1 "
        "and speaks the driver contract of docs/driver.md over iceoryx2 0.10."
    )
    p.add_argument(
        "--driver-id",
        default="pendulum",
        help="the id the rig connects to (services rig/driver/ID/...); "
        "letters, digits, '-' and '_' [default: pendulum]",
    )
    p.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="run S times faster than real time: a sample every 30 ms / S of wall "
        "time, advertised as time_scale S [default: 1, real time]",
    )
    p.add_argument(
        "--clock",
        choices=["realtime", "lockstep"],
        default="realtime",
        help="realtime: a sample every period of wall time, as hardware; lockstep: "
        "sample k+1 only after the action for sample k, as fast as the rig answers, "
        "the same samples every time [default: realtime]",
    )
    p.add_argument(
        "--task",
        default=str(PENDULUM_TASK),
        help="the task file this driver serves: the pendulum's shape (2 states, 1 "
        "action); its name, hash, sampling time and action bounds are advertised "
        "[default: the rig's plant/tasks/pendulum.toml]",
    )
    p.add_argument(
        "--inject-fault",
        choices=["layout", "watchdog", "slow-watchdog", "limits", "clock", "late"],
        help="misbehave on purpose, to see what `rig check-driver` says: publish a "
        "wrong sample layout, never engage the watchdog (or only after two periods "
        "without an action: slow-watchdog), apply out-of-range and "
        "non-finite actions instead of clamping and rejecting them, or time each "
        "sample from the previous one with a wait off by up to ±2 ms (as a timed wait "
        "would be), so that the instants drift; or (late) handle each command at the "
        "sample instant after it arrived, a period late",
    )
    p.add_argument(
        "--sensor",
        choices=["full", "angle"],
        default="full",
        help="what the samples report: the full state, or (angle) an encoder's angle in "
        f"{ENCODER_COUNTS} counts per revolution and NaN for the velocity, as on the "
        "physical pendulum; run the rig with --sensor angle and an observer [default: full]",
    )
    p.add_argument(
        "--realtime-priority",
        type=int,
        metavar="N",
        help="run with SCHED_FIFO priority N (1-99), as a hardware driver should, so that "
        "a loaded machine does not delay the sample instants by milliseconds; needs "
        "CAP_SYS_NICE (or root) [default: normal scheduling]",
    )
    p.add_argument(
        "--cpu-wakeup-us",
        type=int,
        metavar="US",
        help="hold the machine's CPU wake-up latency limit at US microseconds while the "
        "driver runs (Linux PM QoS, /dev/cpu_dma_latency; 0 keeps idle CPUs polling), so "
        "that the sample instants do not wait for a CPU to leave a deep idle state; needs "
        "root [default: the operating system's choice]",
    )
    p.add_argument("--verbose", action="store_true", help="log resets and faults")
    args = p.parse_args()
    if args.cpu_wakeup_us is not None and not 0 <= args.cpu_wakeup_us <= realtime.MAX_WAKEUP_US:
        p.error(f"--cpu-wakeup-us {args.cpu_wakeup_us}: must be in [0, {realtime.MAX_WAKEUP_US}]")
    if not (math.isfinite(args.speed) and 0.0 < args.speed <= 1000.0):
        p.error(f"--speed {args.speed}: must be in (0, 1000]")
    if args.clock == "lockstep" and args.speed != 1.0:
        p.error("--speed applies to the realtime clock only")
    try:
        task = Task.read(args.task)
    except TaskError as e:
        p.error(f"--task: {e}")
    if (task.n, task.m) != (2, 1):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions; this driver is a pendulum (2 and 1)")
    try:
        realtime.check_driver_id(args.driver_id)
    except ValueError as e:
        p.error(f"--driver-id {e}")

    try:
        io = BadLayout(args.driver_id) if args.inject_fault == "layout" else Services(args.driver_id)
    except iox2.PublishSubscribeOpenOrCreateError as e:
        print(
            f"driver: cannot open the services rig/driver/{args.driver_id}/*: {e!r} "
            "(another driver with this id, or a peer with another layout?)",
            file=sys.stderr,
        )
        return 1
    except iox2.PublisherCreateError as e:
        print(
            f"driver: cannot publish on rig/driver/{args.driver_id}/*: {e!r} "
            "(is another driver with this id running?)",
            file=sys.stderr,
        )
        return 1
    clock = (
        "lockstep"
        if args.clock == "lockstep"
        else f"period {task.ts / args.speed * 1e3:g} ms of wall time (speed {args.speed:g})"
    )
    print(
        f"driver {args.driver_id!r}: task {task.name} (the pendulum), "
        f"Ts {task.ts * 1e3:g} ms, {clock}",
        file=sys.stderr,
        flush=True,
    )
    try:
        # --realtime-priority, --cpu-wakeup-us: the limit holds while the file stays open.
        wakeup_limit = realtime.timing(args.realtime_priority, args.cpu_wakeup_us)  # noqa: F841
    except RuntimeError as e:
        print(f"driver: {e}", file=sys.stderr)
        return 1

    stopping = []
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stopping.append(True))
    serve_pendulum(args, task, io, lambda: bool(stopping))
    print("driver: stopped", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
