"""The realtime clock's timing and bookkeeping (rigkit.clocked) on a fake monotonic clock;
serving the rig is the rig's test (rig/tests/realtime_models.rs)."""

from __future__ import annotations

import ctypes
import math
from collections.abc import Callable

import pytest

pytest.importorskip("iceoryx2")

from rigkit import messages  # noqa: E402
from rigkit.clocked import Clocked, serve_realtime  # noqa: E402
from rigkit.task import Task  # noqa: E402

from conftest import ROOT  # noqa: E402

TASK = Task.read(str(ROOT / "plant/tasks/pendulum.toml"))  # Ts 30 ms, u in [-3, 3]
MS = 1_000_000


class Integrator:
    """x' = u on one state pair: the steps it was asked for are its record."""

    def __init__(self) -> None:
        self.x = [0.0, 0.0]
        self.steps: list[tuple[float, float]] = []  # (u, dt)

    def place(self, x0: list[float]) -> None:
        self.x = list(x0)

    def step(self, u: list[float], dt: float) -> None:
        self.steps.append((u[0], dt))
        self.x = [self.x[0] + u[0] * dt, u[0]]

    def state(self) -> list[float]:
        return self.x


def action(u: float, seq: int, n_u: int = 1) -> messages.DriverCommand:
    c = messages.DriverCommand(seq=seq, kind=messages.ACTION, n_u=n_u)
    c.u[0] = u
    return c


def reset(seq: int, x0: list[float]) -> messages.DriverCommand:
    c = messages.DriverCommand(seq=seq, kind=messages.RESET, n_x=len(x0))
    c.x0[: len(x0)] = x0
    return c


def test_a_reset_places_the_model_at_the_next_sample_instant() -> None:
    sim = Integrator()
    d = Clocked(TASK, sim, 1.0, 0)
    d.command(action(1.0, 1), 1 * MS)
    assert d.counters.rejected == 1  # before the first reset
    d.command(reset(2, [math.pi, 0.0]), 10 * MS)
    s = d.sample(0, 30 * MS)
    assert (s.status, s.reset_id, list(s.x[:2])) == (messages.READY, 2, [math.pi, 0.0])
    d.command(action(2.0, 3), 35 * MS)
    d.command(reset(4, [0.5, 0.0]), 40 * MS)
    d.command(action(2.0, 5), 45 * MS)  # while resetting: ignored
    assert d.counters.rejected == 2
    s = d.sample(1, 60 * MS)
    # The old action held until this instant; then placed, READY, zero.
    assert (s.status, s.reset_id, s.u_applied[0], list(s.x[:2])) == (messages.READY, 4, 2.0, [0.5, 0.0])
    assert d.counters.u == [0.0]


def test_an_action_is_applied_from_its_arrival_piecewise() -> None:
    sim = Integrator()
    d = Clocked(TASK, sim, 2.0, 0)  # twice real time: 1 ms of the clock is 2 ms simulated
    d.command(reset(1, [0.0, 0.0]), 0)
    d.sample(0, 15 * MS)
    sim.steps.clear()
    d.command(action(1.0, 2), 20 * MS)
    d.command(action(99.0, 3), 25 * MS)  # clamped to 3
    s = d.sample(1, 30 * MS)
    assert sim.steps == [(0.0, 0.010), (1.0, 0.010), (3.0, 0.010)]
    assert (s.u_applied[0], s.last_command, s.clamped, s.status) == (3.0, 3, 1, messages.READY)
    d.command(action(math.nan, 4), 40 * MS)  # rejected: zero at once
    d.sample(2, 45 * MS)
    assert sim.steps[-2:] == [(3.0, 0.020), (0.0, 0.010)]
    assert (d.counters.rejected, d.counters.last_command) == (1, 3)


def test_the_watchdog_engages_after_a_period_without_an_accepted_action() -> None:
    d = Clocked(TASK, Integrator(), 1.0, 0)
    d.command(reset(1, [0.0, 0.0]), 0)
    d.sample(0, 30 * MS)
    assert d.sample(1, 60 * MS).status == messages.READY  # no action yet: never engages
    d.command(action(1.0, 2), 70 * MS)
    assert d.sample(2, 90 * MS).status == messages.READY
    d.command(action(math.inf, 3), 100 * MS)  # rejected: not an action
    s = d.sample(3, 120 * MS)
    assert (s.status, s.watchdog_trips, d.counters.u) == (messages.READY | messages.WATCHDOG, 1, [0.0])
    s = d.sample(4, 150 * MS)
    assert (s.status, s.watchdog_trips, s.u_applied[0]) == (messages.READY | messages.WATCHDOG, 1, 0.0)
    d.command(action(-1.0, 4), 160 * MS)  # clears it and re-arms
    assert d.sample(5, 180 * MS).status == messages.READY
    assert d.sample(6, 210 * MS).watchdog_trips == 2


