#!/usr/bin/env python3
"""Independent check of an ashlar trajectory recording with the `mcap` reader from PyPI.

    pip install "mcap>=1.6,<2"
    python3 scripts/check_mcap.py trajectory.mcap [--frames N] [--csv histories.csv]

Reads the file twice, with the indexed (seeking) reader and with a linear stream reader that
validates every CRC, and checks docs/format.md section 5: the channels, their schemas (JSON Schema,
embedded, titled by the schema name), one message per frame on each frame channel with
strictly increasing log times equal to the message's "time" in ns, the static transform, the
`ashlar.run` metadata, that every message has the fields its schema requires, and (with --csv)
that /ashlar/blocks equals histories.csv. Exits 1 with one line per failure, 0 when all pass.
"""
import argparse
import csv
import json
import sys

from mcap.reader import make_reader
from mcap.records import Message, Metadata
from mcap.stream_reader import StreamReader

FRAME_CHANNELS = {
    "/ashlar/blocks": "ashlar.BlockStates",
    "/ashlar/ground": "ashlar.GroundMotion",
    "/ashlar/scene": "foxglove.SceneUpdate",
}
STATIC_CHANNELS = {"/tf": "foxglove.FrameTransforms"}

failures = []


def fail(msg):
    failures.append(msg)


def missing_required(schema, value, at):
    """Paths where `value` lacks a field that `schema` requires (recursing into objects and
    arrays), or has the wrong JSON type."""
    out = []
    kind = schema.get("type")
    types = {
        "object": dict,
        "array": list,
        "string": str,
        "boolean": bool,
        "number": (int, float),
        "integer": int,
    }
    if kind in types:
        ok = isinstance(value, types[kind])
        if kind in ("number", "integer") and isinstance(value, bool):
            ok = False
        if not ok:
            return [f"{at}: expected {kind}, got {type(value).__name__}"]
    if isinstance(value, dict):
        for key in schema.get("required", []):
            if key not in value:
                out.append(f"{at}: missing required field {key!r}")
        props = schema.get("properties", {})
        for key, sub in value.items():
            if key in props:
                out += missing_required(props[key], sub, f"{at}.{key}")
    if isinstance(value, list) and "items" in schema:
        for i, item in enumerate(value):
            out += missing_required(schema["items"], item, f"{at}[{i}]")
    return out


