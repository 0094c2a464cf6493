"""Corpus cases in text formats: CARMEN logs, config and world files, output
directories and command lines."""

from __future__ import annotations

import gzip
import math
import os
import random
import struct
import zlib

from corpus_base import (BAG_SECTIONS, REPO, WORLD, case, carmen_lines, example_numeric_keys, flaser, log_case, odom,
                         text)


# ---------------------------------------------------------------------------------------
# CARMEN logs.


def carmen_cases() -> None:
    base = carmen_lines()
    log_case("carmen/good", "room.log", text(base), "map", summary={"scans": 40})
    log_case("carmen/good-gzip", "room.log.gz", gzip.compress(text(base)), "map", summary={"scans": 40})
    log_case("carmen/crlf-line-ends", "room.log", text(base).replace(b"\n", b"\r\n"), "map", summary={"scans": 40})
    log_case("carmen/comments-and-blank-lines", "room.log",
             text(["# a comment", "", "   ", *base, "PARAM robot_front_laser_max 50"]), "map", summary={"scans": 40})

    k = 2 * 10 + 1  # the FLASER line of scan 10
    ranges180 = " ".join(["2.0"] * 180)
    t = "1001.000000"
    bad_lines = {
        "too-few-fields": "FLASER 180 1.0 2.0 3.0",
        "count-zero": f"FLASER 0 0 0 0 0 0 0 {t} corpus {t}",
        "count-negative": f"FLASER -1 0 0 0 0 0 0 {t} corpus {t}",
        "count-huge": f"FLASER 1000000000 {ranges180} 0 0 0 0 0 0 {t} corpus {t}",
        "count-not-a-number": f"FLASER x {ranges180} 0 0 0 0 0 0 {t} corpus {t}",
        "count-float": f"FLASER 180.5 {ranges180} 0 0 0 0 0 0 {t} corpus {t}",
        "range-word": base[k].replace(" 1.", " one.", 1) if " 1." in base[k] else "FLASER 2 a b 0 0 0 0 0 0 1 h 1",
        "pose-nan": f"FLASER 180 {ranges180} nan 0 0 nan 0 0 {t} corpus {t}",
        "pose-inf": f"FLASER 180 {ranges180} inf 0 0 inf 0 0 {t} corpus {t}",
        "stamp-nan": f"FLASER 180 {ranges180} 1.5 2.6 0.1 1.5 2.6 0.1 nan corpus nan",
        "stamp-inf": f"FLASER 180 {ranges180} 1.5 2.6 0.1 1.5 2.6 0.1 inf corpus inf",
        "stamp-1e300": f"FLASER 180 {ranges180} 1.5 2.6 0.1 1.5 2.6 0.1 1e300 corpus 1e300",
        "stamp-negative": f"FLASER 180 {ranges180} 1.5 2.6 0.1 1.5 2.6 0.1 -5 corpus -5",
        "escape-sequence-token": f"FLASER 3 1.0 \x1b]0;pwned\x07\x1b[2J 2.0 0 0 0 0 0 0 {t} corpus {t}",
        "nul-bytes": f"FLASER 3 1.0 \x00 2.0 0 0 0 0 0 0 {t} corpus {t}",
        "unknown-message": "NOSUCHMESSAGE 1 2 3",
        "odom-too-few-fields": "ODOM 1 2",
        "odom-nan": f"ODOM nan nan nan 0 0 0 {t} corpus {t}",
        "robotlaser-too-few": "ROBOTLASER1 0 -1.57 3.14 0.0175 81.9 0.01 0 180",
        "one-megabyte-token": "FLASER 1 " + "9" * (1 << 20) + f" 0 0 0 0 0 0 {t} corpus {t}",
    }
    for what, line in bad_lines.items():
        lines = list(base)
        lines.insert(k, line)
        # A stamp far before the rest on a line with a good pose is a scan like any other.
        summary = {} if what == "stamp-negative" else {"scans": 40}
        log_case(f"carmen/line-{what}", "room.log", text(lines), "map", summary=summary)

    # Ranges that are not obstacles: NaN, inf, 0, negative (never become an obstacle).
    for what, value in {"nan": "nan", "inf": "inf", "zero": "0", "negative": "-1.0"}.items():
        lines = list(base)
        fields = lines[k].split(" ")
        for j in range(2, 182, 2):
            fields[j] = value
        lines[k] = " ".join(fields)
        log_case(f"carmen/ranges-{what}", "room.log", text(lines), "map", summary={"scans": 40})

    lines = list(base)
    lines[k] = flaser(10, dx=1e8)
    glitch = {"summary": {"scans": 40}, "notes": ["1 pose sample(s) rejected as glitches"]}
    log_case("carmen/pose-glitch-1e8m", "room.log", text(lines), "map", **glitch)
    lines = list(base)
    lines[k] = flaser(10, dx=1e3)
    log_case("carmen/pose-glitch-1km", "room.log", text(lines), "map", **glitch)
    lines = list(base)
    lines.insert(k, base[k])
    log_case("carmen/line-written-twice", "room.log", text(lines), "map", summary={"scans": 40})
    lines = list(base)
    lines[k], lines[k + 2] = lines[k + 2], lines[k]
    log_case("carmen/lines-out-of-order", "room.log", text(lines), "map")
    lines = list(base)
    late = base[k].rsplit(" ", 3)
    lines[k] = f"{late[0]} {18429000000.0:.6f} corpus {18429000000.0:.6f}"  # 584 years on
    log_case("carmen/stamp-584-years-on", "room.log", text(lines), "map")
    log_case("carmen/no-return-everywhere", "empty.log",
             text([f"FLASER 4 81.91 81.91 81.91 81.91 0 0 0 0 0 0 {1 + i / 10} h {1 + i / 10}" for i in range(5)]),
             "no_map", names=["no map was written"])
    log_case("carmen/only-odometry", "odom.log", text([odom(i) for i in range(20)]), "error", names=["scan"])
    log_case("carmen/only-comments", "c.log", b"# nothing here\n# at all\n", "error")
    log_case("carmen/empty", "empty.log", b"", "error", names=["empty"])
    log_case("carmen/not-utf8", "room.log", text(base[:30]) + b"\xff\xfe\xfd garbage \xc0\n" + text(base[30:]), "map")
    log_case("carmen/no-final-newline", "room.log", text(base)[:-1], "map", summary={"scans": 40})
    log_case("carmen/one-robot-that-never-moves", "still.log",
             text([flaser(0).replace(f"{1000.0:.6f}", f"{1000.0 + i:.6f}") for i in range(20)]), "map")

    data = gzip.compress(text(base))
    for frac in (0.1, 0.5, 0.9):
        cut = int(len(data) * frac)
        log_case(f"carmen/gzip-cut-at-{int(frac * 100)}pct", "room.log.gz", data[:cut], "either")
    log_case("carmen/gzip-trailing-garbage", "room.log.gz", data + b"garbage after the stream", "either")
    log_case("carmen/gzip-corrupt-body", "room.log.gz", data[:40] + bytes(64) + data[104:], "either")
    log_case("carmen/gzip-header-only", "room.log.gz", data[:10], "error")

    # A gzipped log of one 16 GiB line: 16384 copies of one deflate block holding 1 MiB of
    # 'a' (a full flush makes each block stand alone), never a 16 GiB buffer here.
    comp = zlib.compressobj(9, zlib.DEFLATED, -15)
    start = comp.compress(b"FLASER 180 ") + comp.flush(zlib.Z_FULL_FLUSH)
    block = comp.compress(b"a" * (1 << 20)) + comp.flush(zlib.Z_FULL_FLUSH)
    tail = comp.flush(zlib.Z_FINISH)
    header = b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff"
    bomb = header + start + block * 16384 + tail + struct.pack("<II", 0, 0)
    log_case("carmen/gzip-bomb-16gib-line", "bomb.log.gz", bomb, "error", names=["decompressed_mib"])
    # The same, with a newline each MiB: 16 GiB of (invalid) lines, stopped by the
    # malformed-line budget of a lenient reader or read through in bounded memory.
    comp = zlib.compressobj(9, zlib.DEFLATED, -15)
    block = comp.compress(b"FLASER " + b"a" * ((1 << 20) - 8) + b"\n") + comp.flush(zlib.Z_FULL_FLUSH)
    tail = comp.flush(zlib.Z_FINISH)
    many = header + block * 64 + tail + struct.pack("<II", 0, 0)
    log_case("carmen/gzip-64-one-mib-garbage-lines", "lines.log.gz", many, "error")

    # Limits from the config: a line over `decompressed_mib`.
    d = case("carmen/line-over-decompressed-limit",
             ["map", "--config", "{case}/limits.toml", "--out", "{case}/out", "{case}/long.log"],
             "error", names=["{case}/long.log", "decompressed_mib"])
    (d / "limits.toml").write_text("[limits]\ndecompressed_mib = 1\n")
    (d / "long.log").write_bytes(text(base[:10]) + b"FLASER " + b"1.0 " * 300_000 + b"\n")

    # Limits from the config: a scan over `beams_per_scan` (the lines before it map, but the
    # read stops there with the key named).
    d = case("carmen/scan-over-beam-limit",
             ["map", "--config", "{case}/limits.toml", "--out", "{case}/out", "{case}/wide.log"],
             "error", names=["{case}/wide.log", ":14:", "181 beams", "limits.beams_per_scan"])
    (d / "limits.toml").write_text("[limits]\nbeams_per_scan = 180\n")
    (d / "wide.log").write_bytes(text(base[:13]) + text([base[13].replace("FLASER 180 ", "FLASER 181 3.0 ", 1)]))

    # A lidar of 10,000 beams is fine.
    wide = " ".join(["3.0"] * 10000)
    log_case("carmen/ten-thousand-beams", "wide.log",
             text([f"FLASER 10000 {wide} {0.01 * i} 0 0 {0.01 * i} 0 0 {1 + i / 10} h {1 + i / 10}" for i in range(5)]),
             "map")


