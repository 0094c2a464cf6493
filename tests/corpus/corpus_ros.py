"""Corpus cases in ROS containers: ROS 1 bags, MCAP files and rosbag2 directories,
written by the third-party writers of tests/fixtures and then broken byte by byte."""

from __future__ import annotations

import bz2
import copy
import math
import sqlite3
import struct
import sys
from pathlib import Path

import zstandard
from mcap.reader import make_reader
from mcap.writer import Writer as McapWriter

from corpus_base import CASES, REPO, carmen_lines, case, log_case, patched, random_flips, text

sys.path.insert(0, str(REPO / "tests" / "fixtures"))
import make_ros_fixtures as ros  # noqa: E402


# ---------------------------------------------------------------------------------------
# ROS 1 bags.


def ros_messages(lines: list[str], tmp: Path):
    src = tmp / "base.log"
    src.write_bytes(text(lines))
    messages, _ = ros.read_carmen(src, None)
    return messages, ros.first_stamp(messages)


def write_ros1(out: Path, messages, static_stamp: int, compression, mutate=None, raw=()) -> None:
    """A ROS 1 bag of `messages`; `mutate(topic, n, message dict)`, when given, returns
    the dicts to write in place of the n-th message of `topic` (none drops it). `raw`:
    (topic, type, log time, serialized bytes) written in log-time order with the messages,
    one connection per topic and type."""
    writer = ros.Rosbag1Writer(out)
    if compression is not None:
        writer.set_compression(compression)
    writer.open()
    try:
        conns = {t: writer.add_connection(t, ty, typestore=ros.ROS1_TYPESTORE, callerid="/corpus")
                 for t, ty in ros.TOPICS.items()}
        raw_conns = {}
        for topic, ty, t, data in raw:
            if (topic, ty) not in raw_conns:
                raw_conns[topic, ty] = writer.add_connection(topic, ty, typestore=ros.ROS1_TYPESTORE,
                                                             callerid="/corpus")
        # In receive order with the room's messages, as a recorder writes them (raw
        # messages first at equal log times).
        pending = sorted(enumerate(raw), key=lambda r: (r[1][2], r[0]))[::-1]
        seq = dict.fromkeys(ros.TOPICS, 0)
        for m in [*messages, None]:
            while pending and (m is None or pending[-1][1][2] <= m.log_time):
                topic, ty, t, data = pending.pop()[1]
                writer.write(raw_conns[topic, ty], t, data)
            if m is None:
                break
            ty = ros.TOPICS[m.topic]
            d = ros.as_dict(m, static_stamp, seq=seq[m.topic])
            for d in mutate(m.topic, seq[m.topic], d) if mutate else [d]:
                msg = ros.as_rosbags(ros.ROS1_TYPESTORE, ty, d)
                writer.write(conns[m.topic], m.log_time, bytes(ros.ROS1_TYPESTORE.serialize_ros1(msg, ty)))
            seq[m.topic] += 1
    finally:
        writer.close()


def ros1_records(data: bytes) -> list[tuple[int, int, dict, int, int]]:
    """Top-level records: (offset, header_len, fields, data_offset, data_len)."""
    pos = len(b"#ROSBAG V2.0\n")
    out = []
    while pos + 4 <= len(data):
        hlen = struct.unpack_from("<I", data, pos)[0]
        hstart = pos + 4
        fields = {}
        p = hstart
        while p < hstart + hlen:
            flen = struct.unpack_from("<I", data, p)[0]
            k, _, v = data[p + 4:p + 4 + flen].partition(b"=")
            fields[k.decode()] = (p + 4 + len(k) + 1, v)
            p += 4 + flen
        dlen = struct.unpack_from("<I", data, hstart + hlen)[0]
        out.append((pos, hlen, fields, hstart + hlen + 4, dlen))
        pos = hstart + hlen + 4 + dlen
    return out


