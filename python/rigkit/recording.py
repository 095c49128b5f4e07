"""A run's recording, `run.mcap` (docs/run.md): every message of the run as JSON on its
topic, the resolved configuration attached, the run's metadata; read with the official
`mcap` reader (`pip install "./python[recording]"`).

    rec = read("out/run/run.mcap", [MEASUREMENT])
    for evaluation, trials in greedy_trials(rec.of(MEASUREMENT)).items(): ...

`read` checks what it reads: every chunk's CRC, and the count of messages against the
file's statistics; a recording that fails is a RecordingError naming the file.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.stream_reader import CRCValidationError

# The topics the readers here use.
MEASUREMENT = "/plant/measurement"
TRUTH = "/plant/truth"
ESTIMATE = "/observer/estimate"
AGENT_TIMING = "/timing/agent/action"
PLANT_TIMING = "/timing/plant/measurement"
DRIVER_SAMPLE = "/driver/sample"
DRIVER_COMMAND = "/driver/command"

# Bits of a message's `flags` (wire::messages::flags).
START = 1
END = 2
GREEDY = 4
SHUTDOWN = 8
TERMINAL = 16
PRIMED = 128
ESTIMATED_REWARD = 256
GAP = 512
DRIVER_REWARD = 1024

# A decoded message: its JSON fields (a NaN or infinity is recorded as null).
Message = dict[str, Any]


class RecordingError(ValueError):
    """A recording that cannot be read whole: the message names the file and why."""


@dataclass
class Recording:
    """One recording: its channels and schemas (mcap's records), the names of its
    attachments, its metadata records by name, how many messages it holds, and the
    decoded messages of the topics asked for, in file order."""

    channels: list[Any] = field(default_factory=list)
    schemas: dict[int, Any] = field(default_factory=dict)
    attachment_names: list[str] = field(default_factory=list)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    message_count: int = 0
    messages: dict[str, list[Message]] = field(default_factory=dict)

    def of(self, topic: str) -> list[Message]:
        """The decoded messages of `topic` (one of those `read` was asked for)."""
        return self.messages[topic]


def read(path: str | Path, topics: Iterable[str] = ()) -> Recording:
    """The recording at `path`, the messages of `topics` decoded."""
    rec = Recording(messages={t: [] for t in topics})
    try:
        with open(path, "rb") as f:
            reader = make_reader(f, validate_crcs=True)
            summary = reader.get_summary()
            if summary is None:
                raise RecordingError(f"{path}: the file has no summary section")
            rec.channels = [summary.channels[k] for k in sorted(summary.channels)]
            rec.schemas = dict(summary.schemas)
            rec.attachment_names = [a.name for a in reader.iter_attachments()]
            rec.metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
            for _schema, channel, message in reader.iter_messages(log_time_order=False):
                rec.message_count += 1
                wanted = rec.messages.get(channel.topic)
                if wanted is None:
                    continue
                try:
                    wanted.append(json.loads(message.data))
                except ValueError as e:
                    raise RecordingError(
                        f"{path}: {channel.topic} message {message.sequence} is not JSON: {e}"
                    ) from e
    except OSError as e:
        raise RecordingError(f"{path}: cannot read: {e.strerror}") from e
    except CRCValidationError as e:
        raise RecordingError(f"{path}: {e}") from e
    except McapError as e:
        raise RecordingError(f"{path}: unreadable: {type(e).__name__}: {e}") from e
    stats = summary.statistics
    if stats is not None and stats.message_count != rec.message_count:
        raise RecordingError(
            f"{path}: read {rec.message_count} messages, the statistics record says {stats.message_count}"
        )
    return rec


def number(v: Any) -> float:
    """A recorded number as a float; null (a NaN or infinity) as NaN."""
    return math.nan if v is None else float(v)


def vector(m: Message, prefix: str) -> list[float]:
    """The components `PREFIX0, PREFIX1, ...` of message `m` (`y_` of a measurement:
    its state; `x_` of an estimate or the truth), in order."""
    out: list[float] = []
    while f"{prefix}{len(out)}" in m:
        out.append(number(m[f"{prefix}{len(out)}"]))
    return out


def greedy_trials(measurements: Iterable[Message]) -> dict[int, list[list[Message]]]:
    """The greedy trials of a run's measurements: evaluation (the number of the learning
    trial it follows) -> its trials (one per start state), each its messages in order."""
    evals: dict[int, list[list[Message]]] = {}
    for m in measurements:
        if not m["flags"] & GREEDY or m["flags"] & SHUTDOWN:
            continue
        trials = evals.setdefault(m["trial"], [])
        if m["step"] == 0 or not trials:
            trials.append([])
        trials[-1].append(m)
    return evals


def agent_steps_ns(timings: Iterable[Message]) -> list[int]:
    """The agent's step per sample [ns] of its `/timing/agent/action` messages: from
    receiving the estimate to publishing the action."""
    return [m["t_publish_ns"] - m["t_received_ns"] for m in timings]
