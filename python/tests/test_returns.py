from pathlib import Path

import pytest

from rigkit import returns

HEADER = "run,trial,sim_time_s,return,greedy_return\n"


def test_rows_and_evaluations(tmp_path: Path) -> None:
    f = tmp_path / "returns.csv"
    f.write_text(HEADER + "0,1,3,-120.5,\n0,2,6,-100.25,-90\n")
    rows = returns.read(f)
    assert rows == [returns.Row(0, 1, 3.0, -120.5, None), returns.Row(0, 2, 6.0, -100.25, -90.0)]
    assert [r.trial for r in returns.evaluations(rows)] == [2]
    assert returns.count(f) == 2
    assert returns.count(tmp_path / "absent.csv") == 0


@pytest.mark.parametrize(
    "text, message",
    [
        ("run,trial,return\n", "header [['run', 'trial', 'return']]"),
        ("", "header []"),
        (HEADER + "0,1,3\n", "returns.csv:2: 3 columns, expected 5"),
        (HEADER + "0,1,3,-1,\n0,x,3,-1,\n", "returns.csv:3: invalid literal"),
    ],
)
def test_a_bad_file_names_its_line(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "returns.csv"
    f.write_text(text)
    with pytest.raises(returns.ReturnsError, match=message.replace("[", r"\[").replace("]", r"\]")):
        returns.read(f)


def test_the_follower_reads_complete_rows_as_they_come(tmp_path: Path) -> None:
    f = tmp_path / "returns.csv"
    follow = returns.Follower(f)
    assert follow.new_rows() == []
    f.write_text(HEADER + "0,1,3,-1,\n0,2,6,-2,-1.5\n0,3,9,-3")  # the last row half written
    assert [r.trial for r in follow.new_rows()] == [1, 2]
    with open(f, "a") as out:
        out.write(",\n")
    assert [(r.trial, r.greedy) for r in follow.new_rows()] == [(3, None)]
    assert follow.new_rows() == []
