"""What a script of the rig's needs before it starts, and the end of a script whose
helper thread fails or that is told to stop.

    need("soak.py", modules=["mcap"], tools=["ip", "nft", "nsenter"], root=True)
    interrupt_on_sigterm()          # SIGTERM (a timeout, a scheduler) acts as Ctrl-C
    helpers = Helpers("soak.py")
    helpers.start("faults", chaos)  # a failure interrupts the main thread: its cleanup runs

`need` prints one line naming everything missing and how to install it, and exits 2,
before the script has made anything that would need cleaning up.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import shutil
import signal
import sys
import threading
import traceback
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, NoReturn

# How to install a Python module a script needs (from the repository's root).
MODULES = {
    "rigkit": "pip install ./python",
    "iceoryx2": 'pip install "./python[driver]"',
    "gymnasium": 'pip install "./python[gymnasium]"',
    "mcap": 'pip install "./python[recording]"',
    "numpy": "pip install numpy",
    "matplotlib": "pip install matplotlib==3.11.2",
    "optuna": "pip install -r tune/requirements.txt",
    "tomli_w": "pip install -r tune/requirements.txt",
    "stable_baselines3": "pip install stable-baselines3",
    "mcap_ros2": "pip install mcap-ros2-support",
}
# The Debian package of a program a script runs.
TOOLS = {
    "ip": "iproute2",
    "nft": "nftables",
    "nsenter": "util-linux",
    "unshare": "util-linux",
    "openssl": "openssl",
    "bash": "bash",
}


class Exit(SystemExit):
    """A script's end with a one-line error on stderr and exit status `code`."""


def fail(who: str, message: str, code: int = 2) -> NoReturn:
    """Ends the script: `error: WHO: MESSAGE` on stderr, exit status `code`."""
    print(f"error: {who}: {message}", file=sys.stderr, flush=True)
    raise Exit(code)


def missing(modules: Iterable[str] = (), tools: Iterable[str] = (), root: bool = False) -> list[str]:
    """What of `modules` (importable names), `tools` (programs on PATH) and `root` this
    machine lacks, each with how to install it."""
    lacking = []
    for m in modules:
        if importlib.util.find_spec(m) is None:
            lacking.append(f"the Python module {m} ({MODULES.get(m, f'pip install {m}')})")
    absent = [t for t in tools if shutil.which(t) is None]
    for t in absent:
        lacking.append(f"{t} (apt-get install {TOOLS.get(t, t)})")
    if root and os.geteuid() != 0:
        lacking.append("root (it makes network namespaces)")
    return lacking


def need(who: str, modules: Iterable[str] = (), tools: Iterable[str] = (), root: bool = False) -> None:
    """Ends the script in one line (`fail`) if anything of `missing` lacks."""
    lacking = missing(modules, tools, root)
    if lacking:
        fail(who, "needs " + ", ".join(lacking))


def rig_option(p: argparse.ArgumentParser, default: str | Path) -> None:
    """`--rig PATH`, the rig binary a script runs (`rig_binary` checks it)."""
    p.add_argument("--rig", type=Path, default=Path(default), help=f"the rig binary [default: {default}]")


def rig_binary(who: str, rig: Path) -> Path:
    """`rig` made absolute, or the script's end in one line (`fail`) if it is not an
    executable file."""
    if not (rig.is_file() and os.access(rig, os.X_OK)):
        fail(who, f"--rig {rig}: no such rig binary (cargo build --release -p rig --all-features)")
    return rig.resolve()


def interrupt_on_sigterm() -> None:
    """SIGTERM raises KeyboardInterrupt in the main thread, as Ctrl-C does: the script's
    cleanup (its `finally` blocks) runs whichever way it is told to stop."""
    signal.signal(signal.SIGTERM, signal.default_int_handler)


class Helpers:
    """A script's helper threads. The first to fail says so on stderr (its traceback)
    and interrupts the main thread as Ctrl-C would (KeyboardInterrupt), so that the
    script's cleanup runs; `failure` then names it, for the script's exit. The
    interruption is repeated every half second until the script calls `closing()` (or
    `check()`), which it does first thing in its cleanup: a signal that lands just before
    a blocking call begins would otherwise wait for the call's end."""

    def __init__(self, who: str) -> None:
        self.who = who
        self.failure: str | None = None
        self._main = threading.main_thread().ident
        self._lock = threading.Lock()
        self._closed = threading.Event()

    def start(self, name: str, target: Callable[..., Any], *args: Any) -> threading.Thread:
        """Starts `target(*args)` as helper `name` (a daemon thread)."""
        t = threading.Thread(target=self._body, args=(name, target, args), name=name, daemon=True)
        t.start()
        return t

    def closing(self) -> None:
        """Ends the interruptions: the script is cleaning up."""
        with self._lock:
            self._closed.set()

    def _body(self, name: str, target: Callable[..., Any], args: tuple[Any, ...]) -> None:
        try:
            target(*args)
        except BaseException as e:  # noqa: BLE001 - any failure ends the script
            with self._lock:
                first = self.failure is None and not self._closed.is_set()
                if self.failure is None:
                    self.failure = f"{name}: {type(e).__name__}: {e}"
            traceback.print_exc()
            while first and self._main is not None:
                with self._lock:
                    if self._closed.is_set():
                        return
                    signal.pthread_kill(self._main, signal.SIGINT)
                self._closed.wait(0.5)

    def check(self) -> None:
        """Ends the interruptions (`closing`), then the script (`fail`, status 1) if a
        helper failed."""
        self.closing()
        if self.failure is not None:
            fail(self.who, f"helper thread {self.failure}", 1)
