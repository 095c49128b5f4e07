"""Task files (docs/tasks.md) for drivers written in Python: read one, compute the hash
a driver advertises in DriverInfo.task_hash and the reward, as the rig computes them.

    from rigkit.task import Task, TaskError
    task = Task.read("plant/tasks/pendulum.toml")
    task.name, task.ts, task.n, task.m, task.low, task.high, task.hash()
    task.reward(x, u)          # rho(x, u), the rig's numbers (rigkit.reward)

Standard library only (tomllib: Python 3.11 or later; before, `tomli` from PyPI, which
`pip install ./python` installs there). Every key is checked against the keys the rig
knows: an unknown or missing key is a TaskError of one line naming the file and the key.
The values' checks are the rig's in outline (dimensions, bounds); the rig checks the rest
and names what is wrong.

    python3 -m rigkit.task FILE...          # prints each file's name and hash
    python3 -m rigkit.task --rewards FILE   # rho of each line "x_1 ... x_n | u_1 ... u_m" of stdin
"""

from __future__ import annotations

import hashlib
import math
import struct
import sys
from typing import Any

from .reward import Region, Reward

if sys.version_info >= (3, 11):
    import tomllib
else:  # the same parser, from PyPI
    import tomli as tomllib


class TaskError(ValueError):
    """A task file the rig would refuse: one line naming the file and the key."""


# Each table's keys in the order the rig lists them, and which of them are required.
GOAL_KEYS: tuple[tuple[str, ...], tuple[str, ...]] = (("low", "high", "centre", "radius", "bonus", "reward"), ())
KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "": (
        (
            "name", "description", "sampling_time", "trial_seconds", "start_states", "state",
            "action", "reward", "operating_range", "goal", "start_distribution", "simulation",
        ),
        ("name", "sampling_time", "trial_seconds", "start_states", "state", "action", "reward"),
    ),
    "state": (("name", "unit", "angle", "range"), ("name",)),
    "action": (("name", "unit", "low", "high"), ("name", "low", "high")),
    "reward": (
        (
            "state_weights", "action_weights", "reference", "terminal_weights",
            "cosine_weights", "action_abs_weights", "goal",
        ),
        ("state_weights", "action_weights"),
    ),
    "reward.goal": GOAL_KEYS,
    "goal": GOAL_KEYS,
    "operating_range": (("low", "high", "penalty"), ("low", "high", "penalty")),
    "start_distribution": (("kind", "low", "high", "mean", "std"), ("kind",)),
    "simulation": (("system", "substeps"), ("system", "substeps")),
}


def number(v: object, where: str) -> float:
    """A task file's number: a TOML number, or a multiple of pi as text ("-8pi")."""
    if isinstance(v, bool):
        raise TaskError(f"`{where}`: {v!r} is not a number")
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str):
        s = v.strip()
        for suffix in ("pi", "π"):
            if s.endswith(suffix):
                k = s[: -len(suffix)].strip()
                k = k[:-1].strip() if k.endswith("*") else k
                factor = {"": 1.0, "+": 1.0, "-": -1.0}.get(k)
                if factor is None:
                    try:
                        factor = float(k)
                    except ValueError:
                        break
                if math.isfinite(factor):
                    return factor * math.pi
    raise TaskError(f"`{where}`: {v!r} is not a number or a multiple of pi")


def numbers(values: object, n: int, where: str) -> list[float]:
    """`n` numbers."""
    if not isinstance(values, list) or len(values) != n:
        size = len(values) if isinstance(values, list) else "no"
        raise TaskError(f"`{where}`: has {size} entries; must have {n}")
    return [number(v, f"{where}[{i}]") for i, v in enumerate(values)]