# ---------------------------------------------------------------------------------------
# Config files, through `fusemap map --world worlds/corridor.toml --config`.



def config_case(name: str, body: str, expect: str = "error", names=(), names_config=True, **extra) -> None:
    args = ["map", "--config", "{case}/robot.toml", "--world", WORLD, "--out", "{case}/out"]
    names = ["{case}/robot.toml", *names] if expect == "error" and names_config else list(names)
    d = case(name, args, expect, names=names, **extra)
    (d / "robot.toml").write_text(body)


def config_cases() -> None:
    example, lines, numeric = example_numeric_keys()
    config_case("config/example-as-shipped", example, "map")
    seen = set()
    for i, key, section in numeric:
        name = f"config/nan-{section.replace('.', '-')}-{key}"
        if name in seen:
            continue
        seen.add(name)
        mutated = list(lines)
        mutated[i] = f"{key} = nan"
        config_case(name, "\n".join(mutated), names=[f"{{case}}/robot.toml:{i + 1}:"])
        # Values past any sensible range, each side: a map, or an error naming the file
        # and the key, never a hang or an abort. (The sections a world does not exercise
        # are swept over a bag: corpus_sensors.config_sweep.)
        if section.split(".")[0] in BAG_SECTIONS:
            continue
        for label, value in (("minus-one", "-1"), ("1e300", "1e300")):
            mutated[i] = f"{key} = {value}"
            config_case(name.replace("/nan-", f"/{label}-"), "\n".join(mutated), "either",
                        names=["{case}/robot.toml", key])

    config_case("config/toml-syntax", "[map\nresolution = 0.05\n", names=[":1:"])
    config_case("config/unknown-section", "[mapp]\nresolution = 0.05\n", names=[":1:", "mapp"])
    config_case("config/unknown-key", "[map]\nresolutoin = 0.05\n", names=[":2:", "resolutoin"])
    config_case("config/string-for-number", "[map]\nresolution = \"fine\"\n", names=[":2:"])
    config_case("config/resolution-zero", "[map]\nresolution = 0.0\n", names=["resolution"])
    config_case("config/resolution-negative", "[map]\nresolution = -0.05\n", names=["resolution"])
    config_case("config/resolution-1e-4", "[map]\nresolution = 1e-4\n", names=["ray_cells"], max_seconds=1.0)
    config_case("config/resolution-1e-5", "[map]\nresolution = 1e-5\n", names=["ray_cells"], max_seconds=1.0)
    config_case("config/resolution-1e-9", "[map]\nresolution = 1e-9\n", names=["ray_cells"])
    config_case("config/resolution-inf", "[map]\nresolution = inf\n", names=["resolution"])
    config_case("config/origin-1e15", "[map]\norigin = [1e15, 0.0]\n", names=["map.origin", "within"])
    config_case("config/origin-1e9", "[map]\norigin = [1e9, 1e9]\n", "map")
    config_case("config/prior-one", "[map]\nprior = 1.0\n", names=["prior"])
    config_case("config/clamps-crossed", "[map]\nclamp_min = 0.9\nclamp_max = 0.1\n", names=["clamp"])
    config_case("config/max-range-1e12",
                "[[sensor]]\nkind = \"lidar\"\nmax_range = 1e12\n", names=["ray_cells"])
    config_case("config/min-above-max-range",
                "[[sensor]]\nkind = \"lidar\"\nmin_range = 9.0\nmax_range = 2.0\n", names=["min_range"])
    config_case("config/p-occ-above-one", "[[sensor]]\nkind = \"lidar\"\np_occ = 1.5\n", names=["p_occ"])
    config_case("config/sensor-kind-unknown", "[[sensor]]\nkind = \"sonar\"\n", names=["sonar"])
    config_case("config/limits-zero-map-cells", "[limits]\nmap_cells = 0\n", names=["map_cells"])
    config_case("config/limits-negative", "[limits]\nray_cells = -1\n", names=[":2:"])
    # The map outgrows the budget while the world is mapped: the error names the world.
    config_case("config/limits-tiny-map-cells", "[limits]\nmap_cells = 4096\n", names=[WORLD, "limits.map_cells"],
                names_config=False)
    config_case("config/limits-zero-memory", "[limits]\nmemory_mib = 0\n", names=["memory_mib"])
    # The corridor at 1 mm needs 66 MB of tiles (it maps in 215 MB): past a 64 MiB budget,
    # refused naming it.
    config_case("config/limits-1mm-past-memory", "[map]\nresolution = 0.001\n[limits]\nmemory_mib = 64\n",
                names=[WORLD, "limits.memory_mib = 64 MiB"], names_config=False)
    config_case("config/limits-tiny-export",
                "[limits]\nexport_cells = 1\n", "map", notes=["sparse"])
    config_case("config/max-speed-zero", "[log]\nmax_speed_m_s = 0.0\n", names=["max_speed_m_s"])
    config_case("config/slam-window-costly",
                "[slam]\nresolution_m = 0.005\nsearch_linear_window_m = 5.0\nsearch_angular_window_deg = 180.0\n",
                names=["search_linear_window_m", "candidate poses a scan"], max_seconds=1.0)
    config_case("config/slam-window-negative", "[slam]\nsearch_linear_window_m = -1.0\n",
                names=["search_linear_window_m"])
    config_case("config/integer-overflow", "[slam]\nscans_per_submap = 99999999999999999999\n", names=[":2:"])
    config_case("config/duplicate-key", "[map]\nresolution = 0.05\nresolution = 0.1\n", names=[":3:"])
    config_case("config/lidar-mount-1e300", '[[sensor]]\nkind = "lidar"\n[sensor.base_from_sensor]\nx = 1e300\n',
                names=[":4:", "base_from_sensor.x", "1000 m"])
    # A mount far from everything the lidar could see: no cell observed, no map, exit 1.
    d = case("demo/corridor-lidar-900m-away", ["demo", "--corridor", "--config", "{case}/robot.toml", "--out",
                                               "{case}/out"], "no_map", names=["no map was written"])
    (d / "robot.toml").write_text('[[sensor]]\nkind = "lidar"\n[sensor.base_from_sensor]\nx = 900.0\n')
    gnss = '[[sensor]]\nkind = "gnss"\ntopic = "/fix"\n'
    config_case("config/1001-gnss-sensors-on-one-topic", gnss * 1001, names=[":6:", "sensor[1].topic", "per topic"])
    config_case("config/not-utf8-bytes", "[map]\nresolution = 0.05\n# \udcff\n".encode("utf-8", "surrogateescape")
                .decode("latin-1"), "either")
    config_case("config/empty", "", "map")
    d = case("config/binary-garbage", ["map", "--config", "{case}/robot.toml", "--world", WORLD, "--out",
                                       "{case}/out"], "error", names=["{case}/robot.toml"])
    (d / "robot.toml").write_bytes(bytes(random.Random(7).randrange(256) for _ in range(2048)))
    d = case("config/sparse-2gib", ["map", "--config", "{case}/big.toml", "--world", WORLD, "--out", "{case}/out"],
             "error", names=["{case}/big.toml", "larger than 4 MiB"], max_seconds=1.0)
    with open(d / "big.toml", "wb") as f:
        f.truncate(2 << 30)  # sparse: no disk used
    d = case("config/a-directory", ["map", "--config", "{case}/dir", "--world", WORLD, "--out", "{case}/out"],
             "error", names=["{case}/dir"])
    (d / "dir").mkdir()
    case("config/missing", ["map", "--config", "{case}/none.toml", "--world", WORLD, "--out", "{case}/out"],
         "error", names=["{case}/none.toml"])
    d = case("config/fifo", ["map", "--config", "{case}/pipe", "--world", WORLD, "--out", "{case}/out"],
             "error", names=["{case}/pipe", "FIFO"])
    os.mkfifo(d / "pipe")
    case("config/char-device", ["map", "--config", "/dev/zero", "--world", WORLD, "--out", "{case}/out"],
         "error", names=["/dev/zero"])


