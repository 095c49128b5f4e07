"""Child processes that a script stops as Ctrl-C stops a command: each started in a
process group of its own, so that stopping it reaches every process it started too (a
`rig run` and its plant, observer and agent; `nsenter` and what it runs; a shell script
and its driver), and so that a script stopped by SIGTERM rather than a terminal's Ctrl-C
leaves none of them behind.

    p = start(["rig", "sim-driver", "--driver-id", "x"])
    try:
        out = run(["rig", "run", "--plant", "external", "--driver", "x"], timeout=60)
    finally:
        stop(p)
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from collections.abc import Sequence
from typing import Any

# How long a stopped process has to exit before it is killed [s].
PATIENCE_S = 10.0


def start(argv: Sequence[str], **popen: Any) -> subprocess.Popen[Any]:
    """`argv` started in a process group (and session) of its own; `popen` as Popen's."""
    return subprocess.Popen(list(argv), start_new_session=True, **popen)


def call(argv: Sequence[str], **popen: Any) -> int:
    """`argv` run to its end in a group of its own, its output the script's; stopped with
    everything it started (`stop`) if the wait ends otherwise (Ctrl-C, an exception).
    Returns its exit status."""
    p = start(argv, **popen)
    try:
        return p.wait()
    except BaseException:
        stop(p)
        raise


def run(
    argv: Sequence[str], timeout: float | None = None, **popen: Any
) -> subprocess.CompletedProcess[str]:
    """`argv` run to its end in a group of its own, its output captured as text; stopped
    with everything it started (`stop`) if the wait ends otherwise: a timeout
    (subprocess.TimeoutExpired, raised), Ctrl-C, or any other exception."""
    p = start(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
              text=True, **popen)
    try:
        out, err = p.communicate(timeout=timeout)
    except BaseException:
        stop(p)
        raise
    return subprocess.CompletedProcess(list(argv), p.returncode, out, err)


def stop(p: subprocess.Popen[Any], sig: int | None = signal.SIGINT, patience: float = PATIENCE_S) -> int:
    """Stops `p` with `sig` (SIGINT: as Ctrl-C; None: `p` was told already, by a
    terminal's Ctrl-C, say) and waits for it; kills it if it has not exited within
    `patience` seconds. A process started by `start` is stopped with its whole group, and
    what the group still holds once `p` has exited is stopped the same way. A Ctrl-C
    while it waits does not leave the stop half done: it goes on to its end. Returns
    `p`'s exit status."""
    group = _own_group(p)
    if p.poll() is None and sig is not None:
        _signal(p, group, sig)
    deadline = time.monotonic() + patience
    while True:
        try:
            return _finish(p, group, signal.SIGINT if sig is None else sig, deadline, patience)
        except KeyboardInterrupt:
            continue


def _finish(p: subprocess.Popen[Any], group: int | None, sig: int, deadline: float, patience: float) -> int:
    """`stop` once `p` was told: waits until `deadline`, kills; the rest of its group too."""
    try:
        p.wait(timeout=max(0.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired:
        _signal(p, group, signal.SIGKILL)
        p.wait()
    if group is not None and _group_alive(group):
        _signal(p, group, sig)
        rest = time.monotonic() + patience
        while _group_alive(group) and time.monotonic() < rest:
            time.sleep(0.02)
        if _group_alive(group):
            _signal(p, group, signal.SIGKILL)
    return p.returncode


def _own_group(p: subprocess.Popen[Any]) -> int | None:
    """`p`'s process group if `p` leads it (started by `start`), else None."""
    try:
        return p.pid if os.getpgid(p.pid) == p.pid else None
    except ProcessLookupError:
        # Exited (a zombie still has its group; reaped, it has none): its group may
        # outlive it, so a process `start` made is taken to lead one.
        return p.pid if _group_alive(p.pid) else None


def _signal(p: subprocess.Popen[Any], group: int | None, sig: int) -> None:
    try:
        if group is None:
            p.send_signal(sig)
        else:
            os.killpg(group, sig)
    except ProcessLookupError:
        pass


def _group_alive(group: int) -> bool:
    """Whether a process of `group` still runs (Linux's /proc; zombies, which an init
    that does not reap them keeps, do not count)."""
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                stat = f.read()
        except OSError:
            continue
        # pid (comm) state ppid pgrp ...: comm may hold spaces and parentheses.
        fields = stat[stat.rfind(b")") + 2 :].split()
        if int(fields[2]) == group and fields[0] != b"Z":
            return True
    return False
