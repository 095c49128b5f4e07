#!/usr/bin/env python3
"""Checks the recording of a `rig run`: python3 tests/python/check_mcap.py DIR

Opens DIR/run.mcap with the official Python `mcap` package and checks that
  1. the file is complete and intact: summary section present, every chunk CRC, the
     data-section CRC, the summary CRC and every attachment CRC computed and valid;
  2. every channel has message encoding `json` and a `jsonschema` schema that is a flat
     object of `number`/`integer` properties with no `$ref` (so Foxglove plots it) — but
     `/scene`, protobuf `foxglove.SceneUpdate`; `/returns`, `/latency` and `/scene` are
     there;
  3. the attachment `config.toml` is present;
  4. the per-trial returns recomputed from the `/plant/measurement` messages equal
     DIR/returns.csv (`run,trial,sim_time_s,return,greedy_return`) exactly — from the
     `/observer/estimate` messages (their `reward` and `x`) instead when the measurements
     have flag bit 8 (ESTIMATED_REWARD: a driver that measures positions only, whose
     rewards the observer computes from its estimate).
  5. what a viewer shows besides: `/returns` holds the rows of DIR/returns.csv, in order,
     exactly; `/latency` one message per action, the time from its sample to it and the
     agent's share, exactly as the `/timing/agent/action` stamps give them; `/scene` a
     picture per sample (of `/plant/truth` when recorded, else of the measurement; none
     of the shutdown), decoded with the official protobuf decoder (mcap-protobuf-support):
     the entity `system` in frame `world` at the sample's log time, with points all
     finite — for the pendulum, its tip at (sin phi, 0, cos phi) of the state's angle.

Returns (check 4): a measurement message has fields `trial` (learning trial, from 1),
`step` (0 = the trial's start state; the `reward` of step k >= 1 is r_k = rho(x_{k-1},
u_{k-1})) and `flags` (bit 0 trial start, bit 1 trial end, bit 2 greedy evaluation trial,
bit 3 shutdown, bit 7 primed: predictive timing's repeat of the start state, reward 0).
A trial's return is r_1 + r_2 + ... + r_N summed left to right from 0.0
in Python floats, as the rig sums the same f64 values in the same order, so they are
compared with `==` (NaN equals NaN; a `null` reward, the recorder's encoding of NaN/inf,
reads as NaN). With a finite horizon (the `run` metadata's `horizon = finite`) the
terminal reward tau_N(x_N) = -sum_i q_i e_i^2 of the trial's last state is added last
(Eq. 4.1; e = x - reference, angles wrapped to [-pi, pi) as the rig wraps them; the
weights are the metadata's `reward_terminal` (else `reward_q`), `reward_reference`,
`reward_angles`; x_N is the
`/plant/truth` message of the END sample when the sensor does not measure the full
state, otherwise the END measurement's `y`). Messages without the greedy bit make the
learning trial T's `return`; messages with it make the `greedy_return` of row T — the mean
over the task's start states when it has several (one greedy trial from each). Messages
with the shutdown bit carry no step and are left out.

Exit status 0 when every check passes, 1 with a message naming the first failure
otherwise (2 for a usage error). The functions below can be imported and called one by
one; each raises CheckError.

Needs the rig's Python package with mcap: `pip install "./python[recording]"` (its
readers: rigkit.recording, rigkit.returns; written against mcap 1.6.0 and
mcap-protobuf-support 0.6.0).
"""

from __future__ import annotations

import importlib.util
import json
import math
import struct
import sys
import zlib
from dataclasses import dataclass
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # the same parser, from PyPI (rigkit's dependency there)
    import tomli as tomllib

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: check_mcap.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("check_mcap.py", modules=["mcap", "mcap_protobuf"])

from mcap.exceptions import McapError  # noqa: E402
from mcap_protobuf.decoder import DecoderFactory  # noqa: E402
from mcap.reader import NonSeekingReader, make_reader  # noqa: E402
from mcap.records import Chunk, DataEnd, Footer  # noqa: E402
from mcap.stream_reader import CRCValidationError, StreamReader  # noqa: E402

