import math

from rigkit.reward import Region, Reward
from rigkit.task import Task

from conftest import ROOT


def test_the_quadratic_form_wraps_angle_errors() -> None:
    r = Reward([5.0, 0.1], [1.0], [0.0, 0.0], [True, False])
    assert r([0.0, 0.0], [0.0]) == 0.0
    assert r([1.0, 2.0], [0.5]) == -(5.0 * 1.0 + 0.1 * 4.0) - 0.25
    # 2 pi + 0.5 is 0.5 from the reference on the circle.
    assert math.isclose(r([2 * math.pi + 0.5, 0.0], [0.0]), -5.0 * 0.25)


def test_a_box_takes_angles_on_the_circle_and_a_ball_its_radii() -> None:
    box = Region("box", [-0.1, -1.0], [0.1, 1.0])
    assert box.contains([2 * math.pi + 0.05, 0.5], [True, False])
    assert not box.contains([0.05, 1.5], [True, False])
    assert not box.contains([math.nan, 0.0], [True, False])
    ball = Region("ball", [0.0, 0.0], [0.1, math.inf])
    assert ball.contains([0.09, 100.0], [False, False])
    assert not ball.contains([0.11, 0.0], [False, False])


def test_a_goal_adds_its_bonus() -> None:
    task = Task.read(str(ROOT / "examples/tasks/pendulum-reach.toml"))
    assert task.reward.goal is not None
    region, bonus = task.reward.goal
    inside = [(a + b) / 2 for a, b in zip(region.first, region.second)] if region.kind == "box" else region.first
    outside = [v + 3.0 for v in inside]
    without = Reward(task.q, task.p, task.reference, task.angles, task.reward.cosine, task.reward.abs_action)
    u = [0.0] * task.m
    assert task.reward(inside, u) == without(inside, u) + bonus + 0.0
    assert task.reward(outside, u) == without(outside, u)
