"""The recording's reader on recordings made with the official writer, and on the rig's."""

import json
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mcap")

from mcap.writer import Writer  # noqa: E402

from rigkit import recording  # noqa: E402

from conftest import run  # noqa: E402


def write(path: Path, messages: list[tuple[str, dict[str, Any]]]) -> None:
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        schema = w.register_schema("s", "jsonschema", b'{"type":"object"}')
        channels: dict[str, int] = {}
        for k, (topic, m) in enumerate(messages):
            if topic not in channels:
                channels[topic] = w.register_channel(topic, "json", schema)
            w.add_message(channels[topic], log_time=k, publish_time=k, data=json.dumps(m).encode())
        w.add_metadata("run", {"horizon": "infinite"})
        w.finish()  # type: ignore[no-untyped-call]


def measurement(trial: int, step: int, flags: int, y: list[float | None]) -> tuple[str, dict[str, Any]]:
    m: dict[str, Any] = {"trial": trial, "step": step, "flags": flags}
    m.update({f"y_{i}": v for i, v in enumerate(y)})
    return recording.MEASUREMENT, m


def test_greedy_trials_grouped_by_evaluation_and_start_state(tmp_path: Path) -> None:
    G, S, E = recording.GREEDY, recording.START, recording.END
    path = tmp_path / "run.mcap"
    write(path, [
        measurement(1, 0, S, [0.0, 0.0]),
        measurement(1, 1, E, [0.1, 0.2]),
        measurement(1, 0, G | S, [1.0, None]),
        measurement(1, 1, G | E, [1.5, 2.0]),
        measurement(1, 0, G | S, [3.0, 0.0]),
        measurement(1, 1, G | E, [3.5, 0.0]),
        (recording.AGENT_TIMING, {"t_received_ns": 100, "t_publish_ns": 350}),
        measurement(1, 0, recording.SHUTDOWN | G, []),
    ])
    rec = recording.read(path, [recording.MEASUREMENT, recording.AGENT_TIMING])
    assert rec.message_count == 8 and rec.metadata["run"] == {"horizon": "infinite"}
    trials = recording.greedy_trials(rec.of(recording.MEASUREMENT))
    assert list(trials) == [1] and [len(t) for t in trials[1]] == [2, 2]
    first = [recording.vector(m, "y_") for m in trials[1][0]]
    assert first[0][0] == 1.0 and first[0][1] != first[0][1]  # null is NaN
    assert recording.agent_steps_ns(rec.of(recording.AGENT_TIMING)) == [250]


def test_a_cut_recording_is_an_error_naming_it(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    write(path, [measurement(1, 0, 1, [0.0])] * 50)
    path.write_bytes(path.read_bytes()[:-200])
    with pytest.raises(recording.RecordingError, match=str(path)):
        recording.read(path)


def test_a_rig_run_is_read_whole(tmp_path: Path, rig: Path) -> None:
    done = run([str(rig), "run", "--trials", "6", "--eval-every", "3", "--quiet", "--out", str(tmp_path)])
    assert done.returncode == 0, done.stderr
    rec = recording.read(tmp_path / "run.mcap", [recording.MEASUREMENT])
    assert "config.toml" in rec.attachment_names
    evals = recording.greedy_trials(rec.of(recording.MEASUREMENT))
    assert sorted(evals) == [3, 6]
    # A greedy trial of the pendulum: its start state and one sample per 30 ms of 3 s.
    assert all(len(t) == 101 for trials in evals.values() for t in trials)