from rigkit import recording, returns  # noqa: E402
from rigkit.angle import wrap  # noqa: E402
from rigkit.recording import (  # noqa: E402
    END as FLAG_TRIAL_END,
    ESTIMATED_REWARD as FLAG_ESTIMATED_REWARD,
    GAP as FLAG_GAP,
    GREEDY as FLAG_GREEDY,
    PRIMED as FLAG_PRIMED,
    SHUTDOWN as FLAG_SHUTDOWN,
    START as FLAG_TRIAL_START,
)

MEASUREMENT_TOPIC = recording.MEASUREMENT
TRUTH_TOPIC = recording.TRUTH
ESTIMATE_TOPIC = recording.ESTIMATE
CONFIG_ATTACHMENT = "config.toml"
RETURNS_TOPIC = "/returns"
LATENCY_TOPIC = "/latency"
SCENE_TOPIC = "/scene"
SCENE_SCHEMA = "foxglove.SceneUpdate"
AGENT_TIMING_TOPIC = recording.AGENT_TIMING

MAGIC_SIZE = 8
# opcode (1) + record length (8) + summary_start (8) + summary_offset_start (8) + crc (4)
FOOTER_RECORD_SIZE = 1 + 8 + 8 + 8 + 4


class CheckError(Exception):
    """A check failed; the message says which and why."""


# ---------------------------------------------------------------------------------------
# 1. container integrity


def count_streamable_messages(path: Path) -> tuple[int, str | None]:
    """Messages a streaming reader gets out of `path` before it stops, and why it stopped
    (None when it reached the end). Used to describe a truncated file."""
    count = 0
    try:
        with open(path, "rb") as f:
            for _ in NonSeekingReader(f).iter_messages(log_time_order=False):
                count += 1
    except Exception as e:  # noqa: BLE001 - any failure ends the stream
        return count, f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
    return count, None


def check_container(path: Path) -> None:
    """Check 1, except the chunk CRCs that `read_recording` checks: a summary and footer
    are present, the data-section CRC, the summary CRC and the attachment CRCs are
    computed (non-zero) and match, and every chunk has a CRC."""
    data = path.read_bytes()
    if len(data) < 2 * MAGIC_SIZE + FOOTER_RECORD_SIZE:
        raise CheckError(f"{path}: {len(data)} bytes is too short for an MCAP file")
    # The footer, read by hand: the Python reader does not check the summary CRC.
    footer_at = len(data) - MAGIC_SIZE - FOOTER_RECORD_SIZE
    opcode, length, summary_start, summary_offset_start, summary_crc = struct.unpack_from(
        "<BQQQI", data, footer_at
    )
    magic_ok = data[-MAGIC_SIZE:] == data[:MAGIC_SIZE] == b"\x89MCAP0\r\n"
    if opcode != 0x02 or length != FOOTER_RECORD_SIZE - 9 or not magic_ok:
        n, why = count_streamable_messages(path)
        raise CheckError(
            f"{path}: no footer at the end of the file (a run that did not finish?); "
            f"a streaming reader gets {n} messages out of it"
            + (f", then stops with {why}" if why else "")
        )
    if summary_start == 0:
        raise CheckError(f"{path}: the file has no summary section")
    if summary_crc == 0:
        raise CheckError(f"{path}: the summary CRC was not computed")
    actual = zlib.crc32(data[summary_start : len(data) - MAGIC_SIZE - 4])
    if actual != summary_crc:
        raise CheckError(f"{path}: summary CRC {actual:#010x}, footer says {summary_crc:#010x}")

    # The whole data section, in order: the reader checks the data-section CRC at the
    # DataEnd record (chunks are kept whole here; their CRCs are checked while reading
    # the messages).
    chunks = 0
    data_end = None
    footer = None
    try:
        with open(path, "rb") as f:
            for record in StreamReader(f, emit_chunks=True, validate_crcs=True).records:
                if isinstance(record, Chunk):
                    chunks += 1
                    if record.uncompressed_crc == 0:
                        raise CheckError(f"{path}: chunk {chunks} has no CRC")
                elif isinstance(record, DataEnd):
                    data_end = record
                elif isinstance(record, Footer):
                    footer = record
    except CRCValidationError as e:
        raise CheckError(f"{path}: {e}") from e
    except McapError as e:
        raise CheckError(f"{path}: unreadable: {type(e).__name__}: {e}") from e
    if data_end is None or footer is None:
        raise CheckError(f"{path}: no DataEnd or Footer record")
    if data_end.data_section_crc == 0:
        raise CheckError(f"{path}: the data-section CRC was not computed")
    if chunks == 0:
        raise CheckError(f"{path}: no chunks")

    # Attachment CRCs (the Python reader skips them): CRC32 of the record body from
    # log_time through the data, stored in its last 4 bytes.
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    for index in summary.attachment_indexes:
        record = data[index.offset : index.offset + index.length]
        body = record[9:]
        if len(body) < 4 or record[0] != 0x09:
            raise CheckError(f"{path}: attachment index of {index.name!r} points at no attachment")
        (stored,) = struct.unpack_from("<I", body, len(body) - 4)
        if stored == 0:
            raise CheckError(f"{path}: attachment {index.name!r} has no CRC")
        if zlib.crc32(body[:-4]) != stored:
            raise CheckError(f"{path}: attachment {index.name!r} fails its CRC")


