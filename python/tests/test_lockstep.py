"""The lockstep driver's bookkeeping (rigkit.lockstep); serving the rig is the rig's tests'
(rig/tests/lockstep.rs, driver_reward.rs)."""

import math

import pytest

pytest.importorskip("iceoryx2")

from rigkit import messages  # noqa: E402
from rigkit.lockstep import Counters, Samples, info  # noqa: E402
from rigkit.task import Task  # noqa: E402

from conftest import ROOT  # noqa: E402

TASK = Task.read(str(ROOT / "plant/tasks/pendulum.toml"))


def command(u: list[float], n_u: int = 1, seq: int = 7) -> messages.DriverCommand:
    c = messages.DriverCommand(seq=seq, kind=messages.ACTION, n_u=n_u)
    c.u[: len(u)] = u
    return c


def test_an_action_is_clamped_to_the_bounds_or_rejected() -> None:
    c = Counters(1)
    c.admit(TASK, command([1.5]))
    assert (c.u, c.clamped, c.rejected, c.last_command) == ([1.5], 0, 0, 7)
    c.admit(TASK, command([99.0], seq=8))
    assert (c.u, c.clamped, c.last_command) == ([TASK.high[0]], 1, 8)
    c.admit(TASK, command([math.nan], seq=9))
    assert (c.u, c.rejected, c.last_command) == ([0.0], 1, 8)
    c.admit(TASK, command([1.0, 1.0], n_u=2, seq=10))
    assert (c.u, c.rejected) == ([0.0], 2)


def test_a_sample_carries_the_outcome_of_its_step() -> None:
    s = Samples(TASK)
    c = Counters(1)
    first = s.fill(c, 3, [0.5, -1.0], (2.5, False, True))
    assert (first.seq, list(first.x[:2]), first.reward, first.ending) == (3, [0.5, -1.0], 2.5, messages.TRUNCATED)
    assert first.t_sample_ns <= first.t_publish_ns
    again = s.fill(c, 4, [0.0, 0.0], (1.0, True, True))
    assert again.ending == messages.TERMINATED  # terminated wins
    assert s.fill(c, 5, [0.0, 0.0]).ending == 0


def test_the_info_advertises_the_task() -> None:
    i = info(TASK, messages.LOCKSTEP, 123, provides=messages.PROVIDES_REWARD)
    assert i.task.decode() == "pendulum" and i.task_hash == TASK.hash()
    assert (i.version, i.clock, i.n_x, i.n_u, i.provides) == (messages.VERSION, messages.LOCKSTEP, 2, 1, 1)
    assert i.period_ns == 30_000_000 and (i.u_min[0], i.u_max[0]) == (-3.0, 3.0)


def test_a_driver_id_the_rig_can_carry() -> None:
    from rigkit.realtime import check_driver_id

    assert check_driver_id("lab-pendulum_2") == "lab-pendulum_2"
    for bad in ("", "a b", "a.b", "π"):
        with pytest.raises(ValueError, match="letters, digits, '-' and '_' only"):
            check_driver_id(bad)
