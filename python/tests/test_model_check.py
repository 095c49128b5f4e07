"""rigkit.model_check: a check's verdict from its two figures."""

import pytest

from rigkit.model_check import Check, verdict


def drift(value: float) -> Check:
    return Check("energy drift", "J", value, 1e-6)


def difference(value: float | None) -> Check:
    return Check("largest difference", "", value, 0.0)


def test_both_within_their_most_pass_and_are_printed(capsys: pytest.CaptureFixture[str]) -> None:
    assert verdict(drift(1e-7), difference(0.0), skipped="the comparison") == 0
    assert capsys.readouterr().out == "energy drift: 1.00e-07 J\nlargest difference: 0.00e+00\n"


def test_either_beyond_its_most_fails() -> None:
    assert verdict(drift(2e-6), difference(0.0), skipped="the comparison") == 1
    assert verdict(drift(1e-7), difference(1e-15), skipped="the comparison") == 1


def test_a_missing_comparison_is_said_skipped_and_passes(capsys: pytest.CaptureFixture[str]) -> None:
    assert verdict(drift(1e-7), difference(None), skipped="the comparison with X") == 0
    assert "skipped: gymnasium is not installed (the comparison with X)" in capsys.readouterr().out