def read_recording(path: Path) -> recording.Recording:
    """Reads the summary, attachments, metadata and every message of `path` with chunk
    CRC validation (check 1); decodes the measurement, truth and estimate messages."""
    try:
        return recording.read(
            path,
            [MEASUREMENT_TOPIC, TRUTH_TOPIC, ESTIMATE_TOPIC, RETURNS_TOPIC, LATENCY_TOPIC,
             AGENT_TIMING_TOPIC],
        )
    except recording.RecordingError as e:
        raise CheckError(str(e)) from e


# ---------------------------------------------------------------------------------------
# 2. schemas and encodings


def find_refs(node, where="") -> list[str]:
    """JSON paths of every `$ref` key inside `node`."""
    found = []
    if isinstance(node, dict):
        for k, v in node.items():
            if k == "$ref":
                found.append(where or "/")
            found.extend(find_refs(v, f"{where}/{k}"))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            found.extend(find_refs(v, f"{where}/{i}"))
    return found


def check_schema_data(name: str, data: bytes) -> None:
    """A channel schema is a JSON object schema of flat `number`/`integer` properties,
    with no `$ref`."""
    try:
        schema = json.loads(data)
    except ValueError as e:
        raise CheckError(f"schema {name!r} is not JSON: {e}") from e
    refs = find_refs(schema)
    if refs:
        raise CheckError(f"schema {name!r} uses $ref at {', '.join(refs)}")
    if not isinstance(schema, dict) or schema.get("type") != "object":
        raise CheckError(f"schema {name!r} is not an object schema")
    props = schema.get("properties")
    if not isinstance(props, dict) or not props:
        raise CheckError(f"schema {name!r} has no properties")
    for prop, spec in props.items():
        kind = spec.get("type") if isinstance(spec, dict) else None
        if kind not in ("number", "integer"):
            raise CheckError(
                f"schema {name!r}: property {prop!r} has type {kind!r}, "
                "not number or integer"
            )
        nested = {"properties", "items", "oneOf", "anyOf", "allOf"} & set(spec)
        if nested:
            raise CheckError(f"schema {name!r}: property {prop!r} is not flat ({sorted(nested)})")


def check_channels(rec: recording.Recording) -> None:
    """Check 2 for every channel; the measurement topic must be among them."""
    if not rec.channels:
        raise CheckError("the recording has no channels")
    for ch in rec.channels:
        if ch.topic == SCENE_TOPIC:
            check_scene_channel(rec, ch)
            continue
        if ch.message_encoding != "json":
            raise CheckError(
                f"channel {ch.topic}: message encoding {ch.message_encoding!r}, not 'json'"
            )
        schema = rec.schemas.get(ch.schema_id)
        if schema is None:
            raise CheckError(f"channel {ch.topic}: no schema")
        if schema.encoding != "jsonschema":
            raise CheckError(
                f"channel {ch.topic}: schema encoding {schema.encoding!r}, not 'jsonschema'"
            )
        check_schema_data(schema.name, schema.data)
    topics = {ch.topic for ch in rec.channels}
    for topic in (MEASUREMENT_TOPIC, RETURNS_TOPIC, LATENCY_TOPIC, SCENE_TOPIC):
        if topic not in topics:
            raise CheckError(f"no channel {topic}")