# ---------------------------------------------------------------------------------------
# World files (`fusemap map --world`).


def world_case(name: str, body: str, expect: str = "error", names=(), **extra) -> None:
    names = ["{case}/world.toml", *names] if expect == "error" else list(names)
    d = case(name, ["map", "--world", "{case}/world.toml", "--out", "{case}/out"], expect, names=names, **extra)
    (d / "world.toml").write_text(body)


def world_cases() -> None:
    corridor = (REPO / "worlds" / "corridor.toml").read_text()
    world_case("world/corridor-as-shipped", corridor, "map")
    world_case("world/toml-syntax", corridor + "\n= = =\n", names=[":"])
    world_case("world/empty", "", names=[])
    world_case("world/unknown-key", corridor + "\nbogus_key = 1\n", names=["bogus_key"])
    world_case("world/nan-everywhere", corridor.replace("0.0", "nan"), names=["nan"])
    world_case("world/inf-coordinate", corridor.replace("0.0", "inf", 1), names=[])
    world_case("world/binary", "\x00\x01\x02\x03" * 100, names=[])
    world_case("world/huge-numbers", corridor.replace("0.0", "1e300"), "no_map", names=["no map was written"])
    world_case("world/not-a-world", "[map]\nresolution = 0.05\n", names=[])
    lines = corridor.split("\n")
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("#") or "=" not in s or s.startswith("["):
            continue
        key, value = (p.strip() for p in s.split("=", 1))
        try:
            float(value.split("#")[0])
        except ValueError:
            continue
        mutated = list(lines)
        mutated[i] = f"{key} = nan"
        world_case(f"world/nan-{key}-line-{i + 1}", "\n".join(mutated), names=[f":{i + 1}:"])
        mutated[i] = f"{key} = \"text\""
        world_case(f"world/string-{key}-line-{i + 1}", "\n".join(mutated), names=[f":{i + 1}:"])
    head = corridor[:corridor.index("[trajectory]")]
    for what, far in {"2km": "2000.0", "1e8m": "1e8"}.items():
        poses = [f"[{far}, 0.0, 0.0]" if i == 17 else f"[{0.1 * i:.1f}, 0.0, 0.0]" for i in range(40)]
        world_case(f"world/one-pose-{what}-off", f"{head}[trajectory]\nposes = [{', '.join(poses)}]\n", "map",
                   notes=["1 pose sample(s) rejected as glitches"])
    for key, value in {"world_poses": 10, "beams_per_scan": 100}.items():
        d = case(f"world/over-limits-{key}",
                 ["map", "--config", "{case}/limits.toml", "--world", "{case}/world.toml", "--out", "{case}/out"],
                 "error", names=["{case}/world.toml", f"limits.{key}"])
        (d / "limits.toml").write_text(f"[limits]\n{key} = {value}\n")
        (d / "world.toml").write_text(corridor)
    # Within world_poses and beams_per_scan, yet minutes or hours of ray casting: refused.
    d = case("world/ten-million-poses", ["map", "--world", "{case}/world.toml", "--out", "{case}/out"], "error",
             names=["{case}/world.toml", "trajectory.count", "more than the 2e7"], max_seconds=2.0)
    (d / "world.toml").write_text(corridor.replace("count = 40", "count = 10000000"))
    walls = "".join(f"[[wall]]\nfrom = [{0.1 * (k % 300):.1f}, {0.1 * (k // 300):.1f}]\nto = [{0.1 * (k % 300) + 0.05:.2f}, "
                    f"{0.1 * (k // 300):.1f}]\n" for k in range(80000))
    d = case("world/eighty-thousand-walls", ["map", "--world", "{case}/world.toml", "--out", "{case}/out"], "error",
             names=["{case}/world.toml", "80003 walls", "beam-wall tests"], max_seconds=5.0)
    (d / "world.toml").write_text(corridor.replace("count = 40", "count = 1000") + walls)
    d = case("world/fifo", ["map", "--world", "{case}/pipe", "--out", "{case}/out"], "error",
             names=["{case}/pipe", "FIFO"])
    os.mkfifo(d / "pipe")
    case("world/missing", ["map", "--world", "{case}/none.toml", "--out", "{case}/out"], "error",
         names=["{case}/none.toml"])
    # Files read whole are refused past 4 MiB before they are read.
    d = case("world/sparse-2gib", ["map", "--world", "{case}/big.toml", "--out", "{case}/out"], "error",
             names=["{case}/big.toml", "larger than 4 MiB"], max_seconds=1.0)
    with open(d / "big.toml", "wb") as f:
        f.truncate(2 << 30)  # sparse: no disk used
    d = case("simulate/truth-resolution-1e-9", ["simulate", "{case}/short.toml", "--resolution", "1e-9", "--out",
                                                "{case}/out"], "error", names=["truth.yaml", "no true map at resolution", "coarser"])
    (d / "short.toml").write_text("[robot]\nduration_s = 1.0\n[camera]\nenabled = false\n")
    d = case("simulate/waypoints-1e7-m-apart", ["simulate", "{case}/far.toml", "--out", "{case}/out"], "error",
             names=["{case}/far.toml", "robot.waypoints", "more than the 1e5 m"], max_seconds=2.0)
    (d / "far.toml").write_text("[robot]\nduration_s = 1.0\nwaypoints = [[0.0, 0.0], [1e7, 0.0], [1e7, 1e7]]\n"
                                "[camera]\nenabled = false\n")
    d = case("simulate/scenario-sparse-2gib", ["simulate", "{case}/big.toml", "--out", "{case}/out"],
             "error", names=["{case}/big.toml", "larger than 4 MiB"], max_seconds=1.0)
    with open(d / "big.toml", "wb") as f:
        f.truncate(2 << 30)


