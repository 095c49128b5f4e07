import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rigkit import processes

# A shell whose child writes its pid to $1 and sleeps (in the foreground: a non-interactive
# shell's background jobs ignore SIGINT).
TREE = 'sh -c \'echo $$ > "$1"; exec sleep 30\' sh "$1"; echo done'


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def child_of(pid_file: Path) -> int:
    for _ in range(500):
        if pid_file.exists() and pid_file.read_text().strip():
            return int(pid_file.read_text())
        time.sleep(0.01)
    raise AssertionError("the child did not start")


def test_stop_reaches_the_processes_a_child_started(tmp_path: Path) -> None:
    pid_file = tmp_path / "pid"
    p = processes.start(["sh", "-c", TREE, "sh", str(pid_file)])
    grandchild = child_of(pid_file)
    assert alive(grandchild)
    processes.stop(p, patience=5)
    assert p.returncode is not None
    for _ in range(100):
        if not alive(grandchild):
            break
        time.sleep(0.02)
    assert not alive(grandchild), "the child's own child survived"


def test_a_child_that_ignores_the_signal_is_killed(tmp_path: Path) -> None:
    p = processes.start(["sh", "-c", "trap '' INT; sleep 30"])
    time.sleep(0.2)
    t0 = time.monotonic()
    assert processes.stop(p, patience=0.5) == -signal.SIGKILL
    assert time.monotonic() - t0 < 5


def test_run_stops_what_it_started_on_a_timeout(tmp_path: Path) -> None:
    pid_file = tmp_path / "pid"
    with pytest.raises(subprocess.TimeoutExpired):
        processes.run(["sh", "-c", TREE, "sh", str(pid_file)], timeout=0.5)
    grandchild = child_of(pid_file)
    for _ in range(100):
        if not alive(grandchild):
            break
        time.sleep(0.02)
    assert not alive(grandchild)


def test_run_and_call_give_the_exit_status() -> None:
    done = processes.run(["sh", "-c", "echo out; echo err >&2; exit 3"])
    assert (done.returncode, done.stdout, done.stderr) == (3, "out\n", "err\n")
    assert processes.call(["true"]) == 0


def test_a_process_not_leading_a_group_is_stopped_alone() -> None:
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    assert os.getpgid(p.pid) == os.getpgid(0)
    processes.stop(p, patience=5)
    assert p.returncode == -signal.SIGINT or p.returncode == 1
    assert alive(os.getpid())
