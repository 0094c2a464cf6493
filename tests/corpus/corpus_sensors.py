"""Corpus cases for the sensors besides the lidar, in ROS 1 bags of the room: a semantic
camera (label, depth and camera-info messages) with every kind of broken image and
intrinsics, GNSS fixes and IMU messages no device produces, odometry that contradicts
itself, and the scan streams SLAM and the mapping pass must not be fooled by.

The rule each case checks (issue 27): a sensor whose stream is unusable is left out with
a note saying why and the run maps with the rest; a run is refused only when nothing
usable is left, or when the config names a topic the log does not have; and `doctor`
fails exactly where `map` refuses."""

from __future__ import annotations

import copy
import math
import struct
from pathlib import Path

from corpus_base import BAG_SECTIONS, carmen_lines, case, example_numeric_keys
from corpus_ros import imu, nav_sat_fix, ros1_header, ros_messages, write_ros1

CAMERA = """[[sensor]]
kind = "camera"
name = "camera"
topic = "/camera/labels"
depth_topic = "/camera/depth"
info_topic = "/camera/camera_info"
"""
W, H = 16, 12


def image(seq: int, stamp: int, encoding: bytes, data: bytes, width: int = W, height: int = H,
          step: int | None = None, bigendian: int = 0, frame: bytes = b"camera_optical") -> bytes:
    """A ROS 1 `sensor_msgs/Image`."""
    if step is None:
        step = width * {b"mono8": 1, b"16UC1": 2, b"32FC1": 4}.get(encoding, 1)
    return (ros1_header(seq, stamp, frame) + struct.pack("<II", height, width) + struct.pack("<I", len(encoding))
            + encoding + struct.pack("<BI", bigendian, step) + struct.pack("<I", len(data)) + data)