def test_a_simulation_with_its_own_reward_is_refused() -> None:
    class Rewarding(Integrator):
        provides_reward = True

    with pytest.raises(ValueError, match="lockstep only"):
        Clocked(TASK, Rewarding(), 1.0, 0)


class FakeLink:
    """The services on a fake clock: sleeping moves the clock to the deadline plus a
    lateness, delivering the commands due by then at their times."""

    def __init__(self, late_ns: Callable[[int], int]) -> None:
        self.now = 1_000 * MS
        self.late_ns = late_ns
        self.samples: list[tuple[int, int, int]] = []  # (seq, t_sample_ns, status)
        self.infos = 0
        self.due: list[tuple[int, messages.DriverCommand]] = []
        self.sleeps = 0

    def clock(self) -> int:
        return self.now

    def publish_sample(self, s: messages.DriverSample) -> None:
        self.samples.append((s.seq, s.t_sample_ns, s.status))

    def publish_info(self, info: ctypes.Structure) -> None:
        self.infos += 1

    def info_readers(self) -> int:
        return 1

    def take(self) -> messages.DriverCommand | None:
        if self.due and self.due[0][0] <= self.now:
            return self.due.pop(0)[1]
        return None

    def sleep_until(self, deadline: int, on_wake: Callable[[], None], stopping: Callable[[], bool] = lambda: False) -> None:
        while self.due and self.due[0][0] < deadline:
            self.now = max(self.now, self.due[0][0])
            on_wake()
        self.now = max(self.now, deadline + self.late_ns(self.sleeps))
        self.sleeps += 1


def serve(link: FakeLink, samples: int, speed: float = 1.0) -> None:
    serve_realtime(link, TASK, Integrator(), speed, lambda: len(link.samples) >= samples, clock=link.clock)


def test_samples_keep_absolute_deadlines_whatever_the_lateness() -> None:
    link = FakeLink(lambda k: (k % 3) * 2 * MS)  # woken 0, 2 or 4 ms late
    serve(link, 30, speed=2.0)
    t0 = link.samples[0][1]
    period = 15 * MS  # 30 ms / speed 2
    for seq, t, _ in link.samples:
        assert 0 <= t - (t0 + seq * period) <= 4 * MS  # late, never early, never drifting
    assert [s[0] for s in link.samples] == list(range(30))
    assert link.infos == 1  # 30 x 15 ms: the info once in the first second


def test_a_period_woken_late_is_skipped_and_shows_as_a_gap() -> None:
    link = FakeLink(lambda k: 75 * MS if k == 4 else 0)  # two and a half periods late
    serve(link, 10)
    seqs = [s[0] for s in link.samples]
    assert seqs == [0, 1, 2, 3, 4, 7, 8, 9, 10, 11]  # 5 and 6 missed
    t0 = link.samples[0][1]
    assert link.samples[5][1] == t0 + 5 * 30 * MS + 75 * MS  # taken at once, late
    assert link.samples[6][1] == t0 + 8 * 30 * MS  # back on the grid


def test_commands_are_taken_between_sample_instants() -> None:
    link = FakeLink(lambda _: 0)
    t0 = link.now
    link.due = [(t0 + 10 * MS, reset(1, [0.2, 0.0])), (t0 + 40 * MS, action(1.0, 2))]
    serve(link, 5)
    watchdog = messages.READY | messages.WATCHDOG  # no action in the period before sample 3
    assert [s[2] for s in link.samples] == [0, messages.READY, messages.READY, watchdog, watchdog]


def test_the_speed_is_checked() -> None:
    for bad in (0.0, -1.0, math.nan, 1001.0):
        with pytest.raises(ValueError, match=r"must be in \(0, 1000\]"):
            serve(FakeLink(lambda _: 0), 1, speed=bad)


def test_a_model_driver_takes_the_realtime_clock_flags_or_says_why_not() -> None:
    from conftest import run, said

    helped = run(["python", "examples/furuta/driver.py", "--help"])
    assert helped.returncode == 0, said(helped)
    for flag in ("--clock {lockstep,realtime}", "--speed S", "--realtime-priority N", "--cpu-wakeup-us US"):
        assert flag in helped.stdout, helped.stdout
    for args, why in (
        (["--speed", "2"], "--speed applies to the realtime clock only"),
        (["--clock", "realtime", "--speed", "0"], "--speed 0.0: must be in (0, 1000]"),
        (["--clock", "realtime", "--cpu-wakeup-us", "-1"], "--cpu-wakeup-us -1: must be in [0, 2147483647]"),
    ):
        done = run(["python", "examples/acrobot/driver.py", *args])
        assert done.returncode == 2 and why in done.stderr, said(done)


def test_the_heap_built_before_serving_is_frozen_out_of_the_collector() -> None:
    import gc

    gc.unfreeze()
    try:
        serve(FakeLink(lambda k: 0), 3)
        assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()
