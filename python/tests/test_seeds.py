"""The benchmark's interaction-to-success figures (rigkit.seeds.to_success and
median_to_success) and the success rules (rigkit.seeds.meets)."""

from rigkit.seeds import (
    TaskTimes,
    last_successes,
    median_to_success,
    meets,
    to_success,
    verdict_line,
)


def test_every_verdict_in_order_and_the_last_ten_counted() -> None:
    verdicts = [False] + [True] * 5 + [False] + [True] * 8
    assert verdict_line(verdicts) == ".11111.11111111"
    assert last_successes(verdicts) == (9, 10)
    assert last_successes(verdicts[:4]) == (3, 4)
    assert last_successes([]) == (0, 0)


def test_first_success_and_the_success_held_to_the_end() -> None:
    evals = [(10.0, False), (20.0, True), (30.0, False), (40.0, True), (50.0, True)]
    assert to_success(evals) == (20, 40)


def test_a_run_whose_last_evaluation_fails_never_holds() -> None:
    assert to_success([(10.0, True), (20.0, True), (30.0, False)]) == (10, None)


def test_a_run_that_never_succeeds() -> None:
    assert to_success([(10.0, False), (20.0, False)]) == (None, None)
    assert to_success([]) == (None, None)


def test_success_from_the_first_evaluation_on() -> None:
    assert to_success([(5.0, True), (10.0, True)]) == (5, 5)


def test_a_seed_that_never_got_there_counts_as_later_than_any() -> None:
    assert median_to_success([300, None, 100, 200, None]) == 300


def test_none_when_the_median_seed_never_got_there() -> None:
    assert median_to_success([None, None, 100, None, 50]) is None


def test_an_even_count_averages_the_middle_two_or_has_none() -> None:
    assert median_to_success([40, 10, 20, 30]) == 25
    assert median_to_success([10, 20, None, None]) is None


def test_zero_is_a_time_not_a_failure() -> None:
    assert median_to_success([0, 0, None]) == 0
    assert median_to_success([]) is None


def test_a_return_rule_takes_the_mean_of_the_start_states() -> None:
    task = TaskTimes(ts=0.1, length=1.0, angles=[0])
    trials = [([[0.0]], 100.0), ([[0.0]], 80.0)]
    assert meets({"return_at_least": 90.0}, task, trials) == (90.0, True)
    assert meets({"return_at_least": 91.0}, task, trials) == (90.0, False)


def test_an_upright_rule_needs_every_trial_full_length_and_up_at_its_end() -> None:
    task = TaskTimes(ts=0.5, length=1.0, angles=[1])
    up = [[5.0, 3.0], [5.0, 0.1], [5.0, -0.1]]  # the angle wraps: 3.0 is far from 0
    rule = {"upright": 0.2, "hold": 0.5}
    assert meets(rule, task, [(up, -1.0)])[1]
    assert not meets(rule, task, [(up, -1.0), (up[:2], -1.0)])[1]  # one trial ended early
    assert not meets(rule, task, [([[5.0, 0.1], [5.0, 3.0], [5.0, 0.1]], -1.0)])[1]