# Every numeric key of a scenario file: `simulate` writes its bag, or refuses with one
# error naming the file and the key; never a hang, an abort or memory past the limit.
SCENARIO_KEYS = {
    "world": ["seed", "start_time_s"],
    "robot": ["max_speed_mps", "max_turn_rate_radps", "duration_s", "corner_radius_m", "lookahead_m"],
    "lidar": ["rate_hz", "beams", "fov_deg", "range_min_m", "range_max_m", "sweep_time_s", "range_noise_std_m",
              "glass_pass_probability", "steel_flying_probability", "edge_mixed_probability", "edge_jump_m",
              "dropout_probability", "time_offset_s"],
    "odometry": ["rate_hz", "wheel_separation_m", "scale_error", "slip_factor_left", "slip_factor_right",
                 "wheel_noise_std_mps", "time_offset_s"],
    "imu": ["rate_hz", "gyro_bias_radps", "gyro_noise_std_radps", "time_offset_s"],
    "gnss": ["rate_hz", "datum_lat_deg", "datum_lon_deg", "datum_alt_m", "good_sigma_m", "degraded_sigma_m",
             "degraded_tau_s", "outlier_probability", "outlier_min_m", "outlier_max_m", "time_offset_s"],
    "camera": ["rate_hz", "width", "height", "hfov_deg", "time_offset_s", "max_depth_m", "depth_sigma_k",
               "label_noise_probability", "glass_depth_probability"],
    "person": ["speed_mps", "radius_m", "height_m"],
}