def check_keys(table: object, schema: str, where: str) -> None:
    """Refuses an unknown key and a missing one of `table` (KEYS[schema])."""
    if not isinstance(table, dict):
        raise TaskError(f"`{where or schema}`: must be a table")
    allowed, required = KEYS[schema]
    for key in table:
        if key not in allowed:
            expected = ", ".join(f"`{k}`" for k in allowed)
            at = f"{where}.{key}" if where else key
            raise TaskError(f"`{at}`: unknown key, expected one of {expected}")
    for key in required:
        if key not in table:
            raise TaskError(f"`{f'{where}.{key}' if where else key}`: missing")


def region(g: dict[str, Any], n: int, where: str) -> Region:
    """A goal's box (low, high) or ball (centre, radius)."""
    if "low" in g and "high" in g and "centre" not in g and "radius" not in g:
        return Region("box", numbers(g["low"], n, f"{where}.low"), numbers(g["high"], n, f"{where}.high"))
    if "centre" in g and "radius" in g and "low" not in g and "high" not in g:
        return Region(
            "ball", numbers(g["centre"], n, f"{where}.centre"), numbers(g["radius"], n, f"{where}.radius")
        )
    raise TaskError(f"`{where}`: give a box (`low` and `high`) or a ball (`centre` and `radius`)")


