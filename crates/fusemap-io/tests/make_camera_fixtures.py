#!/usr/bin/env python3
"""Write camera images and calibrations as ROS 1 and ROS 2 logs with rosbags.

Usage:
    make_camera_fixtures.py OUT_DIR [--frames N]

Writes the same messages three times into OUT_DIR, which must not exist yet or be empty:

    ros1.bag          ROS 1 bag v2.0, bz2-compressed chunks  (rosbags.rosbag1.Writer, ROS1_NOETIC)
    rosbag2_sqlite3/  rosbag2 directory, SQLite3 storage      (rosbags.rosbag2.Writer, ROS2_HUMBLE)
    rosbag2_mcap/     rosbag2 directory, MCAP storage         (rosbags.rosbag2.Writer, ROS2_HUMBLE)

N frames (default 3), 100 ms apart, each of these messages, log times 1 ms apart:

    /camera/camera_info   sensor_msgs/msg/CameraInfo  640x480 plumb_bob, K with fx 525 + frame
    /camera/labels        sensor_msgs/msg/Image  mono8, 5x4, step 8 (3 bytes of row padding)
    /camera/labels16      sensor_msgs/msg/Image  mono16 big-endian, 3x2, step 6
    /camera/depth         sensor_msgs/msg/Image  32FC1 metres, 5x4, step 20, one NaN
    /camera/depth_mm      sensor_msgs/msg/Image  16UC1 millimetres, 5x4, step 12, one 0

all in frame `camera_optical`. Label ids and depths depend on the pixel and the frame.

Prints a JSON summary on stdout: the outputs, package versions, and every message as
written: topic, log time, header stamp (sec, nanosec), frame, and for images width,
height, encoding, is_bigendian, step, the data bytes, and the pixel values a decoder
must give (class ids; depth in metres as float32 bit patterns, null for "no depth");
for camera infos width, height, distortion_model, d and k.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Rosbag1Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Rosbag2Writer
from rosbags.typesys import Stores, get_typestore

ROS2_TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
ROS1_TYPESTORE = get_typestore(Stores.ROS1_NOETIC)

IMAGE = "sensor_msgs/msg/Image"
INFO = "sensor_msgs/msg/CameraInfo"
TOPICS = {
    "/camera/camera_info": INFO,
    "/camera/labels": IMAGE,
    "/camera/labels16": IMAGE,
    "/camera/depth": IMAGE,
    "/camera/depth_mm": IMAGE,
}
FRAME = "camera_optical"
FIRST_SEC = 1_700_000_000


def f32_bits(x: float) -> int:
    """The IEEE 754 bit pattern of the float32 nearest to x (JSON numbers are not exact)."""
    return struct.unpack("<I", struct.pack("<f", x))[0]


def image(topic: str, f: int) -> dict:
    """One image message as a dict: its fields, its bytes and the expected pixel values."""
    if topic == "/camera/labels":
        w, h, step = 5, 4, 8
        values = [(r * w + c + f) % 8 for r in range(h) for c in range(w)]
        rows = [bytes(values[r * w:(r + 1) * w]) + b"\xee" * (step - w) for r in range(h)]
        return dict(encoding="mono8", is_bigendian=0, width=w, height=h, step=step, data=b"".join(rows), labels=values)
    if topic == "/camera/labels16":
        w, h, step = 3, 2, 6
        values = [300 * (r * w + c) + f for r in range(h) for c in range(w)]
        data = b"".join(struct.pack(">H", v) for v in values)
        return dict(encoding="mono16", is_bigendian=1, width=w, height=h, step=step, data=data, labels=values)
    if topic == "/camera/depth":
        w, h, step = 5, 4, 20
        metres = [0.5 + 0.25 * (r * w + c) + f for r in range(h) for c in range(w)]
        metres[7] = math.nan
        data = b"".join(struct.pack("<f", v) for v in metres)
        expected = [None if math.isnan(v) else f32_bits(v) for v in metres]
        return dict(encoding="32FC1", is_bigendian=0, width=w, height=h, step=step, data=data, metres=expected)
    w, h, step = 5, 4, 12
    mm = [1000 + 100 * (r * w + c) + f for r in range(h) for c in range(w)]
    mm[3] = 0
    rows = [b"".join(struct.pack("<H", v) for v in mm[r * w:(r + 1) * w]) + b"\x00\x00" for r in range(h)]
    expected = [None if v == 0 else f32_bits(v / 1000.0) for v in mm]
    return dict(encoding="16UC1", is_bigendian=0, width=w, height=h, step=step, data=b"".join(rows), metres=expected)


def camera_info(f: int) -> dict:
    k = [525.0 + f, 0.0, 319.5, 0.0, 526.0 + f, 239.5, 0.0, 0.0, 1.0]
    return dict(width=640, height=480, distortion_model="plumb_bob", d=[0.1, -0.25, 0.001, -0.002, 0.05], k=k)


def make_messages(frames: int) -> list[dict]:
    messages = []
    for f in range(frames):
        for i, topic in enumerate(TOPICS):
            m = {
                "topic": topic,
                "log_time": (FIRST_SEC * 10**9) + f * 100_000_000 + i * 1_000_000,
                "sec": FIRST_SEC,
                "nanosec": f * 100_000_000 + 500,
                "frame_id": FRAME,
            }
            m.update(camera_info(f) if TOPICS[topic] == INFO else image(topic, f))
            messages.append(m)
    return messages


def as_msg(ts, m: dict, ros1: bool):
    t = ts.types
    stamp = t["builtin_interfaces/msg/Time"](sec=m["sec"], nanosec=m["nanosec"])
    header_fields = {"stamp": stamp, "frame_id": m["frame_id"]}
    if ros1:
        header_fields["seq"] = 0
    header = t["std_msgs/msg/Header"](**header_fields)
    if TOPICS[m["topic"]] == IMAGE:
        return t[IMAGE](
            header=header,
            height=m["height"],
            width=m["width"],
            encoding=m["encoding"],
            is_bigendian=m["is_bigendian"],
            step=m["step"],
            data=np.frombuffer(m["data"], dtype=np.uint8),
        )
    roi = t["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    fields = dict(
        header=header,
        height=m["height"],
        width=m["width"],
        distortion_model=m["distortion_model"],
        binning_x=0,
        binning_y=0,
        roi=roi,
    )
    matrices = {"d": m["d"], "k": m["k"], "r": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], "p": [7.0] * 12}
    for name, value in matrices.items():
        fields[name.upper() if ros1 else name] = np.array(value, dtype=np.float64)
    return t[INFO](**fields)


def write_rosbag2(out: Path, messages: list[dict], plugin) -> None:
    writer = Rosbag2Writer(out, version=9, storage_plugin=plugin)
    writer.open()
    try:
        connections = {tp: writer.add_connection(tp, ty, typestore=ROS2_TYPESTORE) for tp, ty in TOPICS.items()}
        for m in messages:
            data = ROS2_TYPESTORE.serialize_cdr(as_msg(ROS2_TYPESTORE, m, ros1=False), TOPICS[m["topic"]])
            writer.write(connections[m["topic"]], m["log_time"], bytes(data))
    finally:
        writer.close()


def write_rosbag1(out: Path, messages: list[dict]) -> None:
    writer = Rosbag1Writer(out)
    writer.set_compression(Rosbag1Writer.CompressionFormat.BZ2)
    writer.open()
    try:
        connections = {
            tp: writer.add_connection(tp, ty, typestore=ROS1_TYPESTORE, callerid="/make_camera_fixtures")
            for tp, ty in TOPICS.items()
        }
        for m in messages:
            data = ROS1_TYPESTORE.serialize_ros1(as_msg(ROS1_TYPESTORE, m, ros1=True), TOPICS[m["topic"]])
            writer.write(connections[m["topic"]], m["log_time"], bytes(data))
    finally:
        writer.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out_dir", type=Path)
    parser.add_argument("--frames", type=int, default=3)
    args = parser.parse_args()
    if args.out_dir.exists() and any(args.out_dir.iterdir()):
        print(f"{args.out_dir}: exists and is not empty", file=sys.stderr)
        return 2
    args.out_dir.mkdir(parents=True, exist_ok=True)
    messages = make_messages(args.frames)
    outputs = {
        "ros1_bag": args.out_dir / "ros1.bag",
        "rosbag2_sqlite3": args.out_dir / "rosbag2_sqlite3",
        "rosbag2_mcap": args.out_dir / "rosbag2_mcap",
    }
    write_rosbag1(outputs["ros1_bag"], messages)
    write_rosbag2(outputs["rosbag2_sqlite3"], messages, StoragePlugin.SQLITE3)
    write_rosbag2(outputs["rosbag2_mcap"], messages, StoragePlugin.MCAP)
    summary = {
        "outputs": {k: str(v) for k, v in outputs.items()},
        "versions": {p: version(p) for p in ("rosbags", "numpy")},
        "messages": [{**m, "data": list(m["data"])} if "data" in m else m for m in messages],
    }
    json.dump(summary, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
