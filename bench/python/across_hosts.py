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
Needs root, iproute2, util-linux and `pip install mcap`.
"""

import argparse
import csv
import os
import platform
import shutil
import signal
import subprocess
import sys
import time

from mcap.reader import make_reader
import json


def quantiles(values):
    v = sorted(values)
    if not v:
        return "none"
    q = lambda p: v[min(len(v) - 1, max(0, int(-(-p * len(v) // 1)) - 1))] * 1e-6
    return f"n {len(v)}, p50 {q(0.5):.3f} ms, p99 {q(0.99):.3f} ms, p99.9 {q(0.999):.3f} ms, max {v[-1] * 1e-6:.3f} ms"


def sample_to_command(mcap_path):
    """Per ACTION command: its t_publish_ns minus the answered sample's t_sample_ns."""
    sampled, delays = {}, []
    with open(mcap_path, "rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=["/driver/sample", "/driver/command"]):
            m = json.loads(message.data)
            if channel.topic == "/driver/sample":
                sampled[m["seq"]] = m["t_sample_ns"]
            elif m["kind"] == 1 and m["sample_seq"] in sampled:
                delays.append(m["t_publish_ns"] - sampled[m["sample_seq"]])
    return delays


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


def sh(*args):
    subprocess.run(args, check=True, capture_output=True)


class Hosts:
    """Two network namespaces joined by a veth pair, each with its own shared memory."""

    def __init__(self):
        self.ns = ["rigbench-a", "rigbench-b"]
        for ns in self.ns:
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)
            sh("ip", "netns", "add", ns)
        sh("ip", "link", "add", "vbench-a", "type", "veth", "peer", "name", "vbench-b")
        self.anchors = []
        for ns, dev, addr in zip(self.ns, ["vbench-a", "vbench-b"], ["10.78.0.1", "10.78.0.2"]):
            sh("ip", "link", "set", dev, "netns", ns)
            sh("ip", "-n", ns, "addr", "add", addr + "/24", "dev", dev)
            sh("ip", "-n", ns, "link", "set", dev, "up")
            sh("ip", "-n", ns, "link", "set", "lo", "up")
            self.anchors.append(subprocess.Popen(
                ["ip", "netns", "exec", ns, "unshare", "--mount", "--propagation", "private", "sh", "-c",
                 "mount -t tmpfs tmpfs /dev/shm && mkdir -p /tmp/iceoryx2 && "
                 "mount -t tmpfs tmpfs /tmp/iceoryx2 && exec sleep infinity"]))
        for a in self.anchors:
            while not open(f"/proc/{a.pid}/cmdline", "rb").read().startswith(b"sleep"):
                time.sleep(0.01)

    def on(self, host, args):
        return ["nsenter", "--target", str(self.anchors[host].pid), "--mount", "--net"] + args

    def close(self):
        for a in self.anchors:
            a.kill()
            a.wait()
        for ns in self.ns:
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def stop(p):
    p.send_signal(signal.SIGINT)
    try:
        p.wait(timeout=10)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()


def one_host(rig, out, trials, speed):
    driver = subprocess.Popen([rig, "sim-driver", "--driver-id", "bench", "--speed", str(speed)],
                              stderr=subprocess.DEVNULL)
    try:
        subprocess.run(latency(rig, out, trials), check=True, capture_output=True)
    finally:
        stop(driver)
    return sample_to_command(os.path.join(out, "run", "run.mcap")), stages(out)


def two_hosts(rig, out, trials, speed):
    os.makedirs(out, exist_ok=True)
    users = os.path.join(out, "users.txt")
    with open(os.open(users, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "w") as f:
        f.write("rig:bench-password\n")
    hosts = Hosts()
    procs = []
    try:
        endpoint = ["--driver", "bench", "--endpoint", "tcp/10.78.0.1:7447", "--credentials", users]
        procs.append(subprocess.Popen(hosts.on(0, [rig, "sim-driver", "--driver-id", "bench", "--speed", str(speed)]),
                                      stderr=subprocess.DEVNULL))
        procs.append(subprocess.Popen(hosts.on(0, [rig, "bridge", "driver", *endpoint, "--timing-out",
                                                   os.path.join(out, "delays.csv")]), stderr=subprocess.DEVNULL))
        time.sleep(0.5)
        procs.append(subprocess.Popen(hosts.on(1, [rig, "bridge", "rig", *endpoint, "--same-clock", "--timing-out",
                                                   os.path.join(out, "link.csv")]), stderr=subprocess.DEVNULL))
        time.sleep(0.5)
        subprocess.run(hosts.on(1, latency(rig, out, trials)), check=True, capture_output=True)
    finally:
        for p in reversed(procs):
            stop(p)
        hosts.close()
    with open(os.path.join(out, "delays.csv")) as f:
        arrived = [int(r["sample_to_actuation"]) for r in csv.DictReader(f)]
    link = {}
    with open(os.path.join(out, "link.csv")) as f:
        for r in csv.DictReader(f):
            link.setdefault(r["what"], []).append(int(r["ns"]))
    return sample_to_command(os.path.join(out, "run", "run.mcap")), arrived, link, stages(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--repetitions", type=int, default=3)
    ap.add_argument("--rig", default="target/release/rig")
    a = ap.parse_args()
    if os.geteuid() != 0 or not shutil.which("nsenter"):
        sys.exit("needs root and util-linux's nsenter (network namespaces)")
    rig = os.path.abspath(a.rig)
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
