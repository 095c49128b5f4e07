"""The bench scripts that no Rust test runs, or that must end cleanly however they end:
soak.py without what it needs, with a helper thread that fails, and stopped by SIGTERM
(each leaves no namespace and no process behind); across_hosts.py, learning_speed.py and
env_step.py, short."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT, run, said

SOAK = "bench/scripts/soak.py"


def network_namespaces() -> set[str]:
    return set(subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout.split())


def running(marker: str) -> list[str]:
    """Command lines of the processes that name `marker`."""
    found = []
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                line = Path(f"/proc/{entry.name}/cmdline").read_bytes().replace(b"\0", b" ").decode()
            except OSError:
                continue
            if marker in line:
                found.append(line)
    return found


@pytest.fixture
def hosts_machine(rig: Path) -> None:
    """Skips a test of two hosts where they cannot be made, or the rig has no bridge."""
    if os.geteuid() != 0 or not all(shutil.which(t) for t in ("ip", "nsenter", "unshare", "nft")):
        pytest.skip("needs root, iproute2, util-linux and nftables (network namespaces)")
    pytest.importorskip("mcap")
    try:
        probe = subprocess.run([str(rig), "bridge", "probe", "--driver", "x", "--endpoint", "tcp/127.0.0.1:1",
                                "--seconds", "0.1"], capture_output=True, text=True, timeout=10)
        without = "built without the Zenoh bridge" in probe.stderr
    except subprocess.TimeoutExpired:
        without = False
    if without:
        pytest.skip(f"{rig} was built without the bridge (the README's test command builds it with --all-features)")


def tools_dir(tmp_path: Path, names: list[str], nft: str | None = None) -> str:
    """A PATH of `names` only (links to this machine's), and `nft` as a script if given."""
    d = tmp_path / "bin"
    d.mkdir()
    for n in names:
        (d / n).symlink_to(shutil.which(n) or n)
    if nft is not None:
        (d / "nft").write_text(nft)
        (d / "nft").chmod(0o755)
    return str(d)


def soak(rig: Path, out: Path, subnet: int) -> list[str]:
    return [sys.executable, SOAK, "--seconds", "10", "--speed", "2", "--trials", "6", "--seed", "1",
            "--subnet", str(subnet), "--rig", str(rig), "--out", str(out)]


def test_soak_without_nft_says_so_in_one_line_and_makes_nothing(tmp_path: Path, rig: Path) -> None:
    before = network_namespaces()
    path = tools_dir(tmp_path, ["ip", "nsenter", "unshare", "sh"])
    t0 = time.monotonic()
    done = run(soak(rig, tmp_path / "out", 93), env={**os.environ, "PATH": path}, timeout=30)
    assert time.monotonic() - t0 < 10
    assert done.returncode == 2
    assert done.stderr == "error: soak.py: needs nft (apt-get install nftables)\n" or (
        os.geteuid() != 0 and done.stderr.startswith("error: soak.py: needs nft (apt-get install nftables), root")
    ), done.stderr
    assert not (tmp_path / "out").exists()
    assert network_namespaces() == before


def test_soak_whose_fault_thread_fails_ends_with_its_cleanup(tmp_path: Path, rig: Path, hosts_machine: None) -> None:
    before = network_namespaces()
    failing = "#!/bin/sh\necho 'nft: no such table here' >&2\nexit 1\n"
    path = tools_dir(tmp_path, ["ip", "nsenter", "unshare", "sh", "mount", "mkdir", "sleep"], nft=failing)
    out = tmp_path / "out"
    t0 = time.monotonic()
    # Seed 1's first fault is a cut, 2.8 s in: its nft fails.
    done = run(soak(rig, out, 94), env={**os.environ, "PATH": path}, timeout=60)
    assert time.monotonic() - t0 < 30
    assert done.returncode == 1, said(done)
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("error: soak.py: helper thread the faults: RuntimeError: ") and "nft" in last
    assert network_namespaces() == before
    assert running(str(out)) == []


def test_soak_stopped_by_sigterm_removes_its_hosts_and_processes(tmp_path: Path, rig: Path, hosts_machine: None) -> None:
    before = network_namespaces()
    out = tmp_path / "out"
    p = subprocess.Popen(soak(rig, out, 95), cwd=ROOT, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while len(running(str(out))) < 4 and time.monotonic() < deadline:  # driver, bridges, run
        time.sleep(0.1)
    assert len(running(str(out))) >= 4
    assert network_namespaces() != before
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err.strip().splitlines()[-1] == "error: soak.py: stopped: its processes stopped and its hosts removed"
    assert network_namespaces() == before
    assert running(str(out)) == []


def test_across_hosts_measures_one_repetition(tmp_path: Path, rig: Path, hosts_machine: None) -> None:
    before = network_namespaces()
    done = run([sys.executable, "bench/python/across_hosts.py", str(tmp_path), "--trials", "1",
                "--repetitions", "1", "--rig", str(rig)], timeout=120)
    assert done.returncode == 0, said(done)
    summary = (tmp_path / "summary.txt").read_text()
    assert summary == done.stdout
    assert "two hosts (veth between two network namespaces, one clock):" in summary
    for line in summary.splitlines():
        if "sample -> action published by the rig" in line:
            assert "n 0," not in line and "none" not in line, line
    assert network_namespaces() == before


def test_learning_speed_of_a_learned_curve(tmp_path: Path, rig: Path) -> None:
    learned = run([str(rig), "learn", "--runs", "2", "--trials", "30", "--quiet", "--out", str(tmp_path)])
    assert learned.returncode == 0, said(learned)
    done = run([sys.executable, "bench/scripts/learning_speed.py", str(tmp_path), "--levels", "-2000,-500"])
    assert done.returncode == 0, said(done)
    assert done.stdout.startswith(f"{tmp_path}: final ") and "; -2000: " in done.stdout
    bad = run([sys.executable, "bench/scripts/learning_speed.py", str(tmp_path / "absent")])
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "runs.csv: cannot read" in bad.stderr


def test_env_step_times_the_environment_alone() -> None:
    pytest.importorskip("gymnasium")
    done = run([sys.executable, "bench/scripts/env_step.py", "--trials", "2", "--trial-steps", "10"])
    assert done.returncode == 0, said(done)
    assert done.stdout.startswith("Pendulum-v1: 20 steps in ") and done.stdout.endswith(" us per step\n")


def test_encodings_rewrites_a_recording_in_both_encodings(tmp_path: Path, rig: Path) -> None:
    pytest.importorskip("mcap_ros2")
    learned = run([str(rig), "run", "--trials", "2", "--quiet", "--out", str(tmp_path / "run")])
    assert learned.returncode == 0, said(learned)
    done = run([sys.executable, "bench/python/encodings.py", str(tmp_path / "run" / "run.mcap"),
                "--out", str(tmp_path / "enc"), "--repetitions", "1"])
    assert done.returncode == 0, said(done)
    for name in ("json-none", "json-zstd", "cdr-lz4"):
        assert (tmp_path / "enc" / f"{name}.mcap").stat().st_size > 0


def test_systems_stopped_by_sigterm_stops_its_runs_and_drivers(tmp_path: Path, rig: Path) -> None:
    pytest.importorskip("iceoryx2")
    pytest.importorskip("matplotlib")
    matrix = tmp_path / "matrix.toml"
    matrix.write_text(
        '[[experiment]]\nname = "acrobot-balance"\nsystem = "acrobot"\n'
        'task = "examples/acrobot/acrobot-balance.toml"\ndriver = ["examples/acrobot/driver.py"]\n'
        'trials = 400\nsuccess = { upright = 0.3, hold = 1.5 }\n'
        'learners = [{ label = "MLAC/LLR", flags = ["--algo", "mlac"] }]\n'
    )
    out = tmp_path / "out"
    p = subprocess.Popen([sys.executable, "bench/python/systems.py", str(out), "--matrix", str(matrix),
                          "--seeds", "1", "--rig", str(rig)], cwd=ROOT, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not (out / "acrobot-balance" / "mlac-llr" / "seed-1" / "returns.csv").exists():
        assert time.monotonic() < deadline and p.poll() is None, "the run did not start"
        time.sleep(0.1)
    started = descendants(p.pid)
    assert any("examples/acrobot/driver.py" in line for line in started.values()), started
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("error: systems.py: stopped (Ctrl-C or SIGTERM)")
    assert [pid for pid in started if Path(f"/proc/{pid}").exists()] == []


def descendants(pid: int) -> dict[int, str]:
    """The processes `pid` started, and theirs: pid -> command line."""
    parent, line = {}, {}
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                stat = Path(f"/proc/{entry.name}/stat").read_text()
                line[int(entry.name)] = Path(f"/proc/{entry.name}/cmdline").read_bytes().replace(b"\0", b" ").decode()
            except OSError:
                continue
            parent[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found: dict[int, str] = {}
    todo = [pid]
    while todo:
        p = todo.pop()
        for child, up in parent.items():
            if up == p and child not in found:
                found[child] = line[child]
                todo.append(child)
    return found


def test_realtime_default_counts_deadline_misses_as_the_rig_does() -> None:
    pytest.importorskip("mcap")
    sys.path.insert(0, str(ROOT / "bench/scripts"))
    import realtime_default as rd  # type: ignore[import-not-found]

    # Driver samples 0-5, 20 ms apart; the plant took 0, 1, 2 and 5 (3 and 4 too late);
    # the action for 1 shows applied at 2, the one for 0 does not, the one for 2 only at 5.
    samples = [{"seq": k, "t_sample_ns": 20 * k, "last_command": {0: 0, 1: 0, 2: 11}.get(k, 12)} for k in range(6)]
    commands = [{"kind": 2, "seq": 9, "sample_seq": 0, "t_publish_ns": 0}] + [
        {"kind": 1, "seq": 10 + k, "sample_seq": k, "t_publish_ns": 20 * k + 3} for k in (0, 1, 2, 5)
    ]
    measured = [{"t_sample_ns": 20 * k} for k in (0, 1, 2, 5)]
    # 0: next taken 1, not applied (1); 1: next 2, applied (0); 2: next 5, two periods
    # without a sample taken, applied (2); 5: no next sample (not judged).
    assert rd.deadline_misses(samples, commands, measured) == (3, 3, 1)
    assert rd.sample_to_action_ns(samples, commands) == [3, 3, 3, 3]
    assert rd.percentile([5, 1, 4, 2, 3], 0.5) == 3 and rd.percentile(range(1, 101), 0.99) == 99


def test_realtime_default_says_what_is_wrong_in_one_line(tmp_path: Path) -> None:
    pytest.importorskip("iceoryx2")
    pytest.importorskip("mcap")
    script = "bench/scripts/realtime_default.py"
    for args, why in (
        ([str(tmp_path / "absent.toml"), "examples/furuta/driver.py"], "absent.toml"),
        (["examples/furuta/furuta.toml", str(tmp_path / "absent.py")], "absent.py: no such driver script"),
        (["examples/furuta/furuta.toml", "examples/furuta/driver.py", "--seconds", "0"], "--seconds 0.0: must be positive"),
        (["examples/furuta/furuta.toml", "examples/furuta/driver.py", "--out", str(tmp_path)], "exists; give another folder"),
    ):
        done = run(["python", script, *args])
        assert done.returncode == 2 and done.stderr.count("\n") == 1 and why in done.stderr, said(done)
