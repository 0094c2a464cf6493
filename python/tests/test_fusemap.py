"""The Python package against the CLI: the same maps, bit for bit, and the same errors.

The CLI binary is $FUSEMAP_BIN, else the repository's target/debug or target/release
build (scripts/test sets it). Without a binary the comparisons skip, and fail under
FUSEMAP_NO_SKIP=1 as the Rust tests do.
"""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import fusemap

REPO = Path(__file__).resolve().parents[2]


def fusemap_bin():
    candidates = [os.environ.get("FUSEMAP_BIN")] + [str(REPO / "target" / p / "fusemap") for p in ("debug", "release")]
    for c in candidates:
        if c and Path(c).is_file():
            return c
    message = "no fusemap binary ($FUSEMAP_BIN, target/debug, target/release)"
    if os.environ.get("FUSEMAP_NO_SKIP") == "1":
        pytest.fail(message)
    pytest.skip(message)


def cli(*args):
    """Runs the CLI; (exit code, stderr's error line without `error: `)."""
    o = subprocess.run([fusemap_bin(), *map(str, args)], capture_output=True, text=True)
    return o.returncode, o.stderr.strip().removeprefix("error: ")


def assert_same_map(arrays, npz_path):
    z = np.load(npz_path)
    for key in ("occupancy", "log_odds", "known"):
        got, want = np.asarray(arrays[key]), z[key]
        assert got.shape == want.shape and got.dtype == want.dtype, (key, got.shape, want.shape, got.dtype)
        # Bit for bit: the float32 payloads compared as integers.
        assert np.array_equal(got.view(np.uint8), want.view(np.uint8)), key
    assert float(arrays["resolution"]) == float(z["resolution"])
    assert tuple(arrays["origin"]) == tuple(z["origin"])


def test_grid_over_the_corridor_is_the_demo_map(tmp_path):
    grid = fusemap.Grid()
    scans = fusemap.corridor_scans()
    assert len(scans) == 40
    for ranges, angle_min, angle_increment, pose, stamp in scans:
        grid.insert_scan(ranges, angle_min, angle_increment, pose, stamp)
    code, err = cli("demo", "--corridor", "--out", tmp_path / "demo")
    assert code == 0, err
    assert_same_map(grid.arrays(), tmp_path / "demo" / "map.npz")
    grid.to_npz(tmp_path / "grid.npz")
    assert_same_map(dict(np.load(tmp_path / "grid.npz")), tmp_path / "demo" / "map.npz")


def test_map_log_on_the_production_line_is_the_cli_map(tmp_path):
    code, err = cli("simulate", "--out", tmp_path / "pl")
    assert code == 0, err
    config = REPO / "configs" / "production_line.toml"
    code, err = cli("map", "--config", config, "--out", tmp_path / "out", tmp_path / "pl" / "bag")
    assert code == 0, err
    m = fusemap.map_log(tmp_path / "pl" / "bag", config=config)
    assert_same_map(m.__dict__, tmp_path / "out" / "map.npz")
    z = np.load(tmp_path / "out" / "map.npz")
    assert np.array_equal(m.semantic_class, z["semantic_class"])
    assert list(m.semantic_class_names) == [str(n) for n in z["semantic_class_names"]]
    assert np.array_equal(m.dynamic.view(np.uint8), z["dynamic"].view(np.uint8))
    tum = np.loadtxt(tmp_path / "out" / "trajectory.tum")
    assert m.trajectory.shape == tum.shape
    # trajectory.tum prints 9 decimals of seconds and metres.
    assert np.allclose(m.trajectory, tum, atol=1e-6, rtol=0)
    assert m.summary["format"] == "rosbag2"
    assert m.summary["log"]["scans_used"] == 1800
    # The same config given as TOML text plans the same map (Grid reads it the same way
    # map_log does; a second map_log would double the test's time).
    text_grid = fusemap.Grid(config=config.read_text())
    path_grid = fusemap.Grid(config=str(config))
    for ranges, angle_min, angle_increment, pose, stamp in fusemap.corridor_scans()[:5]:
        text_grid.insert_scan(ranges, angle_min, angle_increment, pose, stamp)
        path_grid.insert_scan(ranges, angle_min, angle_increment, pose, stamp)
    assert np.array_equal(text_grid.occupancy().view(np.uint8), path_grid.occupancy().view(np.uint8))


