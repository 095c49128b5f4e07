"""Hosts on one machine, for the benchmarks across hosts: network namespaces joined by a
veth pair (networks "a" and "b", addresses 10.SUBNET.0.1 and .2), and on them hosts, each
a mount namespace with its own /dev/shm and /tmp/iceoryx2 — iceoryx2's shared memory —
held by an anchor process (as rig/tests/across_hosts.rs makes them). Needs root,
iproute2 and util-linux (nsenter, unshare); `drop` needs nftables.

    hosts = Hosts("soak", subnet=78, hosts={"a": "a", "b": "b", "c": "b"})
    try:
        subprocess.run(hosts.command("a", ["rig", "sim-driver"]))
    finally:
        hosts.remove()
"""

from __future__ import annotations

import os
import subprocess
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

NETWORKS = ("a", "b")
# How long an anchor may take to hold its host's memory [s].
ANCHOR_S = 10.0


def sh(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    """Runs a command, raising with its stderr when it fails (and `check`)."""
    out = subprocess.run(args, capture_output=True, text=True)
    if check and out.returncode != 0:
        raise RuntimeError(f"{' '.join(args)}: {out.stderr.strip()}")
    return out


class Hosts:
    """`hosts` (name -> its network, "a" or "b"), tagged `prefix` and this process's id
    in the names of the namespaces and devices. Whatever the constructor made is removed
    again if it fails part way; `remove()` removes it all."""

    def __init__(self, prefix: str, subnet: int, hosts: Mapping[str, str] | None = None) -> None:
        tag = str(os.getpid() % 100000)
        self.ns = {n: f"{prefix}{n}{tag}" for n in NETWORKS}
        self.dev = {n: f"v{prefix[:4]}{n}{tag}" for n in NETWORKS}
        self.addr = {n: f"10.{subnet}.0.{k + 1}" for k, n in enumerate(NETWORKS)}
        self.anchors: dict[str, subprocess.Popen[Any]] = {}
        self.made: list[str] = []
        try:
            self._make(hosts or {n: n for n in NETWORKS})
        except BaseException:
            self.remove()
            raise

    def _make(self, hosts: Mapping[str, str]) -> None:
        for n in NETWORKS:
            sh("ip", "netns", "add", self.ns[n])
            self.made.append(self.ns[n])
        sh("ip", "link", "add", self.dev["a"], "type", "veth", "peer", "name", self.dev["b"])
        for n in NETWORKS:
            ns, dev = self.ns[n], self.dev[n]
            sh("ip", "link", "set", dev, "netns", ns)
            sh("ip", "-n", ns, "addr", "add", f"{self.addr[n]}/24", "dev", dev)
            sh("ip", "-n", ns, "link", "set", dev, "up")
            sh("ip", "-n", ns, "link", "set", "lo", "up")
        for host, net in hosts.items():
            self.anchors[host] = subprocess.Popen(
                ["ip", "netns", "exec", self.ns[net], "unshare", "--mount", "--propagation", "private",
                 "sh", "-c", "mount -t tmpfs tmpfs /dev/shm && mkdir -p /tmp/iceoryx2 && "
                 "mount -t tmpfs tmpfs /tmp/iceoryx2 && exec sleep infinity"],
                stdin=subprocess.DEVNULL)
        deadline = time.monotonic() + ANCHOR_S
        for host, p in self.anchors.items():
            while not Path(f"/proc/{p.pid}/cmdline").read_bytes().startswith(b"sleep"):
                if p.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"host {host}: its shared memory could not be made (exit {p.poll()})")
                time.sleep(0.01)

    def command(self, host: str, args: Sequence[str]) -> list[str]:
        """`args` as a command that runs on `host`."""
        return ["nsenter", "--target", str(self.anchors[host].pid), "--mount", "--net", *args]

    def drop(self, table: str, rule: str) -> None:
        """Both networks drop the packets they send that `rule` matches (nftables table
        `table`, until `undrop`)."""
        for n in NETWORKS:
            nft = ["ip", "netns", "exec", self.ns[n], "nft"]
            sh(*nft, "add", "table", "inet", table)
            sh(*nft, "add", "chain", "inet", table, "out", "{ type filter hook output priority 0; }")
            sh(*nft, "add", "rule", "inet", table, "out", *rule.split())

    def undrop(self, table: str) -> None:
        for n in NETWORKS:
            if self.ns[n] in self.made:
                sh("ip", "netns", "exec", self.ns[n], "nft", "delete", "table", "inet", table, check=False)

    def remove(self) -> None:
        """The anchors stopped (the hosts' memory goes with them), the namespaces and the
        veth pair (which goes with them) removed."""
        for p in self.anchors.values():
            if p.poll() is None:
                p.kill()
            p.wait()
        for ns in self.made:
            sh("ip", "netns", "del", ns, check=False)
        self.made = []