def check_scene_channel(rec: recording.Recording, ch) -> None:
    """`/scene`: protobuf messages of the schema foxglove.SceneUpdate."""
    schema = rec.schemas.get(ch.schema_id)
    got = (ch.message_encoding, schema and schema.encoding, schema and schema.name)
    if got != ("protobuf", "protobuf", SCENE_SCHEMA):
        raise CheckError(
            f"channel {SCENE_TOPIC}: (message encoding, schema encoding, schema) {got}, "
            f"not ('protobuf', 'protobuf', {SCENE_SCHEMA!r})"
        )


# ---------------------------------------------------------------------------------------
# 3. attachment


def check_attachment(rec: recording.Recording) -> None:
    """Check 3: the resolved configuration is attached."""
    if CONFIG_ATTACHMENT not in rec.attachment_names:
        raise CheckError(
            f"no attachment {CONFIG_ATTACHMENT!r} (attachments: {rec.attachment_names})"
        )


# ---------------------------------------------------------------------------------------
# 4. returns


as_float = recording.number


def same(a: float, b: float) -> bool:
    """Exact equality, NaN equal to NaN."""
    return a == b or (math.isnan(a) and math.isnan(b))


@dataclass
class TerminalReward:
    """tau_N(x) = -sum_i q_i e_i^2, e = x - reference, angles wrapped (Eq. 4.1)."""

    q: list
    reference: list
    angles: list

    @staticmethod
    def from_metadata(meta: dict) -> "TerminalReward | None":
        """From the `run` metadata; None for an infinite horizon."""
        horizon = meta.get("horizon")
        if horizon != "finite":
            return None
        try:
            weights = meta.get("reward_terminal", meta.get("reward_q"))
            if weights is None:
                raise KeyError("reward_terminal")
            q = [float(v) for v in weights.split(",")]
            ref = [float(v) for v in meta["reward_reference"].split(",")]
            angles = [v == "1" for v in meta["reward_angles"].split(",")]
        except (KeyError, ValueError) as e:
            raise CheckError(f"`run` metadata: finite horizon without reward weights: {e}") from e
        if not len(q) == len(ref) == len(angles):
            raise CheckError(f"`run` metadata: reward weights of different lengths: {meta}")
        return TerminalReward(q, ref, angles)

    def __call__(self, x: list) -> float:
        r = 0.0
        for i, q in enumerate(self.q):
            e = x[i] - self.reference[i]
            if self.angles[i]:
                e = wrap(e)
            r -= q * e * e
        return r


def final_state(m: dict, truth: dict) -> list:
    """The true state of measurement `m`'s sample: its `/plant/truth` message (x_0, ...)
    when the recording has one, else its measured `y` (full-state sensing)."""
    if truth:
        t = truth.get(m.get("seq"))
        if t is None:
            raise CheckError(f"{TRUTH_TOPIC}: no message for sample {m.get('seq')}")
        prefix, src = "x_", t
    else:
        prefix, src = "y_", m
    return recording.vector(src, prefix)


