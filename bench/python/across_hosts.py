#!/usr/bin/env python3
"""The loop's latency across two hosts against the same run on one host.

Usage (as root): python3 bench/python/across_hosts.py OUT [--trials N] [--speed S]
                 [--repetitions R] [--rig target/release/rig]

Runs R times each, alternating:
  * one host: `rig sim-driver` and `rig run --plant external` side by side;
  * two hosts: two network namespaces joined by a veth pair, each with its own
    /dev/shm and /tmp/iceoryx2 (as rig/tests/across_hosts.rs makes them); the driver and
    `rig bridge driver` on one, `rig bridge rig --same-clock` and the rig on the other.
Both are the default pendulum experiment (N trials) against a driver at S × real time.

Each run is `rig latency --driver` (the loop against the driver, recorded, its stages
per cycle in latency.csv). Per run it reads, with the official `mcap` reader, the
recording's driver samples and commands and takes, per action, sample -> action
published by the rig (t_sample_ns of the sample the action answers to the command's
t_publish_ns; one clock: across, the hosts share the machine's), a check of `rig
latency`'s own `sample_to_command`. Across hosts it also reads the driver's bridge's
`--timing-out` file (sample -> action arrived beside the driver, the driver's clock) and
the rig's bridge's (ping round trips, one-way hops). Prints p50 / p99 / p99.9 of each
and of every stage of `rig latency`, pooled over the repetitions, and the machine;
writes OUT/summary.txt.
Needs root, iproute2, util-linux and rigkit with mcap (`pip install "./python[recording]"`),
checked before it starts. Stopped by Ctrl-C or SIGTERM, it stops every process it
started and removes its hosts.
"""

import argparse
import csv
import importlib.util
import os
import platform
import subprocess
import sys
import time

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: across_hosts.py needs the rig's Python package rigkit: pip install ./python")

from rigkit import script  # noqa: E402
from rigkit import processes, recording  # noqa: E402
from rigkit.hosts import Hosts  # noqa: E402

WHO = "across_hosts.py"


