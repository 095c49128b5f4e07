"""The learner configuration a study varies: the resolved configuration of `rig config`,
its keys by dotted path (`actor.alpha`, `learning.gamma`)."""

from __future__ import annotations

import copy
import os
import subprocess
import tomllib
from pathlib import Path
from typing import Any

import tomli_w

# Tables and keys that say what is learned and how long, not how: never tuned.
FIXED = ("system", "task", "algo", "approx", "horizon", "run")


class RigError(Exception):
    """The rig refused something; the message is its own one-line error."""


def rig() -> str:
    """The `rig` binary: the one that started the study (`RIG_BIN`), else `rig` on PATH."""
    return os.environ.get("RIG_BIN", "rig")


def rig_config(selection: list[str]) -> dict[str, Any]:
    """The configuration `rig config SELECTION` resolves (preset ← file ← flags)."""
    done = subprocess.run([rig(), "config", *selection], capture_output=True, text=True)
    if done.returncode != 0:
        raise RigError(last_line(done.stderr) or f"rig config exited with {done.returncode}")
    return tomllib.loads(done.stdout)


def last_line(text: str) -> str:
    """The last non-empty line of a program's output (where the rig puts its error)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def tunable(cfg: dict[str, Any]) -> dict[str, Any]:
    """Every key a study may set, by dotted path, with the preset's value."""
    keys: dict[str, Any] = {}

    def walk(table: dict[str, Any], prefix: str) -> None:
        for name, value in table.items():
            key = prefix + name
            if isinstance(value, dict):
                walk(value, key + ".")
            else:
                keys[key] = value

    walk({k: v for k, v in cfg.items() if k not in FIXED}, "")
    return keys


def with_values(cfg: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    """A copy of `cfg` with each dotted key set to its value."""
    out = copy.deepcopy(cfg)
    for key, value in values.items():
        *tables, leaf = key.split(".")
        table = out
        for name in tables:
            table = table[name]
        table[leaf] = value
    return out


def write(cfg: dict[str, Any], path: Path) -> Path:
    """Writes `cfg` as a TOML file `rig learn --config` and `rig run --config` take."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".part")
    tmp.write_text(tomli_w.dumps(cfg))
    tmp.replace(path)
    return path


def accepted(cfg: dict[str, Any], scratch: Path) -> str | None:
    """None if the rig accepts `cfg`, else its one-line error."""
    try:
        rig_config(["--config", str(write(cfg, scratch))])
    except RigError as e:
        return str(e)
    return None