def trial_returns(
    measurements: list, terminal: "TerminalReward | None" = None, truth: dict | None = None
) -> tuple[dict[int, float], dict[int, float]]:
    """(learning returns, greedy returns) by trial number, from decoded measurement
    messages, summed as the rig sums them: from 0.0, the PRIMED repeat of the start state
    (predictive timing; reward 0) if any, then r_1 + ... + r_N in step order, plus
    `terminal` of the END sample's true state when given (finite horizon). A trial number
    has one learning trial and a greedy trial from each start state (several on arm-6.4),
    each opened by a START message; its greedy return is their mean, (0.0 + g_1 + ...) / n.
    An attempt cut short by a gap (its last sample flagged GAP, with END) does not count:
    the trial is run again, from its START."""
    trials: dict[tuple[int, bool, int], dict[int, float]] = {}
    primed: dict[tuple[int, bool, int], float] = {}
    finals: dict[tuple[int, bool, int], float] = {}
    starts: dict[tuple[int, bool], int] = {}
    cut: set[tuple[int, bool, int]] = set()
    for m in measurements:
        try:
            trial, step, flags = int(m["trial"]), int(m["step"]), int(m["flags"])
            reward = as_float(m["reward"])
        except (KeyError, TypeError, ValueError) as e:
            raise CheckError(f"{MEASUREMENT_TOPIC} message {m}: bad or missing field: {e}") from e
        if flags & FLAG_SHUTDOWN:
            continue
        is_greedy = bool(flags & FLAG_GREEDY)
        kind = "greedy trial" if is_greedy else "trial"
        if flags & FLAG_TRIAL_START:
            starts[(trial, is_greedy)] = starts.get((trial, is_greedy), -1) + 1
            again = (trial, False, starts[(trial, False)] - 1) in cut if not is_greedy else True
            if not is_greedy and starts[(trial, False)] > 0 and not again:
                raise CheckError(f"{MEASUREMENT_TOPIC}: trial {trial} starts twice")
        if (trial, is_greedy) not in starts:
            raise CheckError(f"{MEASUREMENT_TOPIC}: {kind} {trial}: a sample before its START")
        key = (trial, is_greedy, starts[(trial, is_greedy)])
        if flags & FLAG_GAP:
            if not flags & FLAG_TRIAL_END:
                raise CheckError(f"{MEASUREMENT_TOPIC}: {kind} {trial}: GAP without END")
            cut.add(key)
            continue
        if flags & FLAG_PRIMED:
            if step != 0 or key in primed:
                raise CheckError(
                    f"{MEASUREMENT_TOPIC}: {kind} {trial}: PRIMED at step {step}, or twice"
                )
            primed[key] = reward
            continue
        steps = trials.setdefault(key, {})
        if step in steps:
            raise CheckError(f"{MEASUREMENT_TOPIC}: {kind} {trial} has step {step} twice")
        steps[step] = reward
        if terminal is not None and flags & FLAG_TRIAL_END and step >= 1:
            finals[key] = terminal(final_state(m, truth or {}))
    learning: dict[int, float] = {}
    greedy_sums: dict[int, tuple[float, int]] = {}
    for key, steps in sorted(trials.items()):
        if key in cut:
            continue
        trial, is_greedy, _ = key
        kind = "greedy trial" if is_greedy else "trial"
        n = max(steps)
        if sorted(steps) != list(range(n + 1)) or n < 1:
            raise CheckError(
                f"{MEASUREMENT_TOPIC}: {kind} {trial} has steps {sorted(steps)}, not 0..N"
            )
        total = 0.0
        if key in primed:
            total += primed[key]
        for k in range(1, n + 1):
            total += steps[k]
        if terminal is not None:
            if key not in finals:
                raise CheckError(f"{MEASUREMENT_TOPIC}: {kind} {trial} has no END sample")
            total += finals[key]
        if is_greedy:
            acc, count = greedy_sums.get(trial, (0.0, 0))
            greedy_sums[trial] = (acc + total, count + 1)
        else:
            learning[trial] = total
    greedy = {trial: acc / count for trial, (acc, count) in greedy_sums.items()}
    return learning, greedy


def read_returns_csv(path: Path) -> dict[int, tuple[float, float | None]]:
    """returns.csv as trial -> (return, greedy_return or None when blank)."""
    try:
        rows = returns.read(path)
    except returns.ReturnsError as e:
        raise CheckError(str(e)) from e
    out: dict[int, tuple[float, float | None]] = {}
    for line, row in enumerate(rows, start=2):
        if row.trial in out:
            raise CheckError(f"{path}:{line}: trial {row.trial} appears twice")
        out[row.trial] = (row.ret, row.greedy)
    runs = {row.run for row in rows}
    if len(runs) > 1:
        raise CheckError(f"{path}: rows of several runs {sorted(runs)}; one rig run has one")
    return out


def compare_returns(
    learning: dict[int, float], greedy: dict[int, float], csv_rows: dict, csv_name="returns.csv"
) -> None:
    """Check 4: the same trials on both sides and exactly equal returns; the message
    names the first mismatch in trial order."""
    if not learning:
        raise CheckError(f"no learning trials in {MEASUREMENT_TOPIC}")
    for trial in sorted(set(learning) | set(csv_rows) | set(greedy)):
        if trial not in csv_rows:
            raise CheckError(f"trial {trial} is in {MEASUREMENT_TOPIC} but not in {csv_name}")
        ret, greedy_ret = csv_rows[trial]
        if trial not in learning:
            raise CheckError(f"trial {trial} is in {csv_name} but not in {MEASUREMENT_TOPIC}")
        if not same(learning[trial], ret):
            raise CheckError(
                f"trial {trial}: return from {MEASUREMENT_TOPIC} is {learning[trial]!r}, "
                f"{csv_name} says {ret!r}"
            )
        if (trial in greedy) != (greedy_ret is not None):
            have = "has" if trial in greedy else "has no"
            blank = "a" if greedy_ret is not None else "a blank"
            raise CheckError(
                f"trial {trial}: {MEASUREMENT_TOPIC} {have} greedy trial but {csv_name} "
                f"has {blank} greedy_return"
            )
        if greedy_ret is not None and not same(greedy[trial], greedy_ret):
            raise CheckError(
                f"trial {trial}: greedy return from {MEASUREMENT_TOPIC} is "
                f"{greedy[trial]!r}, {csv_name} says {greedy_ret!r}"
            )