def quantiles(values):
    v = sorted(values)
    if not v:
        return "none"
    q = lambda p: v[min(len(v) - 1, max(0, int(-(-p * len(v) // 1)) - 1))] * 1e-6
    return f"n {len(v)}, p50 {q(0.5):.3f} ms, p99 {q(0.99):.3f} ms, p99.9 {q(0.999):.3f} ms, max {v[-1] * 1e-6:.3f} ms"


def sample_to_command(mcap_path):
    """Per ACTION command: its t_publish_ns minus the answered sample's t_sample_ns."""
    rec = recording.read(mcap_path, [recording.DRIVER_SAMPLE, recording.DRIVER_COMMAND])
    sampled = {m["seq"]: m["t_sample_ns"] for m in rec.of(recording.DRIVER_SAMPLE)}
    return [m["t_publish_ns"] - sampled[m["sample_seq"]] for m in rec.of(recording.DRIVER_COMMAND)
            if m["kind"] == 1 and m["sample_seq"] in sampled]


def latency(rig, out, trials):
    """`rig latency --driver bench` for `trials` trials into `out` (a command line)."""
    return [rig, "latency", "--driver", "bench", "--cycles", str(trials * 101), "--raw-samples", "2000",
            "--out", out]


def stages(out):
    """Every stage of OUT/latency.csv: name -> its values (ns) where measured."""
    found = {}
    with open(os.path.join(out, "latency.csv")) as f:
        reader = csv.DictReader(f)
        names = [n for n in reader.fieldnames if not n.startswith("t_") and not n.endswith("_ns")
                 and n not in ("seq", "deadline_miss")]
        for r in reader:
            for n in names:
                if r[n]:
                    found.setdefault(n, []).append(int(r[n]))
    return found


def one_host(rig, out, trials, speed):
    driver = processes.start([rig, "sim-driver", "--driver-id", "bench", "--speed", str(speed)],
                             stderr=subprocess.DEVNULL)
    try:
        checked(processes.run(latency(rig, out, trials)))
    finally:
        processes.stop(driver)
    return sample_to_command(os.path.join(out, "run", "run.mcap")), stages(out)


def two_hosts(rig, out, trials, speed):
    os.makedirs(out, exist_ok=True)
    users = os.path.join(out, "users.txt")
    with open(os.open(users, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "w") as f:
        f.write("rig:bench-password\n")
    hosts = Hosts("rigbench", 78)
    procs = []
    quiet = {"stderr": subprocess.DEVNULL}
    try:
        endpoint = ["--driver", "bench", "--endpoint", f"tcp/{hosts.addr['a']}:7447", "--credentials", users]
        procs.append(processes.start(
            hosts.command("a", [rig, "sim-driver", "--driver-id", "bench", "--speed", str(speed)]), **quiet))
        procs.append(processes.start(hosts.command("a", [rig, "bridge", "driver", *endpoint, "--timing-out",
                                                         os.path.join(out, "delays.csv")]), **quiet))
        time.sleep(0.5)
        procs.append(processes.start(hosts.command("b", [rig, "bridge", "rig", *endpoint, "--same-clock",
                                                         "--timing-out", os.path.join(out, "link.csv")]), **quiet))
        time.sleep(0.5)
        checked(processes.run(hosts.command("b", latency(rig, out, trials))))
    finally:
        for p in reversed(procs):
            processes.stop(p)
        hosts.remove()
    with open(os.path.join(out, "delays.csv")) as f:
        arrived = [int(r["sample_to_actuation"]) for r in csv.DictReader(f)]
    link = {}
    with open(os.path.join(out, "link.csv")) as f:
        for r in csv.DictReader(f):
            link.setdefault(r["what"], []).append(int(r["ns"]))
    return sample_to_command(os.path.join(out, "run", "run.mcap")), arrived, link, stages(out)


def checked(done):
    """A finished `rig latency`: ends the script with its last line if it failed."""
    if done.returncode != 0:
        lines = (done.stdout + done.stderr).strip().splitlines()
        script.fail(WHO, f"`{' '.join(done.args)}` exited with {done.returncode}: {lines[-1] if lines else ''}", 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--repetitions", type=int, default=3)
    script.rig_option(ap, "target/release/rig")
    a = ap.parse_args()
    script.need(WHO, modules=["mcap"], tools=["ip", "nsenter", "unshare"], root=True)
    script.interrupt_on_sigterm()
    rig = str(script.rig_binary(WHO, a.rig))
    try:
        measured = repetitions(a, rig)
    except KeyboardInterrupt:
        script.fail(WHO, "stopped: its processes stopped and its hosts removed", 130)
    summary(a, *measured)


def repetitions(a, rig):
    """The one-host and two-host runs, alternating: what `summary` prints."""
    local, across, arrived, link, stage_one, stage_two = [], [], [], {}, {}, {}
    for r in range(a.repetitions):
        s, st = one_host(rig, os.path.join(a.out, f"one-{r}"), a.trials, a.speed)
        local += s
        for k, v in st.items():
            stage_one.setdefault(k, []).extend(v)
        s, d, l, st = two_hosts(rig, os.path.join(a.out, f"two-{r}"), a.trials, a.speed)
        across += s
        arrived += d
        for k, v in l.items():
            link.setdefault(k, []).extend(v)
        for k, v in st.items():
            stage_two.setdefault(k, []).extend(v)
        print(f"repetition {r + 1} of {a.repetitions} done", file=sys.stderr)
    return local, across, arrived, link, stage_one, stage_two


def summary(a, local, across, arrived, link, stage_one, stage_two):
    """Prints the figures and writes OUT/summary.txt."""
    lines = [
        f"machine: {platform.node()}, {os.cpu_count()} CPUs, {platform.platform()}, load {os.getloadavg()}",
        f"{a.repetitions} repetitions each, alternating; {a.trials} trials of the default experiment; "
        f"driver: rig sim-driver at {a.speed} x real time",
        "",
        "one host (no network):",
        f"  sample -> action published by the rig:      {quantiles(local)}",
        "two hosts (veth between two network namespaces, one clock):",
        f"  sample -> action published by the rig:      {quantiles(across)}",
        f"  sample -> action arrived beside the driver: {quantiles(arrived)}",
        f"  ping round trip (network + bridges):        {quantiles(link.get('ping_round_trip', []))}",
        f"  one way rig -> driver (bridge to bridge):   {quantiles(link.get('command_hop', []))}",
        f"  one way driver -> rig (bridge to bridge):   {quantiles(link.get('sample_hop', []))}",
        "",
        "rig latency --driver, its stages (one host | two hosts):",
    ]
    for name in list(stage_one) + [n for n in stage_two if n not in stage_one]:
        lines.append(f"  {name:<20} one: {quantiles(stage_one.get(name, []))}")
        lines.append(f"  {'':<20} two: {quantiles(stage_two.get(name, []))}")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(a.out, "summary.txt"), "w") as f:
        f.write(text + "\n")


if __name__ == "__main__":
    main()
