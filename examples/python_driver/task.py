"""Task files (docs/tasks.md) for drivers written in Python: read one, and compute the
hash a driver advertises in DriverInfo.task_hash, as the rig computes it.

    from task import Task
    task = Task.read("plant/tasks/pendulum.toml")
    task.name, task.ts, task.n, task.m, task.low, task.high, task.hash()

Standard library only (tomllib: Python 3.11 or later; before, `tomli` from PyPI, which
requirements.txt installs there). The checks are the rig's in outline (dimensions,
bounds); the rig checks the rest and names what is wrong.

    python3 task.py FILE...    # prints each file's name and hash
"""

import hashlib
import math
import struct
import sys

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11: the same parser, from PyPI
    import tomli as tomllib


def number(v, where: str) -> float:
    """A task file's number: a TOML number, or a multiple of pi as text ("-8pi")."""
    if isinstance(v, bool):
        raise ValueError(f"{where}: {v!r} is not a number")
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
                    factor = float(k)
                if math.isfinite(factor):
                    return factor * math.pi
    raise ValueError(f"{where}: {v!r} is not a number or a multiple of pi")


def numbers(values, n: int, where: str) -> list:
    """`n` numbers."""
    if len(values) != n:
        raise ValueError(f"{where}: has {len(values)} entries; must have {n}")
    return [number(v, f"{where}[{i}]") for i, v in enumerate(values)]


class Task:
    """The values of a task file the contract and the hash need."""

    def __init__(self, doc: dict):
        self.name = doc["name"]
        self.ts = number(doc["sampling_time"], "sampling_time")
        self.trial_seconds = number(doc["trial_seconds"], "trial_seconds")
        states, actions = doc["state"], doc["action"]
        self.n, self.m = len(states), len(actions)
        self.angles = [bool(s.get("angle", False)) for s in states]
        self.ranges = [
            numbers(s["range"], 2, f"state[{i}].range")
            if "range" in s
            else [-math.pi, math.pi]
            for i, s in enumerate(states)
        ]
        self.low = [number(a["low"], f"action[{j}].low") for j, a in enumerate(actions)]
        self.high = [number(a["high"], f"action[{j}].high") for j, a in enumerate(actions)]
        r = doc["reward"]
        self.q = numbers(r["state_weights"], self.n, "reward.state_weights")
        self.p = numbers(r["action_weights"], self.m, "reward.action_weights")
        self.reference = numbers(r.get("reference", [0.0] * self.n), self.n, "reward.reference")
        self.terminal = numbers(
            r.get("terminal_weights", r["state_weights"]), self.n, "reward.terminal_weights"
        )
        self.starts = [
            numbers(x0, self.n, f"start_states[{k}]") for k, x0 in enumerate(doc["start_states"])
        ]
        o = doc.get("operating_range")
        self.operating_range = None
        if o is not None:
            low = numbers(o["low"], self.n, "operating_range.low")
            high = numbers(o["high"], self.n, "operating_range.high")
            self.operating_range = (list(zip(low, high)), number(o["penalty"], "penalty"))

    @staticmethod
    def read(path: str) -> "Task":
        with open(path, "rb") as f:
            return Task(tomllib.load(f))

    def canonical_bytes(self) -> bytes:
        """The bytes the hash covers (docs/tasks.md, "The task's hash")."""
        out = bytearray(b"rig.task.v1\0" + self.name.encode() + b"\0")

        def nums(values):
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
        return bytes(out)

    def hash(self) -> int:
        """DriverInfo.task_hash: the SHA-256's first 8 bytes, little-endian."""
        return struct.unpack("<Q", hashlib.sha256(self.canonical_bytes()).digest()[:8])[0]


if __name__ == "__main__":
    for path in sys.argv[1:]:
        t = Task.read(path)
        print(f"{path} {t.name} {t.hash():016x}")