# ---------------------------------------------------------------------------------------


# 5. what a viewer shows besides: returns, latency, the system's picture


def check_returns_channel(rows: list, csv_path: Path) -> None:
    """`/returns` holds the rows of returns.csv, in order, exactly."""
    try:
        csv_rows = returns.read(csv_path)
    except returns.ReturnsError as e:
        raise CheckError(str(e)) from e
    if len(rows) != len(csv_rows):
        raise CheckError(f"{RETURNS_TOPIC}: {len(rows)} rows, {csv_path.name} has {len(csv_rows)}")
    for got, want in zip(rows, csv_rows):
        greedy = as_float(got.get("greedy"))
        fields = (int(got["trial"]), as_float(got["return"]), as_float(got["sim_time_s"]))
        if fields[0] != want.trial or not (same(fields[1], want.ret) and same(fields[2], want.sim_time_s)):
            raise CheckError(f"{RETURNS_TOPIC}: {got} is not the row of trial {want.trial} of {csv_path.name}")
        if (want.greedy is None) != math.isnan(greedy) or (
            want.greedy is not None and not same(greedy, want.greedy)
        ):
            raise CheckError(f"{RETURNS_TOPIC}: trial {want.trial} greedy {greedy!r}, {csv_path.name} says {want.greedy!r}")


def check_latency(latency: list, stamps: list) -> None:
    """`/latency`: per action, its sample to its publication and the agent's share (µs),
    as the recorded stamps give them."""
    if len(latency) != len(stamps) or not latency:
        raise CheckError(f"{LATENCY_TOPIC}: {len(latency)} messages for {len(stamps)} actions")
    for got, s in zip(latency, stamps):
        want = (
            int(s["seq"]),
            (float(s["t_publish_ns"]) - float(s["t_sample_ns"])) / 1e3,
            (float(s["t_publish_ns"]) - float(s["t_received_ns"])) / 1e3,
        )
        values = (int(got["seq"]), as_float(got["sample_to_action_us"]), as_float(got["agent_us"]))
        if values != want or not 0 <= values[2] <= values[1]:
            raise CheckError(f"{LATENCY_TOPIC}: {got}, the stamps {s} give {want}")


def check_scene(path: Path, state_topic: str, system: str) -> int:
    """`/scene`: a picture per message of `state_topic` (but the shutdown), decoded with
    the official protobuf decoder; returns how many."""
    pictures, states = [], []
    decoders = DecoderFactory()
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(
            topics=[SCENE_TOPIC, state_topic], log_time_order=False
        ):
            if channel.topic == SCENE_TOPIC:
                decode = decoders.decoder_for(channel.message_encoding, schema)
                pictures.append((message.log_time, decode(message.data)))
                continue
            state = json.loads(message.data)
            if not int(state.get("flags", 0)) & FLAG_SHUTDOWN:
                states.append((message.log_time, state))
    if len(pictures) != len(states):
        raise CheckError(f"{SCENE_TOPIC}: {len(pictures)} pictures for {len(states)} samples")
    for (log_time, scene), (state_log_time, state) in zip(pictures, states):
        where = f"{SCENE_TOPIC} at sample seq {state.get('seq')}"
        [entity] = scene.entities
        stamp = entity.timestamp.seconds * 10**9 + entity.timestamp.nanos
        got = (entity.id, entity.frame_id, stamp, log_time)
        if got != ("system", "world", state_log_time, state_log_time):
            raise CheckError(f"{where}: (entity, frame, stamp, log time) {got}, sample at {state_log_time}")
        points = [(p.x, p.y, p.z) for line in entity.lines for p in line.points]
        points += [(c.pose.position.x, c.pose.position.y, c.pose.position.z) for c in entity.cubes]
        if not points or not all(math.isfinite(v) for p in points for v in p):
            raise CheckError(f"{where}: points {points}")
        if system == "pendulum":
            phi = as_float(state.get("x_0", state.get("y_0")))
            phi = phi if math.isfinite(phi) else 0.0
            tip = (math.sin(phi), 0.0, math.cos(phi))
            if any(abs(a - b) > 1e-12 for a, b in zip(points[1], tip)):
                raise CheckError(f"{where}: the pendulum's tip at {points[1]}, its angle {phi} puts it at {tip}")
    return len(pictures)


