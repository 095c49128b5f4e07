"""The search space: a TOML file with one table per configuration key,

    [param."actor.alpha"]          # a float, sampled on a log scale
    low = 0.005
    high = 0.5
    log = true

    [param."critic.memory"]        # an integer (as the preset's value is)
    low = 500
    high = 8000

    [param."learning.gamma"]       # one of a list
    choices = [0.97, 0.99, 0.999]

and the starting space a preset suggests (`rig tune --space-for ALGO`)."""

from __future__ import annotations

import difflib
import math
import textwrap
import tomllib
from dataclasses import dataclass
from collections.abc import Callable
from pathlib import Path
from typing import Any

import optuna

FIELDS = ("low", "high", "log", "int", "step", "choices")


class SpaceError(Exception):
    """A bad space file; the message is one line naming the file and the key."""


@dataclass(frozen=True)
class Param:
    """One configuration key and the values a trial may give it."""

    key: str
    low: float | None = None
    high: float | None = None
    log: bool = False
    integer: bool = False
    step: float | None = None
    choices: tuple[Any, ...] = ()

    def suggest(self, trial: optuna.Trial) -> Any:
        """The value of this key in `trial`."""
        if self.choices:
            return trial.suggest_categorical(self.key, list(self.choices))
        low, high = self.bounds()
        if self.integer:
            return trial.suggest_int(
                self.key, int(low), int(high), step=int(self.step or 1), log=self.log
            )
        return trial.suggest_float(self.key, low, high, step=self.step, log=self.log)

    def bounds(self) -> tuple[float, float]:
        """`(low, high)` of a numeric key (`numeric` always sets both)."""
        assert self.low is not None and self.high is not None, f"{self.key}: not numeric"
        return self.low, self.high

    def extremes(self) -> list[Any]:
        """The values the rig must accept for this key to be searchable."""
        if self.choices:
            return list(self.choices)
        cast = int if self.integer else float
        return [cast(v) for v in self.bounds()]


def load(path: Path, keys: dict[str, Any]) -> list[Param]:
    """Reads a space file; `keys` are the configuration's tunable keys with their preset
    values (which tell a key's type)."""
    try:
        text = path.read_text()
    except OSError as e:
        raise SpaceError(f"{path}: cannot read the space file: {e.strerror}") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SpaceError(f"{path}: not TOML: {e}") from None
    for name in doc:
        if name != "param":
            raise SpaceError(f'{path}: unknown key "{name}"; a space file holds [param."KEY"] tables')
    params = doc.get("param", {})
    if not isinstance(params, dict) or not params:
        raise SpaceError(f'{path}: no [param."KEY"] table; name at least one configuration key')
    return [parse(path, key, spec, keys) for key, spec in params.items()]


def parse(path: Path, key: str, spec: Any, keys: dict[str, Any]) -> Param:
    """One `[param."KEY"]` table."""

    def fail(message: str) -> SpaceError:
        return SpaceError(f'{path}: param "{key}": {message}')

    if key not in keys:
        near = difflib.get_close_matches(key, keys, n=1)
        hint = f' (did you mean "{near[0]}"?)' if near else ""
        raise fail(f"not a configuration key of this learner{hint}; keys: {', '.join(sorted(keys))}")
    if not isinstance(spec, dict):
        raise fail('must be a table: low/high (with log, int, step) or choices')
    for field in spec:
        if field not in FIELDS:
            raise fail(f'unknown field "{field}"; allowed: {", ".join(FIELDS)}')
    preset = keys[key]
    if "choices" in spec:
        return choice(fail, key, spec)
    if isinstance(preset, bool) or not isinstance(preset, (int, float)):
        raise fail(f"the preset's value {preset!r} is not a number: give choices = [...]")
    return numeric(fail, key, spec, integer=spec.get("int", isinstance(preset, int)))


