#!/usr/bin/env python3
"""The soak benchmark: a learning run across two hosts under a link that fails.

Usage (as root, with iproute2, util-linux and nftables; Python with rigkit and `mcap`:
`pip install "./python[recording]"`):

    bench/scripts/soak.py [--minutes N | --seconds S] [--rig PATH] [--out DIR]
                          [--seed K] [--speed X] [--trials T]

Two hosts are made of network namespaces joined by a veth pair, each with its own shared
memory (as rig/tests/across_hosts.rs makes them): host A runs `rig sim-driver` and its
`rig bridge driver`, host B the rig's bridge and `rig run --plant external`. For the
first N minutes, at random moments drawn from the seed, the link is cut for 0.1-5 s
(every TCP packet dropped, nftables), loses 10-40 % of its packets for 0.5-3 s, a
`rig bridge probe --zero-actions` tries to command the driver, or a second rig (its own
bridge and `rig run`, a third host on B's network) tries to take it over. Whenever the
run stops, the script resumes it (`rig run --resume DIR --plant external --driver ID`)
once the link is back, until every trial is done. Printed, and written to
DIR/figures.json:

* cuts: how many were made, how many the run survived (it completed a trial after them);
* runs stopped and resumed; trial attempts cut by gaps and redone (`gaps.csv`);
* the longest time to zero action after a cut: from the driver's bridge's own log, the
  time from the last action's arrival to the sample at which the driver's watchdog
  applied the safe action (an engagement after a reset, with no action since, is none);
* probes and second rigs told who holds the driver, and the commands of a second session that reached the
  driver while the run held it (must be 0): values of the driver's `last_command` in the
  recording that the run never sent;
* trials in `returns.csv` with a gap in their recorded samples (must be 0): a learning
  trial whose recorded attempt has a sample flagged GAP, or two consecutive samples more
  than 1.5 periods apart.

What it needs is checked before it starts (one line naming what is missing). Stopped by
Ctrl-C or SIGTERM, or when one of its helper threads (the faults, the watch of
returns.csv) fails, it stops every process it started and removes its hosts before it
exits (130 when stopped, 1 when a helper failed).
"""
import argparse
import bisect
import importlib.util
import json
import os
import random
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: soak.py needs the rig's Python package rigkit: pip install ./python")

from rigkit import script  # noqa: E402
from rigkit import processes, recording, returns  # noqa: E402
from rigkit.hosts import Hosts  # noqa: E402
from rigkit.recording import END, GAP, GREEDY, SHUTDOWN, START  # noqa: E402

WHO = "soak.py"
NEEDS = {"modules": ["mcap"], "tools": ["ip", "nft", "nsenter", "unshare"], "root": True}
DRIVER = "soak"
PORT = 7447
# A rig numbers a session's commands on from its clock at the session's start [ns], one
# by one: numbers within this span after one of a session's are that session's.
OWN_SESSION_SPAN = 10**6


