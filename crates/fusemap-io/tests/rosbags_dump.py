"""Reads a rosbag2 directory with the third-party `rosbags` library and prints JSON.

Used by ros2_writer_rosbags.rs to check fusemap's rosbag2 writer against a reader that
is not fusemap's own. For the bag it prints the metadata rosbags saw; for every topic its
type, count, QoS and whether the schema's message definition equals the one rosbags
generates for ROS 2 Humble; for every message its log time, the message deserialised by
the Humble type store (as plain JSON), whether a type store built from the bag's own
definitions deserialises it to the same value, and whether rosbags serialises it back to
exactly the bytes in the bag. Then it reads the MCAP file again with the `mcap` and
`mcap-ros2-support` packages, whose decoder builds each type from the schema text alone,
and prints the header, the metadata record names and how many messages decoded.

usage: python3 rosbags_dump.py BAG_DIR
"""

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore, get_types_from_msg


def plain(value):
    """A deserialised message as JSON-able data, floats as their repr (exact, NaN too).

    Only the fields: rosbags also lists `__msgtype__` and the constants (UPPER_CASE).
    """
    if dataclasses.is_dataclass(value):
        fields = [f.name for f in dataclasses.fields(value) if not f.name.startswith("__") and not f.name.isupper()]
        return {name: plain(getattr(value, name)) for name in fields}
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, np.generic):
        return plain(value.item())
    return value


def main():
    humble = get_typestore(Stores.ROS2_HUMBLE)
    own = get_typestore(Stores.EMPTY)
    out = {"topics": {}, "messages": []}
    with Reader(sys.argv[1]) as reader:
        out["message_count"] = reader.message_count
        out["start_time"] = reader.start_time
        out["end_time"] = reader.end_time
        out["compression_mode"] = reader.compression_mode
        for conn in reader.connections:
            text = conn.msgdef.data
            expected, _ = humble.generate_msgdef(conn.msgtype, ros_version=2)
            own.register(get_types_from_msg(text, conn.msgtype))
            out["topics"][conn.topic] = {
                "type": conn.msgtype,
                "count": conn.msgcount,
                "definition_format": conn.msgdef.format.name,
                "definition_matches_humble": text == expected,
                "qos": [
                    {
                        "history": q.history.name.lower(),
                        "depth": q.depth,
                        "reliability": q.reliability.name.lower(),
                        "durability": q.durability.name.lower(),
                    }
                    for q in conn.ext.offered_qos_profiles
                ],
            }
        for conn, timestamp, raw in reader.messages():
            msg = humble.deserialize_cdr(raw, conn.msgtype)
            again = own.deserialize_cdr(raw, conn.msgtype)
            out["messages"].append(
                {
                    "topic": conn.topic,
                    "log_time": timestamp,
                    "msg": plain(msg),
                    "own_definitions_agree": json.dumps(plain(msg)) == json.dumps(plain(again)),
                    "reserialised_identical": bytes(humble.serialize_cdr(msg, conn.msgtype)) == bytes(raw),
                }
            )
    (storage,) = sorted(Path(sys.argv[1]).glob("*.mcap"))
    with storage.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        decoded = sum(1 for _ in reader.iter_decoded_messages())
        out["mcap"] = {
            "profile": header.profile,
            "metadata_records": [m.name for m in reader.iter_metadata()],
            "decoded_from_schemas": decoded,
        }
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