def simulate_sweep() -> None:
    for section, keys in SCENARIO_KEYS.items():
        for key in keys:
            for label, value in (("minus-one", "-1"), ("zero", "0"), ("1e300", "1e300")):
                d = case(f"simulate/{label}-{section}-{key}", ["simulate", "{case}/s.toml", "--out", "{case}/out"],
                         "either", names=["{case}/s.toml", key], max_seconds=10.0, writes="bag")
                camera = "" if section == "camera" else "[camera]\nenabled = false\n"
                head = "" if section == "robot" else "[robot]\nduration_s = 1.0\n"
                body = f"{head}{camera}[{section}]\n{key} = {value}\n"
                if section == "robot" and key != "duration_s":
                    body = f"[robot]\nduration_s = 1.0\n{key} = {value}\n[camera]\nenabled = false\n"
                (d / "s.toml").write_text(body)


# ---------------------------------------------------------------------------------------
# Output directories and command lines.


def output_cases() -> None:
    good = text(carmen_lines())

    def with_log(name, args, expect, **extra):
        d = case(name, args, expect, **extra)
        (d / "room.log").write_bytes(good)
        return d

    d = with_log("output/out-is-a-file", ["map", "--out", "{case}/out", "{case}/room.log"], "error",
                 names=["{case}/out"])
    (d / "out").write_text("a file\n")
    d = with_log("output/out-below-a-file", ["map", "--out", "{case}/file/out", "{case}/room.log"], "error",
                 names=["{case}/file"])
    (d / "file").write_text("a file\n")
    d = with_log("output/stale-staging-is-cleaned", ["map", "--out", "{case}/out", "{case}/room.log"], "map",
                 absent=["out/.fusemap-staging-99999999"])
    (d / "out" / ".fusemap-staging-99999999").mkdir(parents=True)
    (d / "out" / ".fusemap-staging-99999999" / "map.pgm").write_text("half-written")
    d = with_log("output/map-png-is-a-directory", ["map", "--out", "{case}/out", "{case}/room.log"], "error",
                 names=["{case}/out/map.png", "is a directory"])
    (d / "out" / "map.png").mkdir(parents=True)
    (d / "out" / "summary.json").write_text("{}\n")
    with_log("output/locked-by-another-run", ["map", "--out", "{case}/out", "{case}/room.log"], "error",
             names=[".fusemap.lock"], setup="lock")
    with_log("output/disk-full-keeps-old-set", ["map", "--out", "{case}/out", "{case}/room.log"], "error",
             names=["File too large"], setup="fsize", keeps_old_set=True)
    d = case("output/no-map-after-good-run", ["map", "--out", "{case}/out", "{case}/empty.log"], "no_map",
             names=["no map was written"], setup="good_run_first")
    (d / "empty.log").write_bytes(text([f"FLASER 4 81.91 81.91 81.91 81.91 0 0 0 0 0 0 {1 + i} h {1 + i}"
                                        for i in range(3)]))
    for what, crop in {"three-numbers": "0,0,1", "nan": "nan,0,1,1", "inverted": "5,5,1,1",
                       "words": "a,b,c,d"}.items():
        with_log(f"output/crop-{what}", ["map", "--crop", crop, "--out", "{case}/out", "{case}/room.log"],
                 "usage", names=["--crop"])
    # Past limits.export_cells: refused before the run, by the budget the config sets.
    with_log("output/crop-over-budget", ["map", "--crop", "-1e6,-1e6,1e6,1e6", "--out", "{case}/out",
                                         "{case}/room.log"], "error", names=["--crop", "limits.export_cells"])
    with_log("output/crop-outside-the-map", ["map", "--crop", "100,100,101,101", "--out", "{case}/out",
                                             "{case}/room.log"], "either")
    # `[output] points = "endpoints"` keeps every return until the clouds are written:
    # 1,500 scans along a corridor (its first 5 m over and over) keep about 285,000 (23 MB
    # at 80 bytes), past an 8 MiB budget the maps alone fit in: refused naming the key, no
    # map written.
    d = case("output/endpoints-past-memory", ["map", "--config", "{case}/c.toml", "--out", "{case}/out",
                                              "{case}/corridor.log"], "error",
             names=["{case}/corridor.log", "limits.memory_mib = 8 MiB", "points = \"endpoints\""])
    (d / "c.toml").write_text("[output]\npoints = \"endpoints\"\n\n[limits]\nmemory_mib = 8\n")
    corridor = []
    for i in range(1500):
        ranges = " ".join(f"{min(1.0 / max(abs(math.sin(math.radians(k * 0.5 - 90))), 1e-9), 8.0) + 0.001 * ((i + k) % 5):.3f}"
                          for k in range(360))
        x, t = 0.05 * (i % 100), 1.0 + 0.1 * i
        corridor.append(f"FLASER 360 {ranges} {x:.2f} 0 0 {x:.2f} 0 0 {t:.3f} host {t:.3f}")
    (d / "corridor.log").write_bytes(text(corridor))
    case("cli/bench-max-scans-overflow", ["bench", "--scanfile", "{case}/none", "--max-scans",
                                          "9223372036854775807"], "error", names=["max-scans"])
    d = case("cli/log-is-a-fifo", ["map", "--out", "{case}/out", "{case}/pipe"], "error", names=["{case}/pipe", "FIFO"],
             doctor_args=["doctor", "{case}/pipe"], doctor="fail")
    os.mkfifo(d / "pipe")
    case("cli/log-is-a-char-device", ["map", "--out", "{case}/out", "/dev/zero"], "error", names=["/dev/zero"])
    case("cli/log-and-world", ["map", "--world", WORLD, "--out", "{case}/out", "/dev/null"], "error", names=[])
    case("cli/neither-log-nor-world", ["map", "--out", "{case}/out"], "error", names=[])