class Soak:
    def __init__(self, args):
        self.args = args
        self.rng = random.Random(args.seed)
        self.out = Path(args.out).resolve()
        self.run_dir = self.out / "run"
        self.hosts = Hosts("soak", args.subnet, {"a": "a", "b": "b", "c": "b"})
        self.endpoint = f"tcp/{self.hosts.addr['a']}:{PORT}"
        self.procs = []
        self.lock = threading.Lock()
        self.link_ok = threading.Event()
        self.link_ok.set()
        self.stop = threading.Event()
        self.events = {"cut": [], "loss": [], "probe": [], "second_rig": []}
        self.attempts = []  # (start monotonic ns, exit code, last line)
        self.rows = []  # (monotonic ns, rows of returns.csv)

    def rig(self, host, args, log=None, timeout=None):
        """`rig ARGS` on `host`: run to its end (its output captured; stopped, with what it
        started, on a timeout or when the script stops), or, with a `log` file, started
        and kept until the script ends."""
        cmd = self.hosts.command(host, [self.args.rig, *args])
        if log is None:
            return processes.run(cmd, timeout=timeout)
        with open(log, "w") as sink:
            p = processes.start(cmd, stdout=subprocess.DEVNULL, stderr=sink,
                                stdin=subprocess.DEVNULL)
        self.procs.append(p)
        return p

    def start(self):
        self.out.mkdir(parents=True, exist_ok=True)
        users = self.out / "users.txt"
        old = os.umask(0o077)
        users.write_text(f"rig:{os.urandom(12).hex()}\nsecond:{os.urandom(12).hex()}\n")
        os.umask(old)
        self.users = str(users)
        second = self.out / "second.txt"
        old = os.umask(0o077)
        second.write_text(users.read_text().splitlines()[1] + "\n")
        os.umask(old)
        self.second_users = str(second)
        speed = ["--speed", str(self.args.speed)]
        self.rig("a", ["sim-driver", "--driver-id", DRIVER, *speed], self.out / "driver.log")
        common = ["--driver", DRIVER, "--endpoint", self.endpoint]
        self.driver_log = self.out / "driver-bridge.log"
        self.rig("a", ["bridge", "driver", *common, "--credentials", self.users],
                 self.driver_log)
        time.sleep(0.5)
        self.rig("b", ["bridge", "rig", *common, "--credentials", self.users],
                 self.out / "rig-bridge.log")
        time.sleep(0.5)

    def chaos(self, until):
        """Cuts, loss bursts, probes and second rigs at random moments until `until`."""
        kinds = ["cut", "cut", "loss", "probe", "second_rig"]
        while not self.stop.is_set() and time.monotonic() < until:
            self.stop.wait(self.rng.uniform(2.0, 8.0))
            if self.stop.is_set() or time.monotonic() >= until:
                return
            kind = self.rng.choice(kinds)
            getattr(self, kind)()

    def cut(self):
        seconds = self.rng.uniform(0.1, 5.0)
        self.link_ok.clear()
        t0 = time.monotonic_ns()
        try:
            self.hosts.drop("soakcut", "meta l4proto tcp counter drop")
            time.sleep(seconds)
        finally:
            self.hosts.undrop("soakcut")
            self.link_ok.set()
        self.events["cut"].append({"start_ns": t0, "end_ns": time.monotonic_ns(),
                                   "seconds": round(seconds, 3)})

    def loss(self):
        percent, seconds = self.rng.randint(10, 40), self.rng.uniform(0.5, 3.0)
        try:
            self.hosts.drop("soakloss", f"meta l4proto tcp numgen random mod 100 < {percent} drop")
            time.sleep(seconds)
        finally:
            self.hosts.undrop("soakloss")
        self.events["loss"].append({"percent": percent, "seconds": round(seconds, 3)})

    def probe(self):
        out = self.rig("b", ["bridge", "probe", "--driver", DRIVER, "--endpoint", self.endpoint,
                             "--credentials", self.second_users, "--zero-actions",
                             "--seconds", "0.3"], timeout=60)
        said = (out.stdout + out.stderr).strip().splitlines()
        self.events["probe"].append({"at_ns": time.monotonic_ns(), "exit": out.returncode,
                                     "held": any("held by" in l for l in said),
                                     "said": said[-1] if said else ""})

    def second_rig(self):
        n = len(self.events["second_rig"])
        bridge = self.rig("c", ["bridge", "rig", "--driver", DRIVER, "--endpoint", self.endpoint,
                                "--credentials", self.second_users],
                          self.out / f"second-bridge-{n}.log")
        time.sleep(0.5)
        try:
            out = self.rig("c", ["run", "--plant", "external", "--driver", DRIVER, "--quiet",
                                 "--trials", "2", "--reset-timeout", "3", "--out",
                                 str(self.out / f"second-{n}")], timeout=60)
            code, said = out.returncode, (out.stdout + out.stderr).strip().splitlines()
        except subprocess.TimeoutExpired:
            code, said = None, ["did not end within 60 s"]
        processes.stop(bridge)
        # Its bridge is told who holds the driver; the run itself sees its reset unanswered.
        told = Path(self.out / f"second-bridge-{n}.log").read_text()
        self.events["second_rig"].append({"exit": code, "said": said[-1] if said else "",
                                          "held": " is held by " in told})

    def watch_rows(self):
        """Notes when `returns.csv` grows."""
        last = -1
        while not self.stop.wait(0.2):
            rows = returns.count(self.run_dir / "returns.csv")
            if rows != last:
                self.rows.append((time.monotonic_ns(), rows))
                last = rows

    def learn(self, hard_limit):
        """Runs, and resumes after each stop, until every trial is done or `hard_limit`."""
        base = ["--plant", "external", "--driver", DRIVER, "--quiet"]
        first = ["run", *base, "--trials", str(self.args.trials), "--out", str(self.run_dir)]
        resume = ["run", *base, "--resume", str(self.run_dir)]
        args, stuck = first, 0
        while time.monotonic() < hard_limit and stuck < 5:
            before = returns.count(self.run_dir / "returns.csv")
            t0 = time.monotonic_ns()
            out = self.rig("b", args)
            lines = (out.stdout + out.stderr).strip().splitlines()
            self.attempts.append({"start_ns": t0, "end_ns": time.monotonic_ns(),
                                  "exit": out.returncode, "said": lines[-1] if lines else ""})
            with open(self.out / "runs.log", "a") as f:
                f.write(f"$ rig {' '.join(args)}\n{out.stdout}{out.stderr}\n")
            if out.returncode == 0:
                return True
            # Five stops in a row without a trial done: something other than the faults.
            stuck = stuck + 1 if returns.count(self.run_dir / "returns.csv") == before else 0
            args = resume
            self.link_ok.wait()
            time.sleep(1.0)
        return False

    def close(self):
        """Every process stopped, newest first (as Ctrl-C would), the hosts removed."""
        for proc in reversed(self.procs):
            processes.stop(proc)
        self.hosts.undrop("soakcut")
        self.hosts.undrop("soakloss")
        self.hosts.remove()

    def figures(self, done):
        log = self.driver_log.read_text()
        zero_ms = [float(m) for m in re.findall(
            r"applies the safe action \(watchdog\) from between .*?, ([0-9.]+) ms\)", log)]
        # When the last trial was done: the first moment the final row count was seen.
        last_growth = min((t for t, r in self.rows if r == self.rows[-1][1]), default=0)
        gaps = read_csv(self.run_dir / "gaps.csv")
        trials = {r.trial for r in returns.read(self.run_dir / "returns.csv")}
        foreign, gap_trials, checked = recorded(self.run_dir / "run.mcap",
                                                self.args.period_ms * 1e6 / self.args.speed,
                                                trials)
        return {
            "done": done,
            "trials": len(trials),
            "cuts": len(self.events["cut"]),
            "cuts_survived": sum(c["end_ns"] < last_growth for c in self.events["cut"]),
            "longest_cut_s": max((c["seconds"] for c in self.events["cut"]), default=0.0),
            "loss_bursts": len(self.events["loss"]),
            "runs_stopped_and_resumed": len(self.attempts) - 1,
            "attempts_cut_by_gaps_and_redone": len(gaps),
            "learning_attempts_cut_by_gaps": sum(g["greedy"] == "0" for g in gaps),
            "longest_ms_to_zero_action_after_a_cut": max(zero_ms, default=None),
            "watchdog_engagements": len(zero_ms),
            "probes": len(self.events["probe"]),
            "probes_told_who_holds": sum(p["held"] for p in self.events["probe"]),
            "second_rigs": len(self.events["second_rig"]),
            "second_rigs_told_who_holds": sum(s["held"] for s in self.events["second_rig"]),
            "second_rigs_that_ran": sum(s["exit"] == 0 for s in self.events["second_rig"]),
            "second_session_commands_reaching_the_driver": foreign,
            "trials_checked_in_recording": checked,
            "trials_in_returns_with_a_gap": gap_trials,
        }


