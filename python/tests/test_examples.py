"""Every example script run, shortened, and what it prints checked: the models' checks
(examples/acrobot/pump.py, lqr_region.py, examples/furuta/pump.py) against the figures
their READMEs quote, and the experiment scripts (a seed or two of a few trials against
the rig, RIG) to their tables. The drivers, the adapter and check_model.py /
check_reward.py are run by the rig's tests (rig/tests/lockstep.rs, furuta.rs, held_out.rs)."""

import csv
from pathlib import Path

import pytest

from conftest import run, said


def needs(*modules: str) -> None:
    for m in modules:
        pytest.importorskip(m)


def test_acrobot_pump_swings_up_at_4_n_m_not_at_1() -> None:
    done = run(["python", "examples/acrobot/pump.py", "--bound", "4", "--bound", "1", "--gains=-2.5,10,1"])
    assert done.returncode == 0, said(done)
    assert done.stdout.splitlines() == [
        "±4 N m: within 0.1 m of the top at 5.50 s (alpha -2.5, k_p 10.0, k_d 1.0)",
        "±1 N m: never within 0.1 m of the top in 10 s",
    ]


def test_acrobot_lqr_region_at_20_n_m() -> None:
    needs("numpy")
    done = run(["python", "examples/acrobot/lqr_region.py", "--bound", "20", "--starts", "2"])
    assert done.returncode == 0, said(done)
    lines = done.stdout.splitlines()
    assert lines[0].startswith("Ts 50 ms, +-20 N m, R 0.01: balances from theta1 up to 0.100 rad")
    assert lines[0].endswith("; 4/4 start states x2")
    assert len(lines) == 2


def test_acrobot_lqr_region_refuses_a_bad_flag() -> None:
    needs("numpy")
    done = run(["python", "examples/acrobot/lqr_region.py", "--gamma", "1.5"])
    assert done.returncode == 2 and "--gamma 1.5: must be in (0, 1]" in done.stderr


def test_furuta_pump_swings_up_with_gym_brt_damping_and_not_the_manuals() -> None:
    done = run(["python", "examples/furuta/pump.py", "--damping", "gym-brt", "--bound", "5",
                "--damping", "manual", "--bound", "10"])
    assert done.returncode == 0, said(done)
    out = done.stdout
    assert "±5 V: closest 0.009 rad from upright at 0.64 s" in out
    assert "±10 V: closest 1.462 rad from upright at 2.04 s" in out


def rows(path: Path) -> list[dict[str, str]]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_mountain_car_sh_learns_a_seed_and_tabulates_it(tmp_path: Path, rig: Path) -> None:
    needs("iceoryx2", "gymnasium", "mcap")
    out = tmp_path / "car"
    done = run(["bash", "examples/gymnasium/mountain-car.sh", str(out), "1", "10", "--", "--eval-every", "10"],
               env=environment(rig))
    assert done.returncode == 0, said(done)
    # Ten trials of the rules' MLAC/LLR reach the hilltop (rig/tests/lockstep.rs).
    assert "1 of 1 seeds succeed at the last evaluation" in done.stdout, done.stdout
    assert (out / "table.md").read_text() in done.stdout
    assert len(rows(out / "runs.csv")) == 10 and len(rows(out / "wall.csv")) == 1


def test_acrobot_experiment_sh_tabulates_its_seeds(tmp_path: Path, rig: Path) -> None:
    needs("iceoryx2", "mcap")
    out = tmp_path / "acrobot"
    done = run(["bash", "examples/acrobot/experiment.sh", str(out), "examples/acrobot/acrobot-balance.toml",
                "2", "4", "--", "--eval-every", "2"], env=environment(rig))
    assert done.returncode == 0, said(done)
    table = done.stdout
    assert "| 1 | 4 |" in table and "| 2 | 4 |" in table, table
    assert " of 2 seeds succeed at the last evaluation" in table
    assert table.count("last greedy trial from start state") == 2 * 4  # two seeds, four start states


def test_furuta_benchmark_sh_reports_its_five_configurations(tmp_path: Path, rig: Path) -> None:
    needs("iceoryx2", "mcap", "matplotlib")
    out = tmp_path / "furuta"
    done = run(["bash", "examples/furuta/benchmark.sh", str(out), "1", "4", "--", "--eval-every", "2"],
               env=environment(rig), timeout=900)
    assert done.returncode == 0, said(done)
    report = (out / "report.md").read_text()
    for learner in ("mlac-llr", "halved", "halved-sigma1", "decay", "two-timescale"):
        assert f"\n{learner}: " in report and f"seeds upright at the end" in report
        assert (out / "bal" / f"response-{learner}.svg").stat().st_size > 0
    assert (out / "bal" / "curves.png").stat().st_size > 0


def test_furuta_experiment_sh_runs_its_seeds(tmp_path: Path, rig: Path) -> None:
    needs("iceoryx2")
    out = tmp_path / "furuta"
    done = run(["bash", "examples/furuta/experiment.sh", str(out), "1", "3", "--eval-every", "3"],
               env={**environment(rig), "TASK": "examples/furuta/furuta-balance.toml", "DAMPING": "manual"})
    assert done.returncode == 0, said(done)
    assert [r["trial"] for r in rows(out / "runs.csv")] == ["1", "2", "3"]
    assert rows(out / "seed-1" / "returns.csv")[-1]["greedy_return"] != ""


def environment(rig: Path) -> dict[str, str]:
    import os
    import sys

    return {**os.environ, "RIG": str(rig), "PYTHON": sys.executable}
