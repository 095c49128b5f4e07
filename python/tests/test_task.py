import math
from pathlib import Path

import pytest

from rigkit.task import Task, TaskError, main, number

from conftest import ROOT

BALANCE = ROOT / "examples/tasks/pendulum-balance.toml"


def test_every_shipped_task_file_reads() -> None:
    files = sorted((ROOT / "plant/tasks").glob("*.toml")) + sorted((ROOT / "examples").rglob("*.toml"))
    tasks = [f for f in files if "sampling_time" in f.read_text()]
    assert len(tasks) >= 10
    for f in tasks:
        t = Task.read(str(f))
        assert t.n >= 1 and t.m >= 1 and 0 <= t.hash() < 2**64


def test_multiples_of_pi() -> None:
    assert number("-8pi", "k") == -8 * math.pi
    assert number("0.5π", "k") == 0.5 * math.pi
    assert number("pi", "k") == math.pi
    assert number("2 * pi", "k") == 2 * math.pi
    with pytest.raises(TaskError, match="`k`: 'tau' is not a number or a multiple of pi"):
        number("tau", "k")
    with pytest.raises(TaskError, match="is not a number"):
        number(True, "k")


def test_the_hash_changes_with_the_reward(tmp_path: Path) -> None:
    text = BALANCE.read_text()
    other = tmp_path / "other.toml"
    other.write_text(text.replace("state_weights = [5.0, 0.1]", "state_weights = [5.0, 0.2]"))
    assert "state_weights = [5.0, 0.2]" in other.read_text()
    assert Task.read(str(other)).hash() != Task.read(str(BALANCE)).hash()


@pytest.mark.parametrize(
    "change, message",
    [
        (("angle = true", "angel = true"), "`state[0].angel`: unknown key"),
        (("sampling_time = 0.03", ""), "`sampling_time`: missing"),
        (("[reward]", "[reward]\nreference = [0.0]"), "`reward.reference`: has 1 entries; must have 2"),
    ],
)
def test_a_bad_file_is_one_line_naming_file_and_key(tmp_path: Path, change: tuple[str, str], message: str) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(BALANCE.read_text().replace(*change, 1))
    with pytest.raises(TaskError) as e:
        Task.read(str(bad))
    assert str(e.value).startswith(f"{bad}: {message}")
    assert "\n" not in str(e.value)


def test_the_command_line(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main([str(BALANCE)]) == 0
    name, h = capsys.readouterr().out.split()[1:]
    assert name == "pendulum-balance" and int(h, 16) == Task.read(str(BALANCE)).hash()
    assert main([str(tmp_path / "absent.toml")]) == 2
    assert "cannot read" in capsys.readouterr().err
