#!/usr/bin/env python3
"""The messages of a run.mcap in two encodings that Foxglove plots natively: the rig's
JSON (jsonschema) and ROS 2 CDR (ros2msg schemas, one float64/uint64 per field).

Usage: python3 bench/python/encodings.py DIR/run.mcap [--out DIR]

Reads every JSON message of the recording with the official `mcap` reader (the system's
pictures on `/scene` are protobuf already, and left out) and writes it again,
with the official writers (`mcap` for JSON, `mcap-ros2-support` for CDR), into
OUT/json-<c>.mcap and OUT/cdr-<c>.mcap, for each chunk compression c (none, lz4, zstd at
the writer's default level 3), the same chunk size (1 MiB) and indexes as the rig's. It
prints each file's size, the time to write it, and the time to read and decode every
message of it again with the official readers, each the median of --repetitions runs.
Needs rigkit, mcap and mcap-ros2-support (`pip install "./python[recording]" mcap-ros2-support`).
"""

import argparse
import importlib.util
import json
import math
import os
import re
import statistics
import sys
import time

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: encodings.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("encodings.py", modules=["mcap", "mcap_ros2"])

from mcap.reader import make_reader  # noqa: E402
from mcap.writer import CompressionType, Writer  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402
from mcap_ros2.writer import Writer as Ros2Writer  # noqa: E402


def read(path):
    """Every JSON message of the recording: (topic, schema name, field kinds, JSON, times).
    The system's pictures (`/scene`) are protobuf already, and left out."""
    out = []
    with open(path, "rb") as f:
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=False):
            if channel.message_encoding != "json":
                continue
            props = json.loads(schema.data)["properties"]
            kinds = [(k, v["type"]) for k, v in props.items()]
            out.append((channel.topic, schema.name, kinds, m.data, m.log_time, m.publish_time))
    return out


def msgdef(kinds):
    """The ros2msg definition of a flat message."""
    return "\n".join(("uint64 " if t == "integer" else "float64 ") + k for k, t in kinds)


def ros2_name(name):
    """A ROS 2 message name for a schema name: `timing.plant` → `TimingPlant`."""
    return "".join(p[:1].upper() + p[1:] for p in re.split(r"[^A-Za-z0-9]+", name) if p)


def write_json(msgs, path, compression):
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=compression)
        w.start(profile="", library="encodings.py")
        channels = {}
        for topic, name, kinds, data, t, tp in msgs:
            if topic not in channels:
                schema = w.register_schema(
                    name=name,
                    encoding="jsonschema",
                    data=json.dumps(
                        {"type": "object", "properties": {k: {"type": t} for k, t in kinds}}
                    ).encode(),
                )
                channels[topic] = w.register_channel(
                    topic=topic, message_encoding="json", schema_id=schema
                )
            w.add_message(channels[topic], log_time=t, data=data, publish_time=tp)
        w.finish()


def write_cdr(msgs, path, compression):
    with open(path, "wb") as f:
        w = Ros2Writer(f, chunk_size=1 << 20, compression=compression)
        schemas = {}
        for topic, name, kinds, data, t, tp in msgs:
            if name not in schemas:
                schemas[name] = w.register_msgdef("rig/msg/" + ros2_name(name), msgdef(kinds))
            d = json.loads(data)
            fields = {
                k: (math.nan if d[k] is None else float(d[k])) if kind == "number" else d[k]
                for k, kind in kinds
            }
            w.write_message(topic, schemas[name], fields, log_time=t, publish_time=tp)
        w.finish()


def decode_all(path):
    """Reads and decodes every message with the official readers; the count."""
    n = 0
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        if path.endswith(".mcap") and "/cdr-" in path:
            for _ in reader.iter_decoded_messages(log_time_order=False):
                n += 1
        else:
            for _, _, m in reader.iter_messages(log_time_order=False):
                json.loads(m.data)
                n += 1
    return n


def timed(f, repetitions):
    times = []
    for _ in range(repetitions):
        t0 = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("recording", help="a run.mcap written by rig run")
    ap.add_argument("--out", default="out/encodings", help="where the rewritten files go")
    ap.add_argument("--repetitions", type=int, default=3, help="runs of each timing")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    msgs = read(a.recording)
    print(f"{a.recording}: {len(msgs)} messages, {os.path.getsize(a.recording)} bytes")
    print(f"{'file':<22}{'bytes':>12}{'write s':>10}{'read s':>10}")
    for cname, c in [("none", CompressionType.NONE), ("lz4", CompressionType.LZ4),
                     ("zstd", CompressionType.ZSTD)]:
        for enc, write in [("json", write_json), ("cdr", write_cdr)]:
            path = os.path.join(a.out, f"{enc}-{cname}.mcap")
            tw, _ = timed(lambda: write(msgs, path, c), a.repetitions)
            tr, n = timed(lambda: decode_all(path), a.repetitions)
            if n != len(msgs):
                sys.exit(f"{path}: read {n} messages of {len(msgs)}")
            print(f"{enc}-{cname:<17}{os.path.getsize(path):>12}{tw:>10.2f}{tr:>10.2f}")


if __name__ == "__main__":
    main()
