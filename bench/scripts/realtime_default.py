#!/usr/bin/env python3
"""The rig's default learner in real time against a model driver: can it decide within
the sampling period?

Usage (Python with rigkit, iceoryx2 and mcap: `pip install "./python[driver,recording]"`;
a release rig):

    bench/scripts/realtime_default.py TASK DRIVER [--seconds 600] [--out DIR]
                                      [--rig PATH] [--python PATH] [--driver-flag F ...]
                                      [--rig-flag F ...]

    bench/scripts/realtime_default.py examples/furuta/furuta-swing-balance.toml examples/furuta/driver.py
    bench/scripts/realtime_default.py examples/acrobot/acrobot.toml examples/acrobot/driver.py --seconds 60

It starts the model driver DRIVER (a driver on rigkit.model_driver) on the realtime clock
at the task's own sampling time (`--clock realtime --task TASK`, real time: speed 1),
then `rig run --plant external --task TASK` with the rig's default learner for the task
(no --algo, no --config: the rig chooses it from the task file), learning trials until
`--seconds` of wall time have passed; then it stops the run as Ctrl-C does (the
recording and returns.csv are finished with every complete trial) and the driver. From
the run's own outputs (DIR/run: run.mcap, returns.csv, gaps.csv) it prints, and writes
to DIR/figures.json:

* the agent's step (receiving the state estimate to publishing the action,
  /timing/agent/action), median and 99th percentile;
* sample to action: from the driver's sample instant (/driver/sample `t_sample_ns`) to
  the ACTION answering it leaving the rig (/driver/command `t_publish_ns`), median and
  99th percentile;
* deadlines missed, as the rig counts them (runtime/src/process/plant/external.rs): for
  each action, the periods without a sample before the driver's next sample, plus one if
  that sample does not show the action applied (`last_command`); the rig's own count from
  its summary beside it when the run printed one;
* trials learned (rows of returns.csv), trial attempts cut by gaps and redone (rows of
  gaps.csv), and the last greedy return with the trial it followed.

What it needs is checked before it starts (one line naming what is missing). Ctrl-C or
SIGTERM stops the run and the driver it started, and exits 130 without figures. A run
that ends before `--seconds` (the rig gives up when the loop cannot keep the period:
docs/run.md, "Gaps: cut and redone") gets its figures up to there, then the rig's last
line as a one-line error, exit 1.
"""
import argparse
import bisect
import importlib.util
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: its PyPI twin, as rigkit.task
    import tomli as tomllib

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: realtime_default.py needs the rig's Python package rigkit: pip install ./python")

from rigkit import processes, recording, returns, script  # noqa: E402
from rigkit.task import Task, TaskError  # noqa: E402

WHO = "realtime_default.py"
ROOT = Path(__file__).resolve().parents[2]
# Trials asked of the run: more than any run of --seconds can learn; the clock ends it.
TRIALS = 1_000_000
PROGRESS_S = 30.0


def percentile(values, q):
    """The nearest-rank q-quantile (0 < q <= 1) of `values` (not empty)."""
    s = sorted(values)
    return s[max(0, math.ceil(q * len(s)) - 1)]


def deadline_misses(samples, commands, measured):
    """Deadlines missed, as the rig's plant process counts them: for each ACTION, the
    periods between the sample it answers and the next sample the plant process took
    (a sample it did not take in time counts as a period without one), and one more if
    that sample does not show the action applied (`last_command`). `samples`,
    `commands`, `measured`: the recorded /driver/sample, /driver/command and
    /timing/plant/measurement messages. Returns (misses, actions judged, of them not
    applied by the next sample)."""
    seq_at = {s["t_sample_ns"]: s["seq"] for s in samples}
    taken = sorted(seq_at[m["t_sample_ns"]] for m in measured if m["t_sample_ns"] in seq_at)
    last_command = {s["seq"]: s["last_command"] for s in samples}
    misses = judged = unapplied = 0
    for c in commands:
        if c["kind"] != 1:
            continue
        i = bisect.bisect_right(taken, c["sample_seq"])
        if i == len(taken):
            continue  # the run ended before the next sample
        nxt = taken[i]
        judged += 1
        late = last_command[nxt] != c["seq"]
        unapplied += late
        misses += nxt - c["sample_seq"] - 1 + late
    return misses, judged, unapplied


