"""`rig tune`'s helpers (tune/rig_tune) on rigkit: the check's runs in parallel end at
the first failure, the others stopped at once, not after they finish."""

import time
from pathlib import Path

import pytest


pytest.importorskip("optuna")
pytest.importorskip("tomli_w")

from rig_tune.check import in_parallel  # type: ignore[import-not-found]  # noqa: E402
from rig_tune.runner import Runner, RunFailed  # type: ignore[import-not-found]  # noqa: E402

# A rig whose `learn` fails at once for seed 1002 and runs for half a minute otherwise.
FAKE_RIG = """#!/bin/sh
while [ $# -gt 0 ]; do
  case "$1" in
    --seed) seed=$2; shift ;;
    --out) out=$2; shift ;;
  esac
  shift
done
if [ "$seed" = 1002 ]; then echo "error: made to fail" >&2; exit 2; fi
echo $$ > "$out/pid"
exec sleep 30
"""


def test_the_first_failed_run_stops_the_others(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    rig = tmp_path / "rig"
    rig.write_text(FAKE_RIG)
    rig.chmod(0o755)
    monkeypatch.setenv("RIG_BIN", str(rig))
    config = tmp_path / "config.toml"
    config.write_text("")
    t0 = time.monotonic()
    with pytest.raises(RunFailed, match="exited with 2: error: made to fail"):
        in_parallel(Runner(), config, [1001, 1002, 1003], tmp_path / "check", workers=3)
    assert time.monotonic() - t0 < 15
    for seed in (1001, 1003):
        pid = int((tmp_path / "check" / f"seed-{seed}" / "pid").read_text())
        assert not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split(")")[-1][:3]