def choice(fail: Callable[[str], Exception], key: str, spec: dict[str, Any]) -> Param:
    """A key that takes one of a list."""
    others = [f for f in spec if f != "choices"]
    if others:
        raise fail(f'choices cannot be given with {", ".join(others)}')
    values = spec["choices"]
    if not isinstance(values, list) or not values:
        raise fail("choices must be a non-empty list")
    if any(isinstance(v, (dict, list)) for v in values):
        raise fail("choices must be numbers, strings or booleans")
    if len(set(map(repr, values))) != len(values):
        raise fail("choices repeat a value")
    return Param(key, choices=tuple(values))


def numeric(fail: Callable[[str], Exception], key: str, spec: dict[str, Any], integer: Any) -> Param:
    """A key that takes a number in [low, high]."""
    for field in ("low", "high"):
        if field not in spec:
            raise fail(f"{field} is missing (or give choices)")
        v = spec[field]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise fail(f"{field} must be a finite number, not {v!r}")
    low, high = spec["low"], spec["high"]
    log, step = spec.get("log", False), spec.get("step")
    if not isinstance(log, bool) or not isinstance(integer, bool):
        raise fail("log and int must be true or false")
    if not low < high:
        raise fail(f"low ({low}) must be below high ({high})")
    if log and low <= 0:
        raise fail(f"a log scale needs low > 0, not {low}")
    if integer and (low != int(low) or high != int(high)):
        raise fail(f"an integer key needs integer bounds, not {low} and {high}")
    if step is not None:
        if isinstance(step, bool) or not isinstance(step, (int, float)) or not step > 0:
            raise fail(f"step must be a number > 0, not {step!r}")
        if log:
            raise fail("step cannot be given with a log scale")
        if integer and step != int(step):
            raise fail(f"an integer key needs an integer step, not {step}")
    return Param(key, low=low, high=high, log=log, integer=integer, step=step)


# The starting space of a preset: per kind of key (its last name), a range around the
# preset's value. Discounts as rl-baselines3-zoo samples them, from a list.
GAMMAS = [0.9, 0.95, 0.97, 0.98, 0.99, 0.995, 0.999]


def suggested(key: str, v: Any) -> dict[str, Any] | None:
    """The starting range of one key, or None if a preset's value is best left alone."""
    name = key.rsplit(".", 1)[-1]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    if name == "gamma":
        return {"choices": sorted(set(GAMMAS) | {v})}
    if name == "lambda":
        return {"low": 0.0, "high": 0.95}
    if name in ("alpha", "sigma") and v > 0:
        f = 10.0 if name == "alpha" else 3.0
        return {"low": v / f, "high": v * f, "log": True}
    if name == "memory" and isinstance(v, int):
        return {"low": max(10, v // 4), "high": v * 4, "log": True}
    if name == "neighbours" and isinstance(v, int):
        return {"low": max(2, v // 2), "high": max(3, v * 2)}
    return None


def toml_value(v: Any) -> str:
    """A number, string, boolean or list as TOML writes it."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(round(v, 12))
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return f'"{v}"' if isinstance(v, str) else repr(v)


def render(key: str, spec: dict[str, Any]) -> str:
    """One `[param."KEY"]` table as text."""
    return "\n".join([f'[param."{key}"]'] + [f"{k} = {toml_value(v)}" for k, v in spec.items()])


def starting_space(keys: dict[str, Any], selection: str) -> str:
    """The search space a preset suggests, as a file to edit."""
    tables, left = [], []
    for key, v in keys.items():
        spec = suggested(key, v)
        if spec is None:
            left.append(key)
        else:
            tables.append(f"# preset: {key} = {toml_value(v)}\n" + render(key, spec))
    head = (
        f"# rig tune search space for {selection}, derived from its preset.\n"
        "# One table per configuration key: low/high (log = true for a log scale, int = true\n"
        "# for integers, step), or choices = [...]. Delete a table to keep the preset's value.\n"
        + textwrap.fill(f"Keys left at the preset: {', '.join(left) if left else 'none'}.", 88,
                        initial_indent="# ", subsequent_indent="# ")
        + "\n"
    )
    return head + "\n" + "\n\n".join(tables) + "\n"