def sample_to_action_ns(samples, commands):
    """Per ACTION: its publication by the rig after the instant of the sample it answers."""
    t_sample = {s["seq"]: s["t_sample_ns"] for s in samples}
    return [c["t_publish_ns"] - t_sample[c["sample_seq"]] for c in commands
            if c["kind"] == 1 and c["sample_seq"] in t_sample]


def figures(run_dir, summary):
    """The figures of the run in `run_dir`; `summary`: what `rig run` printed."""
    rec = recording.read(run_dir / "run.mcap", [recording.AGENT_TIMING, recording.PLANT_TIMING,
                                                recording.DRIVER_SAMPLE, recording.DRIVER_COMMAND])
    samples, commands = rec.of(recording.DRIVER_SAMPLE), rec.of(recording.DRIVER_COMMAND)
    steps = recording.agent_steps_ns(rec.of(recording.AGENT_TIMING))
    latency = sample_to_action_ns(samples, commands)
    if not steps or not latency:
        script.fail(WHO, f"{run_dir / 'run.mcap'}: no action recorded (see {run_dir.parent / 'rig.log'})", 1)
    misses, judged, unapplied = deadline_misses(samples, commands, rec.of(recording.PLANT_TIMING))
    rows = returns.read(run_dir / "returns.csv")
    greedy = [r for r in rows if r.greedy is not None]
    gaps = len((run_dir / "gaps.csv").read_text().splitlines()) - 1
    said = [line for line in summary.splitlines() if "deadline misses:" in line]
    return {
        "agent_step_ms": {"p50": percentile(steps, 0.5) / 1e6, "p99": percentile(steps, 0.99) / 1e6, "n": len(steps)},
        "sample_to_action_ms": {"p50": percentile(latency, 0.5) / 1e6, "p99": percentile(latency, 0.99) / 1e6,
                                "n": len(latency)},
        "deadline_misses": {"missed": misses, "actions": judged, "not_applied_by_next_sample": unapplied,
                            "rig_summary": said[0].split("deadline misses:")[1].strip() if said else None},
        "trials_learned": len(rows),
        "attempts_cut_by_gaps": gaps,
        "last_greedy": {"trial": greedy[-1].trial, "return": greedy[-1].greedy} if greedy else None,
    }


def learner_of(said, config):
    """The learner as `rig run` names it in its log (`learner: ... — why`), else the
    configuration's algorithm and approximator."""
    for line in said.splitlines():
        if line.startswith("learner: "):
            return line[len("learner: "):].split(" — ")[0]
    return f"{config['algo']}/{config['approx']}"