class Task:
    """The values of a task file the contract, the hash and the reward need."""

    def __init__(self, doc: dict[str, Any]) -> None:
        check_keys(doc, "", "")
        self.name = doc["name"]
        self.ts = number(doc["sampling_time"], "sampling_time")
        self.trial_seconds = number(doc["trial_seconds"], "trial_seconds")
        states, actions = doc["state"], doc["action"]
        for i, s in enumerate(states):
            check_keys(s, "state", f"state[{i}]")
        for j, a in enumerate(actions):
            check_keys(a, "action", f"action[{j}]")
        self.n, self.m = len(states), len(actions)
        self.angles = [bool(s.get("angle", False)) for s in states]
        self.ranges = [
            numbers(s["range"], 2, f"state[{i}].range") if "range" in s else [-math.pi, math.pi]
            for i, s in enumerate(states)
        ]
        self.low = [number(a["low"], f"action[{j}].low") for j, a in enumerate(actions)]
        self.high = [number(a["high"], f"action[{j}].high") for j, a in enumerate(actions)]
        self._read_reward(doc["reward"])
        self.starts = [
            numbers(x0, self.n, f"start_states[{k}]") for k, x0 in enumerate(doc["start_states"])
        ]
        self._read_endings(doc)
        self.start_distribution: tuple[str, list[float], list[float]] | None = None
        s = doc.get("start_distribution")
        if s is not None:
            check_keys(s, "start_distribution", "start_distribution")
            names = {"uniform": ("low", "high"), "normal": ("mean", "std")}.get(s["kind"])
            if names is None:
                raise TaskError(f"`start_distribution.kind`: {s['kind']!r} is not `uniform` or `normal`")
            first, second = (numbers(s.get(k), self.n, f"start_distribution.{k}") for k in names)
            self.start_distribution = (s["kind"], first, second)
        if "simulation" in doc:
            check_keys(doc["simulation"], "simulation", "simulation")

    def _read_reward(self, r: dict[str, Any]) -> None:
        check_keys(r, "reward", "reward")
        n, m = self.n, self.m
        self.q = numbers(r["state_weights"], n, "reward.state_weights")
        self.p = numbers(r["action_weights"], m, "reward.action_weights")
        self.reference = numbers(r.get("reference", [0.0] * n), n, "reward.reference")
        self.terminal = numbers(r.get("terminal_weights", r["state_weights"]), n, "reward.terminal_weights")
        cosine = r.get("cosine_weights")
        cosine = None if cosine is None else numbers(cosine, n, "reward.cosine_weights")
        abs_action = r.get("action_abs_weights")
        abs_action = None if abs_action is None else numbers(abs_action, m, "reward.action_abs_weights")
        goal = r.get("goal")
        if goal is not None:
            check_keys(goal, "reward.goal", "reward.goal")
            if "bonus" not in goal:
                raise TaskError("`reward.goal.bonus`: missing")
            goal = (region(goal, n, "reward.goal"), number(goal["bonus"], "reward.goal.bonus"))
        self.reward = Reward(self.q, self.p, self.reference, self.angles, cosine, abs_action, goal)

    def _read_endings(self, doc: dict[str, Any]) -> None:
        o = doc.get("operating_range")
        self.operating_range: tuple[list[tuple[float, float]], float] | None = None
        if o is not None:
            check_keys(o, "operating_range", "operating_range")
            low = numbers(o["low"], self.n, "operating_range.low")
            high = numbers(o["high"], self.n, "operating_range.high")
            self.operating_range = (list(zip(low, high)), number(o["penalty"], "operating_range.penalty"))
        g = doc.get("goal")
        self.goal: tuple[Region, float] | None = None
        if g is not None:
            check_keys(g, "goal", "goal")
            if "reward" not in g:
                raise TaskError("`goal.reward`: missing")
            self.goal = (region(g, self.n, "goal"), number(g["reward"], "goal.reward"))

    @staticmethod
    def read(path: str) -> "Task":
        """The task file at `path`; a TaskError names the file and the key."""
        try:
            with open(path, "rb") as f:
                return Task(tomllib.load(f))
        except TaskError as e:
            raise TaskError(f"{path}: {e}") from None
        except tomllib.TOMLDecodeError as e:
            raise TaskError(f"{path}: not a valid task file: {e}") from None
        except OSError as e:
            raise TaskError(f"{path}: cannot read: {e.strerror}") from None

    def canonical_bytes(self) -> bytes:
        """The bytes the hash covers (docs/tasks.md, "The task's hash")."""
        out = bytearray(b"rig.task.v1\0" + self.name.encode() + b"\0")

        def nums(values: list[float]) -> None:
            for v in values:
                out.extend(struct.pack("<d", v))

        out.extend(struct.pack("<QQ", self.n, self.m))
        nums([self.ts, self.trial_seconds])
        for angle, (lo, hi) in zip(self.angles, self.ranges):
            out.append(1 if angle else 0)
            nums([lo, hi])
        for lo, hi in zip(self.low, self.high):
            nums([lo, hi])
        for v in (self.q, self.p, self.reference, self.terminal):
            nums(v)
        out.extend(struct.pack("<Q", len(self.starts)))
        for x0 in self.starts:
            nums(x0)
        if self.operating_range is None:
            out.append(0)
        else:
            out.append(1)
            limits, penalty = self.operating_range
            for lo, hi in limits:
                nums([lo, hi])
            nums([penalty])
        # Only what the task has of the later keys, each behind its tag.
        r = self.reward
        if r.cosine is not None:
            out.append(1)
            nums(r.cosine)
        if r.abs_action is not None:
            out.append(2)
            nums(r.abs_action)
        for tag, goal in ((3, r.goal), (4, self.goal)):
            if goal is not None:
                out.append(tag)
                out.extend(goal[0].digest())
                nums([goal[1]])
        if self.start_distribution is not None:
            kind, first, second = self.start_distribution
            out.extend([5, 0 if kind == "uniform" else 1])
            for a, b in zip(first, second):
                nums([a, b])
        return bytes(out)

    def hash(self) -> int:
        """DriverInfo.task_hash: the SHA-256's first 8 bytes, little-endian."""
        return int.from_bytes(hashlib.sha256(self.canonical_bytes()).digest()[:8], "little")


def print_rewards(path: str) -> None:
    """rho(x, u) of each stdin line "x_1 ... x_n | u_1 ... u_m", as repr (round trip)."""
    task = Task.read(path)
    for line in sys.stdin:
        if line.strip():
            xs, us = line.split("|")
            print(repr(task.reward([float(v) for v in xs.split()], [float(v) for v in us.split()])))


def main(argv: list[str]) -> int:
    try:
        if argv[:1] == ["--rewards"] and len(argv) == 2:
            print_rewards(argv[1])
            return 0
        for path in argv:
            t = Task.read(path)
            print(f"{path} {t.name} {t.hash():016x}")
    except TaskError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
