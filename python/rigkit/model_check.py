"""The verdict of a model driver's check (examples/*/check_model.py): its integrator keeps
the system's energy without input, and its dynamics are those of the Gymnasium
environment it follows.

    sys.exit(verdict(Check("energy drift over 10 s without torque", "J", energy_drift(), 1e-6),
                     Check("largest difference from Acrobot-v1's derivative", "", diff, 0.0),
                     skipped="the comparison with Acrobot-v1"))
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Check:
    """One figure of a check, in words, with its unit and the most it may be."""

    what: str
    unit: str
    value: float | None
    most: float

    def passes(self) -> bool:
        """Whether the figure is within its most (a missing one passes: it was skipped)."""
        return self.value is None or self.value <= self.most


def verdict(drift: Check, difference: Check, skipped: str) -> int:
    """Prints both figures (the difference as skipped, naming `skipped`, when gymnasium is
    not installed: its value None) and returns the exit status: 0 if both pass, else 1."""
    for c in (drift, difference):
        if c.value is None:
            print(f"skipped: gymnasium is not installed ({skipped})")
        else:
            print(f"{c.what}: {c.value:.2e}" + (f" {c.unit}" if c.unit else ""))
    return 0 if drift.passes() and difference.passes() else 1