def read_csv(path):
    import csv
    try:
        with open(path) as f:
            return list(csv.DictReader(f))
    except OSError:
        return []


def recorded(path, period_ns, trials):
    """From the recording: commands of another session that the driver applied while the
    run held it, and the learning trials of `trials` (those in returns.csv) whose
    recorded attempt has a gap; and how many of `trials` the recording holds."""
    if not Path(path).exists():
        return None, None, 0
    rec = recording.read(path, [recording.DRIVER_COMMAND, recording.DRIVER_SAMPLE,
                                recording.MEASUREMENT, recording.PLANT_TIMING])
    sent = {m["seq"]: m["t_publish_ns"] for m in rec.of(recording.DRIVER_COMMAND)}
    applied = [(m["t_sample_ns"], m["last_command"]) for m in rec.of(recording.DRIVER_SAMPLE)]
    measured = {m["seq"]: (m["trial"], m["flags"]) for m in rec.of(recording.MEASUREMENT)}
    timing = {m["seq"]: m["t_sample_ns"] for m in rec.of(recording.PLANT_TIMING)}
    foreign = foreign_commands(sent, applied, lease_ns(period_ns))
    # The last attempt of each learning trial is the one in returns.csv.
    attempt, last = [], {}
    for seq in sorted(measured):
        trial, flags = measured[seq]
        if flags & GREEDY:
            continue
        if flags & START:
            attempt = []
        attempt.append((seq, flags))
        if flags & (END | GAP | SHUTDOWN):
            last[trial] = attempt
            attempt = []
    bad = 0
    last = {t: a for t, a in last.items() if t in trials}
    for samples in last.values():
        flagged = any(f & GAP for _, f in samples)
        spans = [timing[b] - timing[a] for (a, _), (b, _) in zip(samples, samples[1:])
                 if a in timing and b in timing]
        if flagged or any(s > 1.5 * period_ns for s in spans):
            bad += 1
    return len(foreign), bad, len(last)


