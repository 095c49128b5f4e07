"""The test bootstrap: the package is imported from this source tree (python/, first on
sys.path, and on PYTHONPATH for the scripts the tests run), so that the tests test the
code beside them, installed or not; `rig tune`'s package from tune/, where `rig tune`
runs it. `RIG` names the rig binary for the tests that run it (rig/tests/python.rs sets
it); without it they are skipped."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1]
ROOT = PACKAGE.parent
sys.path.insert(0, str(PACKAGE))
sys.path.insert(1, str(ROOT / "tune"))
os.environ["PYTHONPATH"] = os.pathsep.join([str(PACKAGE), *filter(None, [os.environ.get("PYTHONPATH")])])


@pytest.fixture
def rig() -> Path:
    """The rig binary under test (`RIG`), or the test is skipped."""
    path = os.environ.get("RIG")
    if not path:
        pytest.skip("RIG is not set (the rig binary: rig/tests/python.rs sets it)")
    return Path(path)


def run(args: list[str], timeout: float = 300, **kw: object) -> subprocess.CompletedProcess[str]:
    """`args` from the repository's root, output captured; the Python scripts run by this
    interpreter."""
    argv = [sys.executable, *args[1:]] if args[0] == "python" else args
    return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=timeout, **kw)  # type: ignore[call-overload, no-any-return]


def said(done: subprocess.CompletedProcess[str]) -> str:
    return done.stdout + done.stderr