def ros1_cases(tmp: Path) -> None:
    messages, static = ros_messages(carmen_lines(), tmp)
    variants = {
        "none": None,
        "bz2": ros.Rosbag1Writer.CompressionFormat.BZ2,
        "lz4": ros.Rosbag1Writer.CompressionFormat.LZ4,
    }
    bags = {}
    for what, comp in variants.items():
        p = tmp / f"{what}.bag"
        write_ros1(p, messages, static, comp)
        bags[what] = p.read_bytes()
        log_case(f"ros1/good-{what}", "room.bag", bags[what], "map", summary={"scans": 40})
    data = bags["none"]
    for frac in (0.05, 0.2, 0.4, 0.6, 0.8, 0.95, 0.999):
        log_case(f"ros1/cut-at-{frac * 100:g}pct", "room.bag", data[:int(len(data) * frac)], "either")
    log_case("ros1/magic-only", "room.bag", b"#ROSBAG V2.0\n", "error")
    log_case("ros1/version-1.2", "room.bag", b"#ROSBAG V1.2\n" + data[13:], "error", names=["1.2"])
    for rec_no, (off, hlen, fields, doff, dlen) in enumerate(ros1_records(data)):
        op = fields.get("op", (0, b"?"))[1]
        kind = {b"\x03": "bag-header", b"\x05": "chunk", b"\x07": "connection", b"\x04": "index",
                b"\x06": "chunk-info", b"\x02": "message"}.get(op, "record")
        if rec_no > 3 and kind in ("index", "chunk-info", "connection"):
            continue  # the first of each kind is enough
        tag = f"{kind}-{rec_no}"
        log_case(f"ros1/{tag}-header-len-huge", "room.bag", patched(data, off, struct.pack("<I", 0xFFFFFFF0)),
                 "either")
        log_case(f"ros1/{tag}-header-len-zero", "room.bag", patched(data, off, struct.pack("<I", 0)), "either")
        log_case(f"ros1/{tag}-data-len-huge", "room.bag", patched(data, doff - 4, struct.pack("<I", 0xFFFFFFF0)),
                 "either")
        log_case(f"ros1/{tag}-data-len-plus-one", "room.bag", patched(data, doff - 4, struct.pack("<I", dlen + 1)),
                 "either")
        at, _ = fields["op"]
        log_case(f"ros1/{tag}-unknown-op", "room.bag", patched(data, at, b"\x63"), "either")
    # Chunks: the stated size wrong, the compression unknown, a bomb inside.
    for what in ("bz2", "lz4"):
        data = bags[what]
        recs = ros1_records(data)
        chunk = next(r for r in recs if r[2].get("op", (0, b""))[1] == b"\x05")
        off, hlen, fields, doff, dlen = chunk
        size_at, size = fields["size"]
        size = struct.unpack("<I", size)[0]
        for label, value in {"zero": 0, "minus-one": size - 1, "plus-one": size + 1, "4gib": 0xFFFFFFFF}.items():
            log_case(f"ros1/{what}-chunk-size-{label}", "room.bag", patched(data, size_at, struct.pack("<I", value)),
                     "error", names=["chunk"])
        comp_at, comp = fields["compression"]
        log_case(f"ros1/{what}-chunk-compression-unknown", "room.bag",
                 patched(data, comp_at, b"zip"[:len(comp)].ljust(len(comp), b"x")), "error")
        body = bytearray(data[doff:doff + dlen])
        for j in range(len(body) // 3, len(body) // 3 + 32):
            body[j] ^= 0x5A
        log_case(f"ros1/{what}-chunk-body-corrupt", "room.bag", data[:doff] + bytes(body) + data[doff + dlen:],
                 "either")
    # A bz2 chunk that inflates to 64 MiB while it states 4 KiB.
    data = bags["bz2"]
    recs = ros1_records(data)
    off, hlen, fields, doff, dlen = next(r for r in recs if r[2].get("op", (0, b""))[1] == b"\x05")
    bomb = bz2.compress(bytes(64 << 20), 9)
    size_at, _ = fields["size"]
    head = patched(data[:doff - 4], size_at, struct.pack("<I", 4096))
    log_case("ros1/bz2-chunk-bomb", "bomb.bag", head + struct.pack("<I", len(bomb)) + bomb + data[doff + dlen:],
             "error", names=["chunk"])
    head = patched(data[:doff - 4], size_at, struct.pack("<I", 0xFFFFFFFF))
    log_case("ros1/bz2-chunk-bomb-claims-4gib", "bomb.bag",
             head + struct.pack("<I", len(bomb)) + bomb + data[doff + dlen:], "error", names=["chunk"])
    random_flips("ros1/random-flips", "room.bag", bags["none"], 12)
    ros1_message_cases(tmp, messages, static)


def ros1_message_cases(tmp: Path, messages, static: int) -> None:
    """Well-formed bags whose messages say something wrong."""

    def at(topic: str, n: int | None, change):
        def mutate(t: str, i: int, d: dict) -> list[dict]:
            return change(copy.deepcopy(d)) if t == topic and (n is None or i == n) else [d]
        return mutate

    def setting(**fields):
        return lambda d: [{**d, **fields}]

    lidar = "log.lidars.0.scans_skipped."
    cases = {
        "scan-angle-increment-zero": (at("/scan", 10, setting(angle_increment=0.0)), "map", {lidar + "bad_angles": 1}),
        "scan-angle-increment-nan": (at("/scan", 10, setting(angle_increment=math.nan)), "map",
                                     {lidar + "bad_angles": 1}),
        "scan-twice-the-ranges": (at("/scan", 10, lambda d: [{**d, "ranges": list(d["ranges"]) * 2}]), "map",
                                  {lidar + "bad_angles": 1}),
        "scan-recorded-twice": (at("/scan", 10, lambda d: [d, d]), "map", {lidar + "repeated": 1, "scans": 40}),
        "scan-range-max-below-min": (at("/scan", None, setting(range_min=5.0, range_max=1.0)), "no_map", {}),
        "scan-dropped-odometry": (at("/odom", None, lambda d: []), "map", {}),
    }
    # The lidar driver stalls at scan 10 and republishes that reading while the robot
    # drives on: the 26 frozen scans read after it has moved 10 cm are noted and not mapped.
    held = {}

    def frozen(t: str, i: int, d: dict) -> list[dict]:
        if t != "/scan" or i < 10:
            return [d]
        held.setdefault("ranges", list(d["ranges"]))
        return [{**d, "ranges": held["ranges"]}]

    cases["scan-frozen-while-moving"] = (frozen, "map", {lidar + "frozen": 26, "scans": 14})
    for what, (mutate, expect, summary) in cases.items():
        p = tmp / f"{what}.bag"
        write_ros1(p, messages, static, None, mutate)
        names = ["no map was written"] if expect == "no_map" else []
        log_case(f"ros1/{what}", "room.bag", p.read_bytes(), expect, names=names, summary=summary)

    def conflicting_static(t: str, i: int, d: dict) -> list[dict]:
        if t != "/tf_static":
            return [d]
        other = copy.deepcopy(d)
        other["transforms"][0]["transform"]["translation"]["x"] = 0.5
        return [d, other]

    p = tmp / "static-conflict.bag"
    write_ros1(p, messages, static, None, conflicting_static)
    log_case("ros1/tf-static-conflict", "room.bag", p.read_bytes(), "map",
             summary={"log.frames.rejected.conflicting_static": 1})

    def second_frame(t: str, i: int, d: dict) -> list[dict]:
        if t == "/scan" and i % 2:
            d = copy.deepcopy(d)
            d["header"]["frame_id"] = "laser_rear"
        return [d]

    p = tmp / "two-frames.bag"
    write_ros1(p, messages, static, None, second_frame)
    log_case("ros1/scan-topic-with-two-frames", "room.bag", p.read_bytes(), "map", notes=["laser_rear"])

    def odom_jump(t: str, i: int, d: dict) -> list[dict]:
        if t in ("/odom", "/tf") and i == 20:
            d = copy.deepcopy(d)
            pose = d["pose"]["pose"]["position"] if t == "/odom" else d["transforms"][0]["transform"]["translation"]
            pose["x"] += 1e8
        return [d]

    # Found by fuzzing the camera decoding: a 0 x 1,124,073,476 image made the depth decoder
    # walk a billion empty rows. Now a malformed message, counted, and the scans map.
    def ros1_image(width: int, height: int, encoding: bytes, step: int, data: bytes) -> bytes:
        frame = b"camera"
        head = struct.pack("<III", 0, 1000, 0) + struct.pack("<I", len(frame)) + frame
        return (head + struct.pack("<II", height, width) + struct.pack("<I", len(encoding)) + encoding
                + struct.pack("<BI", 0, step) + struct.pack("<I", len(data)) + data)

    p = tmp / "image-zero-by-billion.bag"
    image = ros1_image(0, 1_124_073_476, b"16UC1", 0, b"")
    write_ros1(p, messages, static, None, raw=[("/camera/depth", "sensor_msgs/msg/Image", static, image)])
    log_case("ros1/image-0-by-1124073476", "room.bag", p.read_bytes(), "map",
             summary={"scans": 40, "log.malformed_records": 1})

    p = tmp / "odom-jump.bag"
    write_ros1(p, messages, static, None, odom_jump)
    log_case("ros1/odometry-jumps-1e8m", "room.bag", p.read_bytes(), "map", notes=["glitch"])

    # An odometry reset that stays (a wheel driver restarted with garbage), and odometry
    # alternating by ±10¹⁷ m: SLAM must neither follow the jump nor grow a submap across it
    # (it allocated until the process aborted), and the mapping pass holds the memory budget.
    def odom_reset(jump: float, every_other: bool):
        def mutate(t: str, i: int, d: dict) -> list[dict]:
            if t in ("/odom", "/tf") and (i % 2 == 1 if every_other else i >= 20):
                d = copy.deepcopy(d)
                pose = d["pose"]["pose"]["position"] if t == "/odom" else d["transforms"][0]["transform"]["translation"]
                pose["x"] += jump if i % 4 < 2 or not every_other else -jump
            return [d]
        return mutate

    for what, jump, every_other, note in (
        ("odometry-reset-1e17", 1e17, False, "more than 1e9 m from their frame's origin"),
        ("odometry-alternating-1e17", 1e17, True, "rejected as glitches"),
        ("odometry-reset-1000km", 1e6, False, "moved faster than log.max_speed_m_s"),
    ):
        p = tmp / f"{what}.bag"
        write_ros1(p, messages, static, None, odom_reset(jump, every_other))
        log_case(f"ros1/{what}", "room.bag", p.read_bytes(), "map", notes=[note])

    pose_sensor_cases(tmp, messages, static)


def ros1_header(seq: int, stamp_ns: int, frame: bytes) -> bytes:
    return struct.pack("<III", seq, stamp_ns // 10**9, stamp_ns % 10**9) + struct.pack("<I", len(frame)) + frame


def nav_sat_fix(seq: int, stamp_ns: int, lat: float, lon: float, alt: float, status: int = 2,
                covariance_type: int = 2) -> bytes:
    """A ROS 1 `sensor_msgs/NavSatFix`: 2 cm RTK unless told otherwise."""
    cov = [4e-4, 0, 0, 0, 4e-4, 0, 0, 0, 1e-3]
    return (ros1_header(seq, stamp_ns, b"gps") + struct.pack("<bH", status, 1) + struct.pack("<3d", lat, lon, alt)
            + struct.pack("<9d", *cov) + struct.pack("<B", covariance_type))


def imu(seq: int, stamp_ns: int, yaw_rate: float) -> bytes:
    """A ROS 1 `sensor_msgs/Imu` with no orientation (covariance[0] = -1) and a yaw rate."""
    return (ros1_header(seq, stamp_ns, b"base_link") + struct.pack("<4d", 0, 0, 0, 1) + struct.pack("<9d", -1, *[0] * 8)
            + struct.pack("<3d", 0, 0, yaw_rate) + struct.pack("<9d", 1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4)
            + struct.pack("<3d", 0, 0, 9.81) + struct.pack("<9d", *[0] * 9))


def pose_sensor_cases(tmp: Path, messages, static: int) -> None:
    """GNSS fixes and gyro rates no sensor can produce, beside the room's odometry and
    scans: each is dropped and counted by reason, and the room maps."""
    odom_times = [m.log_time for m in messages if m.topic == "/odom"]
    lat0, lon0, alt0 = 48.137, 11.575, 520.0
    gnss = "log.estimator.gnss_input.0."
    fix_cases = {
        "gnss-latitude-91": (dict(lat=91.0), {gnss + "out_of_range": len(odom_times)}),
        "gnss-latitude-1e308": (dict(lat=1e308), {gnss + "out_of_range": len(odom_times)}),
        "gnss-longitude-minus-181": (dict(lon=-181.0), {gnss + "out_of_range": len(odom_times)}),
        "gnss-altitude-1e6": (dict(alt=1e6), {gnss + "out_of_range": len(odom_times)}),
        "gnss-status-5": (dict(status=5), {gnss + "invalid_field": len(odom_times)}),
        "gnss-covariance-type-9": (dict(covariance_type=9), {gnss + "invalid_field": len(odom_times)}),
    }
    for what, (fault, summary) in fix_cases.items():
        raw = []
        for i, t in enumerate(odom_times):
            f = {**dict(lat=lat0, lon=lon0, alt=alt0), **fault}
            raw.append(("/fix", "sensor_msgs/msg/NavSatFix", t, nav_sat_fix(i, t, **f)))
        p = tmp / f"{what}.bag"
        write_ros1(p, messages, static, None, raw=raw)
        log_case(f"ros1/{what}", "room.bag", p.read_bytes(), "map",
                 summary={"scans": 40, gnss + "passed": 0, **summary}, notes=["receiver faults"])
    raw = [("/imu", "sensor_msgs/msg/Imu", t, imu(i, t, 1e30 if i == 5 else 0.0)) for i, t in enumerate(odom_times)]
    p = tmp / "gyro-1e30.bag"
    write_ros1(p, messages, static, None, raw=raw)
    log_case("ros1/gyro-rate-1e30", "room.bag", p.read_bytes(), "map",
             summary={"scans": 40, "log.estimator.estimator.gyro.implausible": 1})


# ---------------------------------------------------------------------------------------
# MCAP and rosbag2.


def mcap_records(data: bytes) -> list[tuple[int, int, int]]:
    """Top-level records: (offset, opcode, length)."""
    pos, out = 8, []
    while pos + 9 <= len(data):
        op = data[pos]
        length = struct.unpack_from("<Q", data, pos + 1)[0]
        out.append((pos, op, length))
        if op == 0x02:  # footer
            break
        pos += 9 + length
    return out


def mcap_cases(tmp: Path) -> None:
    messages, static = ros_messages(carmen_lines(), tmp)
    p = tmp / "room.mcap"
    ros.write_bare_mcap(p, messages, static)
    data = p.read_bytes()
    log_case("mcap/good", "room.mcap", data, "map", summary={"scans": 40})
    for frac in (0.02, 0.3, 0.6, 0.9, 0.99):
        log_case(f"mcap/cut-at-{frac * 100:g}pct", "room.mcap", data[:int(len(data) * frac)], "either")
    log_case("mcap/magic-only", "room.mcap", data[:8], "error")
    log_case("mcap/no-closing-magic", "room.mcap", data[:-8], "either")
    recs = mcap_records(data)
    for off, op, length in recs:
        if op not in (0x01, 0x06, 0x02, 0x03, 0x04):
            continue
        name = {0x01: "header", 0x06: "chunk", 0x02: "footer", 0x03: "schema", 0x04: "channel"}[op]
        log_case(f"mcap/{name}-at-{off}-length-huge", "room.mcap", patched(data, off + 1, struct.pack("<Q", 1 << 62)),
                 "either")
        log_case(f"mcap/{name}-at-{off}-length-short", "room.mcap",
                 patched(data, off + 1, struct.pack("<Q", max(length // 2, 1))), "either")
    # A channel record whose topic claims 3.5 GB (the MCAP fuzz target's first find: the
    # mcap crate reserves a string's stated length before reading it).
    channel_off = next(off for off, op, _ in recs if op == 0x04)
    log_case("mcap/channel-topic-length-3.5gb", "room.mcap",
             patched(data, channel_off + 9 + 4, struct.pack("<I", 0xD1AA1F80)), "error", names=["claims"])
    chunk_off = next(off for off, op, _ in recs if op == 0x06)
    # Chunk content: start u64, end u64, uncompressed_size u64, crc u32, compression str, records.
    usize_at = chunk_off + 9 + 16
    usize = struct.unpack_from("<Q", data, usize_at)[0]
    for label, value in {"zero": 0, "minus-one": usize - 1, "huge": 1 << 40}.items():
        log_case(f"mcap/chunk-uncompressed-size-{label}", "room.mcap",
                 patched(data, usize_at, struct.pack("<Q", value)), "error", names=["chunk"])
    # A chunk whose zstd records inflate to 1 GiB but say 4 KiB.
    cctx = zstandard.ZstdCompressor(level=1)
    bomb = cctx.compress(bytes(1 << 30))
    content = struct.pack("<QQQI", 0, 1, 4096, 0) + struct.pack("<I", 4) + b"zstd" + struct.pack("<Q", len(bomb)) + bomb
    record = bytes([0x06]) + struct.pack("<Q", len(content)) + content
    log_case("mcap/zstd-chunk-bomb", "bomb.mcap", data[:chunk_off] + record + data[chunk_off:], "error",
             names=["chunk"])
    random_flips("mcap/random-flips", "room.mcap", data, 10)


def rosbag2_dir(tmp: Path, name: str, plugin) -> Path:
    messages, static = ros_messages(carmen_lines(), tmp)
    out = tmp / name
    ros.write_rosbag2(out, plugin, messages, static)
    return out


def copy_bag(src: Path, dst: Path) -> None:
    dst.mkdir()
    for f in src.iterdir():
        (dst / f.name).write_bytes(f.read_bytes())


def bag_case(name: str, src: Path, expect: str, names=(), edit=None, **extra) -> Path:
    names = ["{case}/bag", *names] if expect == "error" else list(names)
    doctor = {"error": "fail", "no_map": "fail", "map": "ok"}.get(expect, "any")
    d = case(name, ["map", "--out", "{case}/out", "{case}/bag"], expect, names=names, doctor=doctor, **extra)
    copy_bag(src, d / "bag")
    if edit:
        edit(d / "bag")
    return d


def _restyle_metadata(path: Path, style: str) -> None:
    """Rewrites a metadata.yaml in block style, in flow style (as PyYAML's
    `default_flow_style=True` writes it) or as JSON: the same document, other spellings."""
    import io
    import json

    from ruamel.yaml import YAML  # rosbags' own YAML library

    doc = YAML(typ="safe", pure=True).load(path.read_text())
    if style == "json":
        path.write_text(json.dumps(doc, indent=2))
        return
    out = YAML(typ="safe", pure=True)
    out.default_flow_style = style == "flow"
    buf = io.StringIO()
    out.dump(doc, buf)
    text = buf.getvalue()
    assert text.lstrip().startswith("{") == (style == "flow"), text[:80]
    path.write_text(text)


def rosbag2_cases(tmp: Path) -> None:
    mcap_bag = rosbag2_dir(tmp, "bag-mcap", ros.StoragePlugin.MCAP)
    db3_bag = rosbag2_dir(tmp, "bag-db3", ros.StoragePlugin.SQLITE3)
    db3_name = next(f.name for f in db3_bag.iterdir() if f.suffix == ".db3")
    mcap_name = next(f.name for f in mcap_bag.iterdir() if f.suffix == ".mcap")
    bag_case("rosbag2/good-mcap", mcap_bag, "map", summary={"scans": 40})
    bag_case("rosbag2/good-db3", db3_bag, "map", summary={"scans": 40})

    def meta_edit(old: str, new: str):
        def edit(bag: Path):
            m = bag / "metadata.yaml"
            t = m.read_text()
            assert old in t, old
            m.write_text(t.replace(old, new))
        return edit

    for what, path in {"parent": "../../../etc/passwd", "absolute": "/etc/passwd", "sibling": "../other.db3"}.items():
        bag_case(f"rosbag2/path-{what}", db3_bag, "error", names=["outside"],
                 edit=meta_edit(f"- {db3_name}", f"- {path}"))
    bag_case("rosbag2/file-listed-twice", db3_bag, "error", names=["twice"],
             edit=meta_edit(f"- {db3_name}", f"- {db3_name}\n  - ./{db3_name}"))
    bag_case("rosbag2/file-missing", db3_bag, "error", names=["none.db3"],
             edit=meta_edit(f"- {db3_name}", "- none.db3"))
    # An unknown storage plugin name: the files' extensions say what they are.
    bag_case("rosbag2/storage-unknown", db3_bag, "map",
             edit=meta_edit("storage_identifier: sqlite3", "storage_identifier: floppy"))
    bag_case("rosbag2/yaml-broken", db3_bag, "error", names=["metadata.yaml"],
             edit=lambda b: (b / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n  {{{\n"))
    bag_case("rosbag2/yaml-empty", db3_bag, "error", names=["metadata.yaml"],
             edit=lambda b: (b / "metadata.yaml").write_text(""))
    # One metadata.yaml in three YAML styles: each maps the bag as the block style
    # rosbag2 writes does (the same 40 scans; crates/fusemap-cli/tests/cli/formats.rs
    # checks the maps are bit-identical).
    for style in ("block", "flow", "json"):
        bag_case(f"rosbag2/metadata-{style}", mcap_bag, "map", summary={"scans": 40},
                 edit=lambda b, style=style: _restyle_metadata(b / "metadata.yaml", style))
    bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 10))
    bag_case("rosbag2/yaml-alias-bomb", db3_bag, "error", names=["metadata.yaml", "alias"],
             edit=lambda b: (b / "metadata.yaml").write_text(bomb))
    bag_case("rosbag2/yaml-key-twice", db3_bag, "error", names=["metadata.yaml", "twice"],
             edit=meta_edit("storage_identifier: sqlite3", "storage_identifier: sqlite3\n  storage_identifier: mcap"))
    bag_case("rosbag2/metadata-missing", db3_bag, "error", names=[],
             edit=lambda b: (b / "metadata.yaml").unlink())
    bag_case("rosbag2/message-count-huge", db3_bag, "map",
             edit=meta_edit("message_count: 40", "message_count: 18446744073709551615"))
    bag_case("rosbag2/claims-zstd-messages", db3_bag, "error", names=["zstd"], edit=_claim_zstd)
    bag_case("rosbag2/mcap-cut", mcap_bag, "either",
             edit=lambda b: _cut(b / mcap_name, 0.5))
    bag_case("rosbag2/db3-cut", db3_bag, "map", notes=["cut short", "truncated or corrupt"],
             edit=lambda b: _cut(b / db3_name, 0.5))
    bag_case("rosbag2/db3-header-garbage", db3_bag, "error", names=[],
             edit=lambda b: _overwrite(b / db3_name, 100, b"\xff" * 64))

    def sql(statements: str):
        def edit(bag: Path):
            con = sqlite3.connect(bag / db3_name)
            con.executescript(statements)
            con.commit()
            con.close()
        return edit

    bag_case("rosbag2/db3-messages-is-a-view", db3_bag, "error", names=["view"],
             edit=sql("ALTER TABLE messages RENAME TO m2; CREATE VIEW messages AS SELECT * FROM m2;"))
    bag_case("rosbag2/db3-recursive-view", db3_bag, "error", names=[], max_seconds=1.0,
             edit=sql("ALTER TABLE messages RENAME TO m2; CREATE VIEW messages(id, topic_id, timestamp, data) AS "
                      "WITH RECURSIVE r(n) AS (SELECT 1 UNION ALL SELECT n + 1 FROM r) "
                      "SELECT n, 1, n, zeroblob(10) FROM r ORDER BY n DESC;"))
    bag_case("rosbag2/db3-recursive-view-disguised-as-table", db3_bag, "error", names=["view"], max_seconds=1.0,
             edit=sql("ALTER TABLE messages RENAME TO m2; CREATE VIEW messages(id, topic_id, timestamp, data) AS "
                      "WITH RECURSIVE r(n) AS (SELECT 1 UNION ALL SELECT n + 1 FROM r) "
                      "SELECT n, 1, n, zeroblob(10) FROM r; PRAGMA writable_schema = ON; "
                      "UPDATE sqlite_master SET type = 'table' WHERE name = 'messages';"))
    bag_case("rosbag2/db3-topics-is-a-view", db3_bag, "error", names=["view"],
             edit=sql("ALTER TABLE topics RENAME TO t2; CREATE VIEW topics AS SELECT * FROM t2;"))
    bag_case("rosbag2/db3-no-messages-table", db3_bag, "error", names=["messages"],
             edit=sql("DROP TABLE messages;"))
    bag_case("rosbag2/db3-unknown-topic-id", db3_bag, "either",
             edit=sql("UPDATE messages SET topic_id = 999 WHERE id % 7 = 0;"))
    bag_case("rosbag2/db3-short-blobs", db3_bag, "either",
             edit=sql("UPDATE messages SET data = substr(data, 1, 10) WHERE id % 5 = 0;"))
    bag_case("rosbag2/db3-empty-blobs", db3_bag, "either",
             edit=sql("UPDATE messages SET data = x'' WHERE id % 5 = 0;"))
    bag_case("rosbag2/db3-negative-timestamps", db3_bag, "either",
             edit=sql("UPDATE messages SET timestamp = -timestamp;"))
    d = bag_case("rosbag2/db3-blob-over-decompressed-limit", db3_bag, "error", names=["decompressed_mib"],
                 edit=sql("UPDATE messages SET data = zeroblob(2100000) WHERE id = 5;"))
    d_args = CASES[-1]["args"]
    d_args[1:1] = ["--config", "{case}/limits.toml"]
    CASES[-1]["doctor_args"] = ["doctor", "--config", "{case}/limits.toml", "{case}/bag"]
    (d / "limits.toml").write_text("[limits]\ndecompressed_mib = 1\n")
    bag_case("rosbag2/db3-wal-mode", db3_bag, "map", edit=sql("PRAGMA journal_mode=WAL;"))
    bag_case("rosbag2/db3-type-unknown", db3_bag, "either",
             edit=sql("UPDATE topics SET type = 'my_msgs/msg/Thing';"))
    bag_case("rosbag2/db3-escape-in-topic", db3_bag, "map",
             edit=sql("UPDATE topics SET name = '/odom' || char(27) || '[2J' WHERE name = '/odom';"))
    # A message-compressed bag whose one message inflates to 2 GiB, in both storages.
    bag_case("rosbag2/zstd-message-bomb", db3_bag, "error", names=["decompressed_mib"], edit=_zstd_bomb(db3_name))
    bag_case("rosbag2/mcap-zstd-message-bomb", mcap_bag, "error", names=["decompressed_mib"],
             edit=_mcap_zstd_bomb(mcap_name))


def _claim_zstd(bag: Path) -> None:
    m = bag / "metadata.yaml"
    t = m.read_text()
    t = t.replace("compression_format: ''", "compression_format: zstd").replace(
        "compression_mode: ''", "compression_mode: MESSAGE")
    m.write_text(t)


def _zstd_bomb(db3_name: str):
    def edit(bag: Path) -> None:
        _claim_zstd(bag)
        frame = _bomb_frame()
        con = sqlite3.connect(bag / db3_name)
        rows = con.execute("SELECT id, data FROM messages ORDER BY id").fetchall()
        for i, (row_id, payload) in enumerate(rows):
            blob = frame if i == 3 else zstandard.ZstdCompressor().compress(payload)
            con.execute("UPDATE messages SET data = ? WHERE id = ?", (blob, row_id))
        con.commit()
        con.close()
    return edit


def _bomb_frame() -> bytes:
    """One zstd frame of 2 GiB of zeros, made from 64 MiB pieces."""
    comp = zstandard.ZstdCompressor(level=1).compressobj()
    zero = bytes(64 << 20)
    return b"".join(comp.compress(zero) for _ in range(32)) + comp.flush()


def _mcap_zstd_bomb(mcap_name: str):
    def edit(bag: Path) -> None:
        _claim_zstd(bag)
        path = bag / mcap_name
        with open(path, "rb") as f:
            reader = make_reader(f)
            summary = reader.get_summary()
            rows = [(c.topic, m) for _, c, m in reader.iter_messages(log_time_order=False)]
        frame = _bomb_frame()
        with open(path, "wb") as f:
            w = McapWriter(f)
            w.start(profile="ros2", library="corpus")
            schema_ids = {s.id: w.register_schema(s.name, s.encoding, s.data) for s in summary.schemas.values()}
            channel_ids = {c.topic: w.register_channel(c.topic, c.message_encoding, schema_ids[c.schema_id])
                           for c in summary.channels.values()}
            for i, (topic, m) in enumerate(rows):
                data = frame if i == 3 else zstandard.ZstdCompressor().compress(m.data)
                w.add_message(channel_ids[topic], m.log_time, data, m.publish_time, m.sequence)
            w.finish()
    return edit


def _cut(path: Path, frac: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[:int(len(data) * frac)])


def _overwrite(path: Path, at: int, value: bytes) -> None:
    path.write_bytes(patched(path.read_bytes(), at, value))