def simulated_system(run_dir: Path, rec: recording.Recording) -> str:
    """The system the rig simulates for the run's task, the one whose picture `rig run`
    draws (rig/src/picture.rs): a built-in system's name (config.toml without a [task]:
    the recording's metadata says which), a task file's `[task.simulation] system`, or ""
    for a task only its driver knows (drawn as bars)."""
    with open(run_dir / "config.toml", "rb") as f:
        task = tomllib.load(f).get("task")
    if task is None:
        return str(rec.metadata.get("run", {}).get("system", ""))
    return str(task.get("simulation", {}).get("system", ""))


def check_run(run_dir: Path, log=print) -> None:
    """Every check on the run directory `run_dir`; raises CheckError at the first failure
    and calls `log` with a line per check passed."""
    path = run_dir / "run.mcap"
    if not path.is_file():
        part = path.with_name(path.name + ".part")
        hint = f" ({part.name} exists: the run did not finish)" if part.exists() else ""
        raise CheckError(f"{path} does not exist{hint}")
    check_container(path)
    rec = read_recording(path)
    log(
        f"ok: {path}: summary present, chunk/data/summary/attachment CRCs valid, "
        f"{rec.message_count} messages on {len(rec.channels)} channels"
    )
    check_channels(rec)
    log("ok: every channel is json with a flat numeric jsonschema schema, no $ref, "
        f"but {SCENE_TOPIC}, protobuf {SCENE_SCHEMA}")
    check_attachment(rec)
    log(f"ok: attachment {CONFIG_ATTACHMENT} present")
    terminal = TerminalReward.from_metadata(rec.metadata.get("run", {}))
    measurements = rec.of(MEASUREMENT_TOPIC)
    truth = {t.get("seq"): t for t in rec.of(TRUTH_TOPIC)}
    source, topic = measurements, MEASUREMENT_TOPIC
    if any(int(m.get("flags", 0)) & FLAG_ESTIMATED_REWARD for m in measurements):
        # The driver measures positions only: the rewards are the observer's, computed
        # from its estimate x̂, which also gives x_N.
        topic, truth = ESTIMATE_TOPIC, {}
        source = [
            {**e, **{"y_" + k[2:]: v for k, v in e.items() if k.startswith("x_")}}
            for e in rec.of(ESTIMATE_TOPIC)
        ]
    learning, greedy = trial_returns(source, terminal, truth)
    csv_path = run_dir / "returns.csv"
    compare_returns(learning, greedy, read_returns_csv(csv_path), csv_path.name)
    log(
        f"ok: returns of {len(learning)} trials and {len(greedy)} greedy trials "
        f"from {topic}"
        + (" (with the terminal reward of a finite horizon)" if terminal else "")
        + f" equal {csv_path.name} exactly"
    )
    check_returns_channel(rec.of(RETURNS_TOPIC), csv_path)
    check_latency(rec.of(LATENCY_TOPIC), rec.of(AGENT_TIMING_TOPIC))
    drawn = TRUTH_TOPIC if rec.of(TRUTH_TOPIC) else MEASUREMENT_TOPIC
    pictures = check_scene(path, drawn, simulated_system(run_dir, rec))
    log(
        f"ok: {RETURNS_TOPIC} holds the {len(rec.of(RETURNS_TOPIC))} rows of {csv_path.name}, "
        f"{LATENCY_TOPIC} the latency of every action, {SCENE_TOPIC} {pictures} pictures, "
        "one per sample"
    )


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(f"usage: {argv[0]} DIR  (a rig run directory with run.mcap and returns.csv)",
              file=sys.stderr)
        return 2
    try:
        check_run(Path(argv[1]))
    except CheckError as e:
        print(f"check_mcap: FAIL: {e}", file=sys.stderr)
        return 1
    print("check_mcap: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
