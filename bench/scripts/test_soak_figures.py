#!/usr/bin/env python3
"""Checks soak.py's count of a second session's commands on made-up driver samples: a
command of another session applied while the run commands the driver counts; one applied
after the run fell silent past its lease, one shown at a resumed run's start (the last
command before it), and the run's own commands a resume dropped from the recording do
not. Exits non-zero with the failed case."""

import sys

from soak import foreign_commands, lease_ns  # the script beside this one

MS = 1_000_000
PERIOD = 30 * MS
LEASE = lease_ns(PERIOD)
BASE = 5_000 * 1_000 * MS  # the run's session: numbers from its clock at the start


def run_commanding(t0, n, base=BASE):
    """The run's commands `base + k`, one a period from t0, and the samples showing each."""
    sent = {base + k: t0 + k * PERIOD for k in range(n)}
    applied = [(t0 + k * PERIOD + 5 * MS, base + k) for k in range(n)]
    return sent, applied


def count(sent, applied):
    return len(foreign_commands(sent, applied, LEASE))


def main():
    other = 7_000 * 1_000 * MS  # another session's numbers
    sent, applied = run_commanding(0, 20)
    cases = {}
    # Another session's command applied between two of the run's: it reached the driver
    # while the run held it.
    cases["foreign while held"] = (count(sent, applied + [(10 * PERIOD + 20 * MS, other)]), 1)
    # After the run's last command, silence past the lease: the driver is free.
    late = 19 * PERIOD + LEASE + 50 * MS
    cases["foreign after the lease"] = (count(sent, applied + [(late, other)]), 0)
    # A resumed run's start: its first command published, the driver still showing an old
    # one of the run's and then another session's (which holds it: the run's is refused).
    s2, a2 = run_commanding(60_000 * MS, 5, base=BASE + 60_000 * MS)
    start = 59_900 * MS
    seen = [(start, BASE + 19), (start + PERIOD, other), (start + 2 * PERIOD, other + 1)]
    both = {**sent, **s2, BASE + 60_000 * MS - 1: start - 10 * MS}
    cases["another holds at a resumed start"] = (count(both, applied + seen), 0)
    # The run's own commands whose recording a resume dropped: its numbers, not another's.
    dropped = [(20 * PERIOD + 5 * MS, BASE + 20), (21 * PERIOD + 5 * MS, BASE + 21)]
    cases["own commands dropped by a resume"] = (count(sent, applied + dropped), 0)
    failed = {k: v for k, v in cases.items() if v[0] != v[1]}
    for k, (got, want) in failed.items():
        print(f"{k}: counted {got}, expected {want}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