def lease_ns(period_ns):
    """A session's lease at the driver's bridge (docs/across-hosts.md): 10 periods, at
    least 250 ms."""
    return max(10 * period_ns, 250e6)


def foreign_commands(sent, applied, lease):
    """The commands of another session the driver applied while the run held it.
    `sent`: the run's commands, number -> when it published them; `applied`: the driver's
    samples' `(t_sample_ns, last_command)`. The run holds the driver from a sample showing
    a command it published within `lease` before, until it falls silent for longer than
    `lease` (its lease lapses: the driver is free for anyone). The run's own commands that
    a resume dropped from the recording (numbers following one it kept, within its
    session) are not another session's."""
    kept = sorted(sent)
    published = sorted(sent.values())

    def own(c):
        i = bisect.bisect_right(kept, c)
        return i > 0 and c - kept[i - 1] < OWN_SESSION_SPAN

    def heard_throughout(since, t):
        """Whether the run published at least once a lease from `since` to `t`."""
        i = max(bisect.bisect_right(published, since) - 1, 0)
        times = published[i:bisect.bisect_right(published, t)] + [t]
        return times[0] <= since and all(b - a <= lease for a, b in zip(times, times[1:]))

    foreign, holding, before = set(), False, None
    for t, c in sorted(applied):
        holding = holding and heard_throughout(before, t)
        before = t
        if c == 0 or own(c):
            holding = holding or (c in sent and t - sent[c] <= lease)
        elif holding:
            foreign.add(c)
    return foreign


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    span = p.add_mutually_exclusive_group()
    span.add_argument("--minutes", type=float, help="minutes of faults (default 30)")
    span.add_argument("--seconds", type=float, help="seconds of faults (the CI's short soak)")
    script.rig_option(p, "target/release/rig")
    p.add_argument("--out", default="out/soak", help="the output folder (replaced)")
    p.add_argument("--seed", type=int, default=1, help="seed of the faults' moments and kinds")
    p.add_argument("--speed", type=float, default=1.0, help="the driver's speed (sim-driver)")
    p.add_argument("--trials", type=int,
                   help="trials of the run (default: about as many as the faults last)")
    p.add_argument("--period-ms", type=float, default=30.0,
                   help="the task's sampling period at speed 1 [ms]")
    p.add_argument("--subnet", type=int, default=78, help="hosts at 10.SUBNET.0.1 and .2")
    args = p.parse_args()
    script.need(WHO, **NEEDS)
    script.interrupt_on_sigterm()
    args.rig = str(script.rig_binary(WHO, args.rig))
    seconds = args.seconds if args.seconds is not None else 60 * (args.minutes or 30)
    if args.trials is None:
        # A pendulum trial (3 s at speed 1) and its share of greedy evaluations.
        args.trials = max(4, int(seconds * args.speed / 4.0))
    shutil.rmtree(args.out, ignore_errors=True)
    helpers = script.Helpers(WHO)
    try:
        soak = Soak(args)
    except KeyboardInterrupt:
        script.fail(WHO, "stopped while making the hosts (removed again)", 130)
    try:
        soak.start()
        t0 = time.monotonic()
        helpers.start("the watch of returns.csv", soak.watch_rows)
        chaos = helpers.start("the faults", soak.chaos, t0 + seconds)
        done = soak.learn(t0 + 3 * seconds + 300)
        soak.stop.set()
        chaos.join()
        soak.link_ok.wait()
        time.sleep(0.5)
        helpers.closing()
        soak.close()
        figures = soak.figures(done)
        figures["seconds_of_faults"] = seconds
        figures["wall_s"] = round(time.monotonic() - t0, 1)
        figures["seed"] = args.seed
    except KeyboardInterrupt:
        helpers.check()
        script.fail(WHO, "stopped: its processes stopped and its hosts removed", 130)
    finally:
        helpers.closing()
        soak.stop.set()
        soak.close()
    (soak.out / "figures.json").write_text(json.dumps(figures, indent=1) + "\n")
    (soak.out / "events.json").write_text(json.dumps(
        {"faults": soak.events, "runs": soak.attempts}, indent=1) + "\n")
    for k, v in figures.items():
        print(f"{k}: {v}")
    ok = done and figures["second_session_commands_reaching_the_driver"] == 0 \
        and figures["trials_in_returns_with_a_gap"] == 0
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
