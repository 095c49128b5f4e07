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
import time
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("driver.py", modules=["iceoryx2"])

import iceoryx2 as iox2  # noqa: E402

from rigkit import realtime  # noqa: E402
from rigkit.angle import wrap  # noqa: E402
from rigkit.lockstep import Services, info, serve  # noqa: E402

# DriverSample, DriverCommand and the constants of docs/driver.md.
from rigkit.messages import (  # noqa: E402
    ACTION,
    READY,
    REALTIME,
    RESET,
    RESETTING,
    WATCHDOG,
    DriverCommand,
    DriverSample,
)
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


def finite(values):
    return all(math.isfinite(v) for v in values)


class Driver:
    """One driver instance: services, the simulated pendulum, the watchdog, resets."""

    KP, KD = 1.0, 0.7  # reset controller [V/rad], [V s/rad]
    REST_ANGLE, REST_SPEED = 0.02, 0.05  # "at rest" tolerance [rad], [rad/s]
    REST_SAMPLES = 3  # consecutive samples at rest before READY

    def __init__(self, args, task):
        self.args = args
        self.task = task
        self.u_min, self.u_max = task.low[0], task.high[0]
        self.speed = args.speed
        self.period_ns = round(task.ts / self.speed * 1e9)
        self.clock_error = random.Random(1)  # --inject-fault clock
        self.plant = Pendulum()
        self.t_start = time.monotonic_ns()
        self.t_phys = self.t_start  # monotonic time the physics has reached
        self.u = 0.0  # the action in effect
        self.status = 0  # no reset yet: actions are not applied
        self.reset_id = 0
        self.reset_target = None
        self.at_rest = 0
        self.last_command = 0
        self.action_this_period = False
        self.acted_since_reset = False
        self.periods_without_action = 0
        self.clamped = 0
        self.rejected = 0
        self.watchdog_trips = 0
        self.held = []  # --inject-fault late: commands kept for the next sample instant

        sample_type = BadSample if args.inject_fault == "layout" else DriverSample
        io = Services(args.driver_id, sample_type)
        self.io = io
        self.sample_pub, self.sample_note = io.sample_pub, io.sample_note
        self.commands = io.commands
        self.stopping = False

    def publish(self, pub, notifier, msg):
        pub.loan_uninit().write_payload(msg).send()
        notifier.notify()

    def publish_info(self):
        """The info of the real-time clock (lockstep.serve publishes its own)."""
        self.io.publish_info(info(self.task, REALTIME, self.t_start, self.speed))

    def physics_to(self, t_ns):
        """Advances the simulation to monotonic time t_ns with the action in effect."""
        self.plant.advance(self.u, (t_ns - self.t_phys) * 1e-9 * self.speed)
        self.t_phys = max(self.t_phys, t_ns)

    def log(self, text):
        if self.args.verbose:
            print(f"driver: {text}", file=sys.stderr, flush=True)

    def command(self, c):
        """Handles one command, at its arrival (the physics is already there)."""
        if c.kind == ACTION:
            u = c.u[0]
            if self.status & READY == 0:
                self.rejected += 1  # not reset yet, or resetting: ignored
            elif c.n_u != 1 or not finite([u]):
                if self.args.inject_fault == "limits" and c.n_u == 1:
                    return  # the fault: keep the previous action
                self.rejected += 1
                self.u = 0.0  # the safe action
                self.log(f"rejected command {c.seq}: n_u {c.n_u}, u {u}")
            else:
                lo, hi = self.u_min, self.u_max
                if not lo <= u <= hi and self.args.inject_fault != "limits":
                    self.clamped += 1
                    u = min(max(u, lo), hi)
                self.u = u
                self.last_command = c.seq
                self.action_this_period = True
                self.acted_since_reset = True
                self.status &= ~WATCHDOG
        elif c.kind == RESET:
            x0 = [c.x0[0], c.x0[1]]
            if c.n_x != 2 or not finite(x0):
                self.rejected += 1
                self.log(f"rejected reset {c.seq}: n_x {c.n_x}, x0 {x0}")
                return
            self.status = RESETTING
            self.reset_id = c.seq
            self.reset_target = x0
            self.at_rest = 0
            self.log(f"reset {c.seq} to {x0}")
        else:
            self.rejected += 1

    def at_sample_instant(self):
        """Decisions at a sample instant, after sampling: reset progress, watchdog."""
        phi, omega = self.plant.x
        if self.status & RESETTING:
            target_phi, target_omega = self.reset_target
            e_phi = wrap(target_phi - phi)
            e_omega = target_omega - omega
            rest = abs(e_phi) < self.REST_ANGLE and abs(e_omega) < self.REST_SPEED
            self.at_rest = self.at_rest + 1 if rest else 0
            if self.at_rest >= self.REST_SAMPLES:
                self.status = READY
                self.u = 0.0
                self.action_this_period = False
                self.acted_since_reset = False
                self.periods_without_action = 0
                self.log(f"reset {self.reset_id} done at {self.plant.x}")
            else:
                u = self.KP * e_phi + self.KD * e_omega
                self.u = min(max(u, self.u_min), self.u_max)
            return
        if self.status & READY:
            if self.action_this_period:
                self.periods_without_action = 0
            else:
                self.periods_without_action += 1
            self.action_this_period = False
            # --inject-fault slow-watchdog: a period too late.
            periods = 2 if self.args.inject_fault == "slow-watchdog" else 1
            engage = self.periods_without_action >= periods and self.acted_since_reset
            if engage and not self.status & WATCHDOG and self.args.inject_fault != "watchdog":
                self.status |= WATCHDOG
                self.watchdog_trips += 1
                self.u = 0.0
                self.log("watchdog: no action for a period, applying zero")

    def sample(self, seq, t_sample):
        s = (BadSample if self.args.inject_fault == "layout" else DriverSample)()
        s.seq = seq
        s.t_sample_ns = t_sample
        s.status = self.status
        s.reset_id = self.reset_id
        s.last_command = self.last_command
        s.n_x = 2
        s.n_u = 1
        s.x[0], s.x[1] = self.measured()
        s.u_applied[0] = self.u
        if self.args.inject_fault != "layout":
            s.clamped = self.clamped
            s.rejected = self.rejected
            s.watchdog_trips = self.watchdog_trips
        return s

    def drain_commands(self):
        """Handles every command waiting, each at the time it is taken."""
        while True:
            c = self.commands.receive()
            if c is None:
                return
            cmd = DriverCommand.from_buffer_copy(c.payload().contents)
            del c  # returns the slot
            if self.args.inject_fault == "late":
                self.held.append(cmd)  # the fault: handled a period late
                continue
            self.physics_to(time.monotonic_ns())
            self.command(cmd)

    def wait_until(self, deadline):
        """Handles commands as they arrive until monotonic time `deadline`."""
        self.io.sleep_until(deadline, self.drain_commands, lambda: self.stopping)

    def measured(self):
        """The state as the samples report it (an encoder's counts with --sensor angle)."""
        x = list(self.plant.x)
        if self.args.sensor == "angle":
            # An encoder: the angle in whole counts, the velocity not measured (NaN);
            # the rig's observer estimates it (docs/driver.md, "Positions only").
            q = 2.0 * math.pi / ENCODER_COUNTS
            x = [wrap(round(x[0] / q) * q), math.nan]
        return x

    def run_lockstep(self):
        """The lockstep clock (docs/driver.md, "Lockstep"), by lockstep.serve: resets
        place the pendulum, each action integrates exactly one period."""

        driver = self

        class Simulation:
            def place(self, x0):
                driver.plant.x = [wrap(x0[0]), x0[1]]

            def step(self, u, dt):
                driver.plant.advance(u[0], dt)

            def state(self):
                return driver.measured()

        log = self.log if self.args.verbose else None
        serve(self.io, self.task, Simulation(), lambda: self.stopping, log)

    def run(self):
        if self.args.clock == "lockstep":
            return self.run_lockstep()
        period = self.period_ns
        seq = 0
        next_info = self.t_start
        while not self.stopping:
            t_sample = time.monotonic_ns()
            self.physics_to(t_sample)
            s = self.sample(seq, t_sample)
            self.at_sample_instant()
            s.status = self.status  # status after this instant's decisions
            s.t_publish_ns = time.monotonic_ns()
            self.publish(self.sample_pub, self.sample_note, s)
            held, self.held = self.held, []
            for cmd in held:  # --inject-fault late: last period's commands, now
                self.command(cmd)
            if t_sample >= next_info:
                self.publish_info()
                next_info = t_sample + 1_000_000_000
            seq += 1
            if self.args.inject_fault == "clock":
                # The fault: a relative wait, each off by up to ±2 ms (a fixed seed).
                error = self.clock_error.randint(-2_000_000, 2_000_000)
                self.wait_until(t_sample + period + error)
                continue
            self.wait_until(self.t_start + seq * period)
            # Woken late by a period or more: those periods were missed.
            late = (time.monotonic_ns() - (self.t_start + seq * period)) // period
            if late > 0:
                seq += late
                self.log(f"missed {late} period(s)")


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
        driver = Driver(args, task)
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
        else f"period {driver.period_ns / 1e6:g} ms of wall time (speed {args.speed:g})"
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

    def stop(signum, frame):
        driver.stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    driver.run()
    print("driver: stopped", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