def check(path, frames, csv_path):
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        if summary is None:
            fail("no summary section (file not finished?)")
            return
        topics = {c.topic: c for c in summary.channels.values()}
        schemas = {}
        for topic, name in {**FRAME_CHANNELS, **STATIC_CHANNELS}.items():
            ch = topics.get(topic)
            if ch is None:
                fail(f"channel {topic} missing")
                continue
            if ch.message_encoding != "json":
                fail(f"{topic}: message encoding {ch.message_encoding!r}, expected 'json'")
            schema = summary.schemas.get(ch.schema_id)
            if schema is None or schema.name != name or schema.encoding != "jsonschema":
                fail(f"{topic}: schema {schema and (schema.name, schema.encoding)}, expected ({name!r}, 'jsonschema')")
                continue
            parsed = json.loads(schema.data)
            if parsed.get("title") != name:
                fail(f"{topic}: schema title {parsed.get('title')!r} != {name!r}")
            schemas[topic] = parsed

        counts = {t: 0 for t in topics}
        last = {}
        blocks = []
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            topic = channel.topic
            counts[topic] = counts.get(topic, 0) + 1
            try:
                body = json.loads(message.data)
            except ValueError as e:
                fail(f"{topic} message {counts[topic]}: not JSON ({e})")
                continue
            if topic in schemas:
                for problem in missing_required(schemas[topic], body, topic)[:3]:
                    fail(problem)
            if topic in FRAME_CHANNELS:
                if topic in last and message.log_time <= last[topic]:
                    fail(f"{topic}: log time {message.log_time} not after {last[topic]}")
                last[topic] = message.log_time
                t = body.get("time") if topic != "/ashlar/scene" else None
                if t is not None and abs(round(t * 1e9) - message.log_time) > 0:
                    fail(f"{topic}: log time {message.log_time} ns != time {t} s")
                if topic == "/ashlar/scene":
                    for e in body.get("entities", []):
                        ts = e["timestamp"]
                        if ts["sec"] * 10**9 + ts["nsec"] != message.log_time:
                            fail(f"/ashlar/scene: entity {e['id']} timestamp != log time")
                            break
            if topic == "/ashlar/blocks":
                blocks.append(body)

        n = counts.get("/ashlar/blocks", 0)
        for topic in FRAME_CHANNELS:
            if counts.get(topic, 0) != n:
                fail(f"{topic}: {counts.get(topic, 0)} messages, /ashlar/blocks has {n}")
        if frames is not None and n != frames:
            fail(f"{n} frames, expected {frames}")
        if counts.get("/tf", 0) < 1:
            fail("/tf: no static transform")
        stats = summary.statistics
        if stats is None or stats.message_count != sum(counts.values()):
            fail(f"statistics say {stats and stats.message_count} messages, read {sum(counts.values())}")
        names = [m.name for m in reader.iter_metadata()]
        if "ashlar.run" not in names:
            fail(f"metadata 'ashlar.run' missing (found {names})")

    # Second, linear read of every record with CRC validation (data section and chunks).
    linear = 0
    linear_meta = 0
    with open(path, "rb") as f:
        for record in StreamReader(f, validate_crcs=True).records:
            if isinstance(record, Message):
                linear += 1
            elif isinstance(record, Metadata):
                linear_meta += 1
    if linear != sum(counts.values()):
        fail(f"linear read found {linear} messages, indexed read {sum(counts.values())}")
    if linear_meta < 1:
        fail("linear read found no metadata record")

    if csv_path:
        with open(csv_path, newline="") as f:
            rows = list(csv.reader(f))
        header, rows = rows[0], rows[1:]
        # Header version 2 (summary.json "format": "ashlar.run/2") names units:
        # time_s, <id>.x_m, <id>.y_m, <id>.rotation_rad; version 1 had time, <id>.x, ...
        units = {"x": "m", "y": "m", "rotation": "rad"}
        v2 = header[:1] == ["time_s"]
        if not v2 and header[:1] != ["time"]:
            fail(f"{csv_path}: unexpected first column {header[:1]}")
        fields = []
        for col in header[1:]:
            block, field = col.rsplit(".", 1)
            if v2:
                field, _, unit = field.rpartition("_")
                if units.get(field) != unit:
                    fail(f"{csv_path}: column {col}: expected the unit {units.get(field)}")
            fields.append((col, block, field))
        if len(rows) != len(blocks):
            fail(f"{csv_path}: {len(rows)} rows, /ashlar/blocks has {len(blocks)} messages")
        for row, msg in zip(rows, blocks):
            by_id = {b["id"]: b for b in msg["blocks"]}
            # The CSV's time is rounded to the nanosecond (the log-time resolution).
            if abs(float(row[0]) - msg["time"]) > (1e-9 if v2 else 0.0):
                fail(f"{csv_path}: time {row[0]} != {msg['time']}")
                break
            for (col, block, field), cell in zip(fields, row[1:]):
                if block not in by_id or float(cell) != by_id[block][field]:
                    fail(f"{csv_path}: {col} = {cell} at t = {row[0]} differs from /ashlar/blocks")
                    break
    return n


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mcap")
    ap.add_argument("--frames", type=int, help="expected number of frames")
    ap.add_argument("--csv", help="histories.csv written from the same run")
    args = ap.parse_args()
    try:
        n = check(args.mcap, args.frames, args.csv)
    except Exception as e:  # a reader error is a failed check, reported in one line
        fail(f"{type(e).__name__}: {e}")
        n = None
    if failures:
        for msg in failures:
            print(f"check_mcap: {args.mcap}: {msg}", file=sys.stderr)
        return 1
    print(f"check_mcap: {args.mcap}: OK ({n} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