def test_a_missing_log_is_an_os_error_with_the_cli_message(tmp_path):
    missing = tmp_path / "missing.log"
    code, err = cli("map", "--out", tmp_path / "out", missing)
    assert code != 0
    with pytest.raises(OSError) as e:
        fusemap.map_log(missing)
    assert str(e.value) == err
    assert e.value.stage is None


def test_a_bad_config_is_a_value_error_with_the_cli_message(tmp_path):
    config = tmp_path / "bad.toml"
    config.write_text("[map]\nresolution = -1\n")
    log = tmp_path / "one.log"
    log.write_text("FLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 1.0 host 1.0\n")
    code, err = cli("map", "--config", config, "--out", tmp_path / "out", log)
    assert code != 0
    with pytest.raises(ValueError) as e:
        fusemap.map_log(log, config=config)
    assert str(e.value) == err
    assert e.value.stage is None, "a bad config is no run's refusal"
    with pytest.raises(ValueError, match="map.resolution"):
        fusemap.Grid(config="[map]\nresolution = -1\n")
    with pytest.raises(ValueError, match="map.resolution"):
        fusemap.Grid(resolution=-1.0)
    with pytest.raises(OSError, match="missing=.toml"):
        fusemap.Grid(config=str(tmp_path / "missing=.toml"))


def test_points_mark_their_cells_and_clear_the_way():
    grid = fusemap.Grid(resolution=0.1)
    wall = np.stack([np.full(21, 2.0), np.linspace(-1.0, 1.0, 21)], axis=1)
    for k in range(5):
        grid.insert_points(wall, (0.0, 0.0, 0.0), 0.1 * k)
    a = grid.arrays()
    occ, res, (ox, oy) = a["occupancy"], a["resolution"], a["origin"]

    def at(x, y):
        return occ[int((y - oy) / res), int((x - ox) / res)]

    assert at(2.05, 0.05) > 0.9
    assert at(1.0, 0.05) < 0.2
    with pytest.raises(ValueError, match="finite"):
        grid.insert_points(np.array([[np.nan, 0.0]]), (0.0, 0.0, 0.0), 1.0)
    with pytest.raises(ValueError, match="N x 2"):
        grid.insert_points(np.zeros((4, 3)), (0.0, 0.0, 0.0), 1.0)


def test_an_empty_grid_says_so():
    with pytest.raises(ValueError, match="no cell was observed"):
        fusemap.Grid().occupancy()


def test_mapping_releases_the_gil():
    """Another Python thread runs while a Grid maps: the Rust work runs without the GIL.

    One insert_points call of 200,000 points 15 m away (each clears its ray to the lidar's
    10 m maximum range: about 40 million cell visits) in a worker thread; the main thread stamps the clock in a loop meanwhile. Holding the GIL,
    the call would stop the loop for its whole length; released, the loop runs through it.
    """
    import threading
    import time

    grid = fusemap.Grid(resolution=0.05)
    angles = np.linspace(-np.pi, np.pi, 200_000, endpoint=False)
    points = np.stack([15.0 * np.cos(angles), 15.0 * np.sin(angles)], axis=1)
    window = []

    def work():
        t0 = time.perf_counter()
        grid.insert_points(points, (0.0, 0.0, 0.0), 0.0)
        window.extend([t0, time.perf_counter()])

    ticks = []
    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    t0, t1 = window
    assert t1 - t0 > 0.02, f"the call took {t1 - t0:.3f} s, too short to tell"
    quarter = 0.25 * (t1 - t0)
    middle = [t for t in ticks if t0 + quarter < t < t1 - quarter]
    assert len(middle) > 100, f"{len(middle)} loop turns in the middle half of a {t1 - t0:.3f} s call"
    assert grid.occupancy().shape[0] == 401  # 20 m across at 5 cm


def test_a_refused_run_names_the_stage_that_refused_it(tmp_path):
    log = tmp_path / "odometry-only.log"
    log.write_text("ODOM 0 0 0 0 0 0 1.0 host 1.0\nODOM 0.1 0 0 0 0 0 1.1 host 1.1\n")
    code, err = cli("map", "--out", tmp_path / "out", log)
    assert code != 0
    with pytest.raises(ValueError) as e:
        fusemap.map_log(log)
    assert str(e.value) == err
    assert "no laser scans" in err
    assert e.value.stage == "sensors"
