"""fusemap from Python: fused occupancy-grid maps as numpy arrays.

- ``map_log(path, config=None)`` maps a log (CARMEN, ROS 1 bag, MCAP, rosbag2 directory)
  exactly as ``fusemap map`` does and returns a :class:`Map` (its ``occupancy`` is
  ``map.npz``'s, bit for bit).
- :class:`Grid` maps online: ``insert_scan`` / ``insert_points`` one scan at a time, then
  ``occupancy()`` or ``to_npz(path)``; a ROS 2 node (rclpy) or a notebook can map live.

Errors are ``OSError`` (a file that cannot be read or written) or ``ValueError``
(anything else), with the messages the CLI prints; ``map_log``'s carry ``stage``, the
stage that refused the run (``"sensors"``, ``"mounts"``, ``"poses"``, ``"budget"``, …),
or ``None`` when the run was not refused. The GIL is released while mapping.
Arrays are row 0 = lowest y, column 0 = lowest x, as ``map.npz``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Optional, Union

import numpy as np

from . import _fusemap

__version__ = _fusemap.__version__
__all__ = ["Map", "Grid", "map_log", "corridor_scans"]

Config = Union[str, "os.PathLike[str]", None]


def _config(config: Config) -> Optional[str]:
    return None if config is None else os.fspath(config)


@dataclass(frozen=True)
class Map:
    """A mapped log: the arrays of ``map.npz``, the track and the run's summary."""

    occupancy: np.ndarray
    """Occupancy probability per cell (float32, H × W; the prior where never observed)."""
    log_odds: np.ndarray
    """Log-odds per cell (float32, H × W)."""
    known: np.ndarray
    """Whether each cell was observed (bool, H × W)."""
    resolution: float
    """Cell side, metres."""
    origin: tuple
    """(x, y) of the lower-left corner of cell [0, 0], metres."""
    trajectory: np.ndarray
    """The track the scans were placed with, N × 8 as TUM: t x y z qx qy qz qw."""
    summary: dict
    """The log's format, the run's notes and its report (summary.json's ``log``)."""
    semantic_class: Optional[np.ndarray] = None
    """With a camera: the most likely class index per cell (int16, -1 none)."""
    semantic_prob: Optional[np.ndarray] = None
    """With a camera: that class's probability (float32)."""
    semantic_probs: Optional[np.ndarray] = None
    """With a camera: every class's probability (float32, H × W × K)."""
    semantic_class_names: list = field(default_factory=list)
    """With a camera: the class names, by index."""
    semantic_class_ids: Optional[np.ndarray] = None
    """With a camera: the label-image id of each class (uint16)."""
    dynamic: Optional[np.ndarray] = None
    """With a camera: the dynamic layer's probability at the last stamp (float32)."""


def map_log(path: Union[str, "os.PathLike[str]"], config: Config = None) -> Map:
    """Maps the log at ``path`` with ``config`` (a TOML file's path or TOML text; the
    defaults without) as ``fusemap map`` does, and returns the :class:`Map`."""
    fields = _fusemap.map_log_fields(os.fspath(path), _config(config))
    return Map(**fields)


class Grid:
    """An occupancy grid mapped online with one lidar model (the config's first lidar, or
    the defaults)."""

    def __init__(self, resolution: Optional[float] = None, config: Config = None) -> None:
        """``config``: a TOML file's path or TOML text (with a newline); ``resolution``
        replaces its ``[map] resolution``. Calls from several threads wait for each
        other."""
        self._grid = _fusemap.Grid(resolution, _config(config))

    def insert_scan(self, ranges: Any, angle_min: float, angle_increment: float,
                    pose: tuple, stamp: float) -> None:
        """Inserts a scan: beam ``i`` at ``angle_min + i * angle_increment`` radians with
        range ``ranges[i]`` metres, the base at ``pose`` = (x, y, yaw), at ``stamp`` s."""
        r = np.ascontiguousarray(ranges, dtype=np.float32)
        self._grid.insert_scan(r, float(angle_min), float(angle_increment), tuple(map(float, pose)), float(stamp))

    def insert_points(self, points: Any, pose: tuple, stamp: float) -> None:
        """Inserts obstacle points (N × 2, x y in the base frame, metres) seen from
        ``pose``: free space along each ray from the lidar's mount, occupied at the point."""
        p = np.ascontiguousarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 2:
            raise ValueError(f"points must be N x 2 (x, y), got shape {p.shape}")
        self._grid.insert_points(p, tuple(map(float, pose)), float(stamp))

    def arrays(self) -> dict:
        """``occupancy``, ``log_odds``, ``known``, ``resolution``, ``origin`` over the
        observed cells' bounding box, as ``map.npz`` holds them."""
        return self._grid.arrays()

    def occupancy(self) -> np.ndarray:
        """Occupancy probabilities over the observed box (float32, H × W)."""
        return self._grid.arrays()["occupancy"]

    def to_npz(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes ``map.npz`` (the CLI's layout) to ``path``, atomically."""
        self._grid.to_npz(os.fspath(path))


def corridor_scans() -> list:
    """The design document's corridor run (§3.3) that ``fusemap demo --corridor`` maps:
    ``(ranges, angle_min, angle_increment, (x, y, yaw), stamp)`` per scan."""
    return _fusemap.corridor_scans()