def labels(seq: int, stamp: int, cls: int = 2, **kw) -> bytes:
    """Class `cls` (a wall) in the upper half, the floor (1) below."""
    rows = [bytes([cls] * W) if r < H // 2 else bytes([1] * W) for r in range(H)]
    return image(seq, stamp, b"mono8", b"".join(rows), **kw)


def depth(seq: int, stamp: int, value: float = 2.0, **kw) -> bytes:
    return image(seq, stamp, b"32FC1", struct.pack(f"<{W * H}f", *[value] * (W * H)), **kw)


def camera_info(seq: int, stamp: int, width: int = W, height: int = H, fx: float = 8.0, fy: float = 8.0,
                model: bytes = b"plumb_bob", d=(0.0, 0.0, 0.0, 0.0, 0.0)) -> bytes:
    """A ROS 1 `sensor_msgs/CameraInfo` of a rectified pinhole camera."""
    cx, cy = width / 2, height / 2
    k = [fx, 0, cx, 0, fy, cy, 0, 0, 1]
    p = [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0]
    return (ros1_header(seq, stamp, b"camera_optical") + struct.pack("<II", height, width)
            + struct.pack("<I", len(model)) + model + struct.pack("<I", len(d)) + struct.pack(f"<{len(d)}d", *d)
            + struct.pack("<9d", *k) + struct.pack("<9d", 1, 0, 0, 0, 1, 0, 0, 0, 1) + struct.pack("<12d", *p)
            + struct.pack("<II", 0, 0) + struct.pack("<IIII?", 0, 0, 0, 0, False))


def camera_stream(scan_times, label=labels, dep=depth, info=camera_info, every: int = 1):
    """Label, depth and camera-info messages at every `every`-th scan's stamp."""
    raw = []
    for i, t in enumerate(scan_times[::every]):
        for topic, ty, make in (("/camera/camera_info", "sensor_msgs/msg/CameraInfo", info),
                                ("/camera/labels", "sensor_msgs/msg/Image", label),
                                ("/camera/depth", "sensor_msgs/msg/Image", dep)):
            if make is not None:
                raw.append((topic, ty, t, make(i, t)))
    return raw


def sensor_case(name: str, bag: Path, config: str, expect: str, names=(), doctor=None, **extra) -> None:
    """`map --config` (and `doctor --config`) of the bag `bag`."""
    if doctor is None:
        doctor = {"error": "fail", "no_map": "fail", "map": "ok"}.get(expect, "any")
    d = case(name, ["map", "--config", "{case}/robot.toml", "--out", "{case}/out", "{case}/room.bag"], expect,
             names=list(names), doctor=doctor,
             doctor_args=["doctor", "--config", "{case}/robot.toml", "{case}/room.bag"], **extra)
    (d / "room.bag").write_bytes(bag.read_bytes())
    (d / "robot.toml").write_text(config)


def sensor_cases(tmp: Path) -> None:
    messages, static = ros_messages(carmen_lines(), tmp)
    camera_cases(tmp, messages, static)
    gnss_cases(tmp, messages, static)
    imu_cases(tmp, messages, static)
    odometry_cases(tmp, messages, static)
    scan_cases(tmp, messages, static)
    config_sweep(tmp, messages, static)


# ---------------------------------------------------------------------------------------
# The camera.


def camera_cases(tmp: Path, messages, static: int) -> None:
    scans = [m.log_time for m in messages if m.topic == "/scan"]
    cam = "log.cameras.0."
    dropped = "camera `camera` is not mapped"
    nan = struct.pack("<f", math.nan)

    def bad_pixels(value: bytes):
        return lambda i, t: image(i, t, b"32FC1", value * (W * H))

    cases = {
        # (stream changes, expect, summary, notes, names)
        "clean": (dict(), "map", {"scans": 40, cam + "frames_used": 40, "camera_frames": 40}, [], []),
        "clean-every-fourth-scan": (dict(every=4), "map", {cam + "frames_used": 10}, [], []),
        "labels-one-byte-short": (dict(label=lambda i, t: labels(i, t)[:-1]), "map", {"scans": 40},
                                  [dropped, "all malformed"], []),
        "depth-one-byte-short": (dict(dep=lambda i, t: depth(i, t)[:-1]), "map", {"scans": 40},
                                 [dropped, "all malformed"], []),
        "labels-half-size": (dict(label=lambda i, t: image(i, t, b"mono8", bytes([2] * (W * H // 4)), W // 2, H // 2)),
                             "map", {cam + "frames_refused": 40, cam + "frames_used": 0}, [], []),
        "labels-step-times-height-overflows": (
            dict(label=lambda i, t: image(i, t, b"mono8", b"\x02" * 64, width=1 << 31, height=1 << 31, step=1 << 31)),
            "map", {"scans": 40}, [dropped, "all malformed"], []),
        "labels-step-below-width": (dict(label=lambda i, t: image(i, t, b"mono8", bytes([2] * (W * H)), step=W - 1)),
                                    "map", {"scans": 40}, [dropped, "all malformed"], []),
        "labels-zero-width": (dict(label=lambda i, t: image(i, t, b"mono8", b"", width=0)),
                              "map", {"scans": 40}, [dropped, "all malformed"], []),
        "labels-65536-square-claimed": (
            dict(label=lambda i, t: image(i, t, b"mono8", b"\x02" * 256, width=65536, height=65536)),
            "map", {"scans": 40}, [dropped], []),
        "labels-unknown-class": (dict(label=lambda i, t: labels(i, t, cls=200)), "map",
                                 {cam + "frames_used": 40}, [], []),
        "labels-rgb8": (dict(label=lambda i, t: image(i, t, b"rgb8", bytes(W * H * 3), step=3 * W)), "map",
                        {cam + "undecodable": 40, cam + "frames_used": 0}, [], []),
        "labels-bigendian-mono16": (
            dict(label=lambda i, t: image(i, t, b"mono16", bytes(2 * W * H), step=2 * W, bigendian=1)),
            "map", {"scans": 40}, [], []),
        "depth-all-nan": (dict(dep=bad_pixels(nan)), "map", {cam + "frames_used": 40}, [], []),
        "depth-all-inf": (dict(dep=lambda i, t: depth(i, t, math.inf)), "map", {cam + "frames_used": 40}, [], []),
        "depth-negative": (dict(dep=lambda i, t: depth(i, t, -2.0)), "map", {cam + "frames_used": 40}, [], []),
        "depth-1e30": (dict(dep=lambda i, t: depth(i, t, 1e30)), "map", {cam + "frames_used": 40}, [], []),
        "depth-16uc1-millimetres": (
            dict(dep=lambda i, t: image(i, t, b"16UC1", struct.pack(f"<{W * H}H", *[2000] * (W * H)))),
            "map", {cam + "frames_used": 40}, [], []),
        "depth-rgb8": (dict(dep=lambda i, t: image(i, t, b"rgb8", bytes(W * H * 3), step=3 * W)), "map",
                       {cam + "undecodable": 40}, [], []),
        "depth-bigger-than-labels": (
            dict(dep=lambda i, t: image(i, t, b"32FC1", struct.pack("<f", 2.0) * (4 * W * H), 2 * W, 2 * H)),
            "map", {cam + "frames_refused": 40}, [], []),
        "info-fx-zero": (dict(info=lambda i, t: camera_info(i, t, fx=0.0)), "map", {"scans": 40}, [dropped], []),
        "info-fx-nan": (dict(info=lambda i, t: camera_info(i, t, fx=math.nan)), "map", {"scans": 40}, [dropped], []),
        "info-fx-negative": (dict(info=lambda i, t: camera_info(i, t, fx=-8.0)), "map", {"scans": 40}, [dropped], []),
        "info-fy-1e308": (dict(info=lambda i, t: camera_info(i, t, fy=1e308)), "map", {"scans": 40}, [], []),
        "info-size-zero": (dict(info=lambda i, t: camera_info(i, t, width=0, height=0)), "map", {"scans": 40},
                           [dropped], []),
        "info-size-differs-from-images": (dict(info=lambda i, t: camera_info(i, t, width=2 * W, height=2 * H)), "map",
                                          {cam + "frames_refused": 40}, [], []),
        "info-distorted": (dict(info=lambda i, t: camera_info(i, t, d=(0.1, 0, 0, 0, 0))), "map", {"scans": 40},
                           [dropped, "plumb_bob"], []),
        "info-distortion-nan": (dict(info=lambda i, t: camera_info(i, t, d=(math.nan,) * 5)), "map", {"scans": 40},
                                [dropped], []),
        "info-unknown-model": (dict(info=lambda i, t: camera_info(i, t, model=b"kannala_brandt_9", d=(0.0,) * 9)),
                               "map", {"scans": 40}, [dropped], []),
        "info-changes-every-message": (dict(info=lambda i, t: camera_info(i, t, fx=8.0 + i)), "map",
                                       {cam + "camera_info_differing": 39}, ["differ from the first"], []),
        "info-missing": (dict(info=None), "error", {}, [], ["/camera/camera_info"]),
        "depth-missing": (dict(dep=None), "error", {}, [], ["/camera/depth"]),
    }
    for what, (stream, expect, summary, notes, names) in cases.items():
        p = tmp / f"camera-{what}.bag"
        write_ros1(p, messages, static, None, raw=camera_stream(scans, **stream))
        extra = {"summary": summary, "notes": notes} if expect == "map" else {}
        sensor_case(f"camera/{what}", p, CAMERA, expect, names=names, **extra)

    # 5,000 frames of 1 x 1 pixel, ten for every scan: each a frame, none a cost.
    times = [scans[0] + k * (scans[-1] - scans[0]) // 5000 for k in range(5000)]
    tiny = [(topic, "sensor_msgs/msg/" + ty, t, make(i, t)) for i, t in enumerate(times)
            for topic, ty, make in (
                ("/camera/camera_info", "CameraInfo", lambda i, t: camera_info(i, t, 1, 1, 1.0, 1.0)),
                ("/camera/labels", "Image", lambda i, t: image(i, t, b"mono8", b"\x02", 1, 1)),
                ("/camera/depth", "Image", lambda i, t: image(i, t, b"32FC1", struct.pack("<f", 2.0), 1, 1)))]
    p = tmp / "camera-tiny.bag"
    write_ros1(p, messages, static, None, raw=tiny)
    sensor_case("camera/5000-frames-of-1x1", p, CAMERA, "map", summary={cam + "frames_used": 5000})

    # Labels and depth 0.05 s apart (the tolerance is 5 ms): no pair is formed, and
    # nothing is paired with a far image.
    shifted = camera_stream(scans, dep=lambda i, t: depth(i, t + 50_000_000))
    shifted = [(topic, ty, t + (50_000_000 if topic == "/camera/depth" else 0), data)
               for topic, ty, t, data in shifted]
    p = tmp / "camera-unpaired.bag"
    write_ros1(p, messages, static, None, raw=shifted)
    sensor_case("camera/depth-50ms-after-labels", p, CAMERA, "map",
                summary={cam + "frames_paired": 0, cam + "labels_unpaired": 40})

    # Frames a minute after the last pose: counted, not placed at the last pose.
    late = camera_stream([t + 60_000_000_000 for t in scans[-5:]])
    p = tmp / "camera-late.bag"
    write_ros1(p, messages, static, None, raw=camera_stream(scans[:-5]) + late)
    sensor_case("camera/frames-after-the-log", p, CAMERA, "map",
                summary={cam + "frames_used": 35, cam + "frames_skipped.after_last_pose": 5})

    # An image budget the images are over: counted frames, not an allocation.
    p = tmp / "camera-budget.bag"
    write_ros1(p, messages, static, None, raw=camera_stream(scans))
    sensor_case("camera/over-image-pixels", p, CAMERA + "\n[limits]\nimage_pixels = 100\n", "error",
                names=["{case}/room.bag", "/camera/labels", "limits.image_pixels"])
    # A camera the config does not list, on the usual topics, with broken intrinsics: the
    # run maps the room without it and says why.
    p = tmp / "camera-auto-broken.bag"
    write_ros1(p, messages, static, None, raw=camera_stream(scans, info=lambda i, t: camera_info(i, t, fx=0.0)))
    sensor_case("camera/found-with-broken-intrinsics", p, "", "map", summary={"scans": 40},
                notes=["camera `camera` is not mapped"])
    # The camera's only frame id has no transform and the config no mount: noted.
    sensor_case("camera/no-mount", p.with_name("camera-budget.bag"), CAMERA, "map",
                notes=["no mount in the config or the log's TF"])


# ---------------------------------------------------------------------------------------
# GNSS.


gnss_fixes: list = []  # the clean fixes, for the config sweep


def gnss_cases(tmp: Path, messages, static: int) -> None:
    odom = [m.log_time for m in messages if m.topic == "/odom"]
    lat0, lon0, alt0 = 48.137, 11.575, 520.0
    deg_per_m = 1.0 / 111_320.0
    gnss = "log.estimator.gnss_input.0."

    def fixes(fault=lambda i: {}, cov=None, stamps=None):
        raw = []
        for i, t in enumerate(odom):
            x, y = 1.0 + 0.05 * i, 2.5 + 0.01 * i
            f = dict(lat=lat0 + y * deg_per_m, lon=lon0 + x * deg_per_m / math.cos(math.radians(lat0)), alt=alt0)
            f.update(fault(i))
            data = nav_sat_fix(i, stamps[i] if stamps else t, **f)
            if cov is not None:
                data = data[:-73] + struct.pack("<9d", *cov(i)) + data[-1:]
            raw.append(("/fix", "sensor_msgs/msg/NavSatFix", stamps[i] if stamps else t, data))
        return raw

    cases = {
        "clean": (dict(), {gnss + "passed": 40}, []),
        "covariance-negative": (dict(cov=lambda i: [-4e-4, 0, 0, 0, -4e-4, 0, 0, 0, -1e-3]), {"scans": 40}, []),
        "covariance-nan": (dict(cov=lambda i: [math.nan] * 9), {"scans": 40}, []),
        "covariance-1e300": (dict(cov=lambda i: [1e300, 0, 0, 0, 1e300, 0, 0, 0, 1e300]), {"scans": 40}, []),
        "covariance-zero": (dict(cov=lambda i: [0.0] * 9), {"scans": 40}, []),
        "latitude-nan": (dict(fault=lambda i: {"lat": math.nan}), {gnss + "passed": 0}, []),
        "longitude-inf": (dict(fault=lambda i: {"lon": math.inf}), {gnss + "passed": 0}, []),
        "altitude-minus-1e6": (dict(fault=lambda i: {"alt": -1e6}), {gnss + "passed": 0}, []),
        "status-no-fix": (dict(fault=lambda i: {"status": -1}), {"scans": 40}, []),
        "status-minus-5": (dict(fault=lambda i: {"status": -5}), {gnss + "passed": 0}, []),
        "first-fix-1000km-off": (dict(fault=lambda i: {"lat": lat0 + 9.0} if i == 0 else {}), {"scans": 40}, []),
        "jump-111m-from-fix-20": (dict(fault=lambda i: {"lat": lat0 + 0.001} if i >= 20 else {}), {"scans": 40}, []),
        "teleport-1000km-from-fix-20": (dict(fault=lambda i: {"lat": lat0 + 9.0} if i >= 20 else {}),
                                        {"scans": 40}, []),
        "every-other-fix-at-the-pole": (dict(fault=lambda i: {"lat": 90.0} if i % 2 else {}), {"scans": 40}, []),
        "stamps-all-equal": (dict(stamps=[odom[0]] * len(odom)), {"scans": 40}, []),
        "stamps-backwards": (dict(stamps=odom[::-1]), {"scans": 40}, []),
        "stamps-1e9-s-late": (dict(stamps=[t + 10**18 for t in odom]), {"scans": 40}, []),
    }
    gnss_fixes[:] = fixes()
    for what, (kw, summary, notes) in cases.items():
        p = tmp / f"gnss-{what}.bag"
        write_ros1(p, messages, static, None, raw=fixes(**kw))
        sensor_case(f"gnss/{what}", p, "", "map", summary=summary, notes=notes)


# ---------------------------------------------------------------------------------------
# IMU.


def imu_message(seq: int, stamp: int, yaw_rate: float = 0.0, q=(0.0, 0.0, 0.0, 1.0), q_cov0: float = -1.0,
                gyro_cov: float = 1e-4) -> bytes:
    """A ROS 1 `sensor_msgs/Imu`; with q_cov0 >= 0 the orientation is given."""
    return (ros1_header(seq, stamp, b"base_link") + struct.pack("<4d", *q)
            + struct.pack("<9d", q_cov0, 0, 0, 0, max(q_cov0, 0), 0, 0, 0, max(q_cov0, 0))
            + struct.pack("<3d", 0, 0, yaw_rate) + struct.pack("<9d", gyro_cov, 0, 0, 0, gyro_cov, 0, 0, 0, gyro_cov)
            + struct.pack("<3d", 0, 0, 9.81) + struct.pack("<9d", *[0] * 9))


def imu_cases(tmp: Path, messages, static: int) -> None:
    odom = [m.log_time for m in messages if m.topic == "/odom"]
    est = "log.estimator.estimator."

    def yaw_q(th: float):
        return (0.0, 0.0, math.sin(th / 2), math.cos(th / 2))

    cases = {
        "clean-rates": lambda i, t: imu(i, t, 0.1),
        "all-rates-1e30": lambda i, t: imu(i, t, 1e30),
        "rate-nan": lambda i, t: imu(i, t, math.nan if i % 3 == 0 else 0.1),
        "rate-inf": lambda i, t: imu(i, t, math.inf if i == 7 else 0.1),
        "orientation-zero-quaternion": lambda i, t: imu_message(i, t, 0.1, q=(0, 0, 0, 0), q_cov0=1e-3),
        "orientation-nan": lambda i, t: imu_message(i, t, 0.1, q=(math.nan,) * 4, q_cov0=1e-3),
        "orientation-1e300": lambda i, t: imu_message(i, t, 0.1, q=(1e300, 0, 0, 1e300), q_cov0=1e-3),
        "orientation-frozen-tiny-covariance": lambda i, t: imu_message(i, t, 0.1, q=yaw_q(0.3), q_cov0=1e-12),
        "orientation-covariance-negative": lambda i, t: imu_message(i, t, 0.1, q=yaw_q(0.01 * i), q_cov0=-5.0),
        "orientation-covariance-nan": lambda i, t: imu_message(i, t, 0.1, q=yaw_q(0.01 * i), q_cov0=math.nan),
        "orientation-spins-90deg-a-message": lambda i, t: imu_message(i, t, 0.1, q=yaw_q(1.5708 * i), q_cov0=1e-3),
        "gyro-covariance-nan": lambda i, t: imu_message(i, t, 0.1, gyro_cov=math.nan),
        "gyro-covariance-1e300": lambda i, t: imu_message(i, t, 0.1, gyro_cov=1e300),
    }
    for what, make in cases.items():
        raw = [("/imu", "sensor_msgs/msg/Imu", t, make(i, t)) for i, t in enumerate(odom)]
        p = tmp / f"imu-{what}.bag"
        write_ros1(p, messages, static, None, raw=raw)
        summary = {"scans": 40}
        if what == "all-rates-1e30":
            summary[est + "gyro.implausible"] = 40
        sensor_case(f"imu/{what}", p, "", "map", summary=summary)
    # An IMU at 10 kHz for the log's 4 s: 40,000 messages, read in a stream.
    t0, t1 = odom[0], odom[-1]
    raw = [("/imu", "sensor_msgs/msg/Imu", t0 + k * 100_000, imu(k, t0 + k * 100_000, 0.1))
           for k in range((t1 - t0) // 100_000)]
    p = tmp / "imu-10khz.bag"
    write_ros1(p, messages, static, None, raw=raw)
    sensor_case("imu/10-khz", p, "", "map", summary={"scans": 40})


# ---------------------------------------------------------------------------------------
# Odometry and scans.


def odometry_cases(tmp: Path, messages, static: int) -> None:
    def odom(change):
        def mutate(t: str, i: int, d: dict) -> list[dict]:
            if t != "/odom":
                return [d]
            d = copy.deepcopy(d)
            change(i, d)
            return [d]
        return mutate

    def pos(d):
        return d["pose"]["pose"]["position"]

    def orient(d):
        return d["pose"]["pose"]["orientation"]

    def set_nan(i, d):
        if i % 5 == 2:
            pos(d)["x"] = math.nan

    def zero_q(i, d):
        orient(d).update(x=0.0, y=0.0, z=0.0, w=0.0)

    def cov_nan(i, d):
        d["pose"]["covariance"] = [math.nan] * 36

    def stamp_equal(i, d):
        d["header"]["stamp"] = {"sec": 1000, "nanosec": 0}

    def spin(i, d):
        pos(d).update(x=1.0, y=2.5)
        orient(d).update(z=math.sin(0.2 * i), w=math.cos(0.2 * i))

    cases = {
        "position-nan-every-fifth": set_nan,
        "quaternion-zero": zero_q,
        "covariance-nan": cov_nan,
        "spins-in-place-while-scans-move": spin,
    }
    for what, change in cases.items():
        p = tmp / f"odom-{what}.bag"
        write_ros1(p, messages, static, None, odom(change))
        sensor_case(f"odometry/{what}", p, "", "either", doctor="any")
    def late(i, d):
        d["header"]["stamp"]["sec"] += 100

    p = tmp / "odom-after-the-scans.bag"
    write_ros1(p, messages, static, None, lambda t, i, d: [d] if t != "/odom" else odom(late)(t, i, d))
    sensor_case("odometry/starts-100s-after-the-last-scan", p, "", "either", doctor="any")
    p = tmp / "odom-stamps-equal.bag"
    write_ros1(p, messages, static, None, odom(stamp_equal))
    sensor_case("odometry/stamps-all-equal", p, "", "either", doctor="any")


def scan_cases(tmp: Path, messages, static: int) -> None:
    def scans(change):
        def mutate(t: str, i: int, d: dict) -> list[dict]:
            if t != "/scan":
                return [d]
            return change(i, copy.deepcopy(d))
        return mutate

    def one_stamp(i, d):
        d["header"]["stamp"] = {"sec": 1000, "nanosec": 0}
        return [d]

    def doubled(i, d):
        other = copy.deepcopy(d)
        other["ranges"] = [r + 0.3 for r in d["ranges"]]
        return [d, other]

    def ranges(value):
        def change(i, d):
            d["ranges"] = [value] * len(d["ranges"])
            return [d]
        return change

    def unknown_frame(i, d):
        d["header"]["frame_id"] = "laser_unmounted"
        return [d]

    def one_beam(i, d):
        d["ranges"] = d["ranges"][:1]
        d["angle_max"] = d["angle_min"]
        return [d]

    def angle_nan(i, d):
        d["angle_increment"] = math.nan
        return [d]

    def frozen(i, d):
        d["ranges"] = list(messages_first_scan[0])
        return [d]

    messages_first_scan = [next(m.body.ranges for m in messages if m.topic == "/scan")]
    cases = {
        "every-scan-at-one-stamp": (one_stamp, "either", {}, []),
        "every-angle-increment-nan": (angle_nan, "either", {}, []),
        "every-scan-frozen-on-the-first": (frozen, "either", {}, []),
        "two-scans-a-stamp-0.3m-apart": (doubled, "map", {}, ["two scans at one"]),
        "all-ranges-max": (ranges(81.91), "either", {}, []),
        "all-ranges-zero": (ranges(0.0), "either", {}, []),
        "all-ranges-nan": (ranges(math.nan), "either", {}, []),
        "all-ranges-inf": (ranges(math.inf), "either", {}, []),
        "frame-without-transform": (unknown_frame, "map", {"scans": 40}, ["no mount in the config or the log"]),
        "one-beam": (one_beam, "either", {}, []),
    }
    for what, (change, expect, summary, notes) in cases.items():
        p = tmp / f"scan-{what}.bag"
        write_ros1(p, messages, static, None, scans(change))
        extra = {"summary": summary, "notes": notes} if expect == "map" else {}
        sensor_case(f"scan/{what}", p, "", expect, doctor="any" if expect != "map" else None, **extra)


# ---------------------------------------------------------------------------------------
# The config sections a world does not exercise, swept over a bag whose run uses them.


def config_sweep(tmp: Path, messages, static: int) -> None:
    """Each numeric key of configs/example.toml's [estimator], [slam] and [log] set to -1
    and to 1e300, run over the room with odometry, GNSS and an IMU (the estimator and
    SLAM both run): a map, or one error naming the file and the key; never a hang, an
    abort, a panic or memory past the limit."""
    odom = [m.log_time for m in messages if m.topic == "/odom"]
    raw = gnss_fixes + [("/imu", "sensor_msgs/msg/Imu", t, imu(i, t, 0.01)) for i, t in enumerate(odom)]
    bag = tmp / "sweep.bag"
    write_ros1(bag, messages, static, None, raw=raw)
    _, lines, numeric = example_numeric_keys()
    seen = set()
    for i, key, section in numeric:
        if section not in BAG_SECTIONS or (section, key) in seen:
            continue
        seen.add((section, key))
        for label, value in (("minus-one", "-1"), ("1e300", "1e300")):
            mutated = list(lines)
            mutated[i] = f"{key} = {value}"
            sensor_case(f"config-on-bag/{label}-{section}-{key}", bag, "\n".join(mutated), "either",
                        names=["{case}/robot.toml", key], doctor="any")