def report(head, f):
    """The figures as printed."""
    a, s, d, g = f["agent_step_ms"], f["sample_to_action_ms"], f["deadline_misses"], f["last_greedy"]
    rig_said = f"; the rig's summary: {d['rig_summary']}" if d["rig_summary"] else ""
    return "\n".join([
        head,
        f"  agent step            p50 {a['p50']:.3f} ms, p99 {a['p99']:.3f} ms ({a['n']} steps)",
        f"  sample -> action      p50 {s['p50']:.3f} ms, p99 {s['p99']:.3f} ms ({s['n']} actions)",
        f"  deadlines missed      {d['missed']} ({d['not_applied_by_next_sample']} of {d['actions']} actions "
        f"not applied by the next sample, the rest periods without a sample taken){rig_said}",
        f"  trials learned        {f['trials_learned']} ({f['attempts_cut_by_gaps']} attempts cut by gaps and redone)",
        "  last greedy return    " + (f"{g['return']:.1f} (after trial {g['trial']})" if g else "none (no evaluation yet)"),
    ])


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    p.add_argument("task", type=Path, help="the task file, e.g. examples/furuta/furuta-swing-balance.toml")
    p.add_argument("driver", type=Path, help="its model driver, e.g. examples/furuta/driver.py (run with --clock realtime)")
    p.add_argument("--seconds", type=float, default=600.0, help="wall time to learn for [default: 600]")
    p.add_argument("--out", type=Path, help="where the run and figures.json go (must not exist) "
                   "[default: out/realtime-default/TASK-NAME]")
    script.rig_option(p, ROOT / "target/release/rig")
    p.add_argument("--python", default=sys.executable, help="the Python that runs the driver [default: this one]")
    p.add_argument("--driver-flag", action="append", default=[], metavar="F",
                   help="a further flag for the driver, e.g. --driver-flag=--realtime-priority=10 (repeatable)")
    p.add_argument("--rig-flag", action="append", default=[], metavar="F",
                   help="a further flag for `rig run` that names no learner, e.g. --rig-flag=--rt-priority=20 "
                        "(repeatable)")
    args = p.parse_args()
    script.need(WHO, modules=["iceoryx2", "mcap"])
    if not (math.isfinite(args.seconds) and args.seconds > 0):
        script.fail(WHO, f"--seconds {args.seconds}: must be positive")
    try:
        task = Task.read(args.task)
    except TaskError as e:
        script.fail(WHO, f"{e}")
    if not args.driver.is_file():
        script.fail(WHO, f"{args.driver}: no such driver script")
    out = (args.out or ROOT / "out/realtime-default" / task.name).resolve()
    if out.exists():
        script.fail(WHO, f"--out {out}: exists; give another folder")
    rig = script.rig_binary(WHO, args.rig)
    out.mkdir(parents=True)
    script.interrupt_on_sigterm()
    driver_id = f"realtime-default-{os.getpid()}"
    run_dir = out / "run"
    driver = run = None
    ended = None  # why the run ended before --seconds, if it did
    try:
        with open(out / "driver.log", "w") as log:
            driver = processes.start(
                [args.python, str(args.driver), "--clock", "realtime", "--task", str(args.task),
                 "--driver-id", driver_id, *args.driver_flag], stdout=log, stderr=subprocess.STDOUT)
        with open(out / "rig.log", "w") as log:
            run = processes.start(
                [str(rig), "run", "--plant", "external", "--driver", driver_id, "--driver-timeout", "30",
                 "--task", str(args.task), "--trials", str(TRIALS), "--out", str(run_dir), *args.rig_flag],
                stdout=log, stderr=subprocess.STDOUT)
        t0 = time.monotonic()
        next_progress = t0 + PROGRESS_S
        while time.monotonic() - t0 < args.seconds:
            if run.poll() is not None:
                tail = (out / "rig.log").read_text().strip().splitlines()[-1:]
                ended = f"rig run ended early ({run.returncode}): {' '.join(tail)} (see {out / 'rig.log'})"
                break
            if driver.poll() is not None:
                script.fail(WHO, f"the driver ended early ({driver.returncode}): see {out / 'driver.log'}", 1)
            if time.monotonic() >= next_progress:
                print(f"{WHO}: {time.monotonic() - t0:.0f} s, {returns.count(run_dir / 'returns.csv')} trials",
                      file=sys.stderr, flush=True)
                next_progress += PROGRESS_S
            time.sleep(0.5)
        wall = time.monotonic() - t0
        load = os.getloadavg()
        if ended is None:
            processes.stop(run)  # as Ctrl-C: every complete trial recorded
        run = None
        processes.stop(driver)
        driver = None
    except KeyboardInterrupt:
        print(f"{WHO}: interrupted", file=sys.stderr)
        return 130
    finally:
        for child in (run, driver):
            if child is not None:
                processes.stop(child)
    if ended is not None and not (run_dir / "run.mcap").is_file():
        script.fail(WHO, ended, 1)
    said = (out / "rig.log").read_text()
    learner = learner_of(said, tomllib.loads((run_dir / "config.toml").read_text()))
    f = figures(run_dir, said)
    f.update(task=task.name, learner=learner, ts_ms=task.ts * 1e3, wall_s=wall, load_average=list(load),
             ended_early=ended)
    (out / "figures.json").write_text(json.dumps(f, indent=2) + "\n")
    head = (f"{task.name}: {learner} (the rig's default for the task), Ts {task.ts * 1e3:g} ms, real time, "
            f"{wall:.0f} s wall; load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
            + (f"; driver flags {' '.join(args.driver_flag)}" if args.driver_flag else "")
            + (f"; rig flags {' '.join(args.rig_flag)}" if args.rig_flag else ""))
    print(report(head, f))
    print(f"(run, logs and figures.json in {out})")
    if ended is not None:  # the figures of what it did, then why it stopped
        script.fail(WHO, ended, 1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
