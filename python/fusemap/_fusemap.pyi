"""Type stubs of the Rust extension behind ``fusemap``."""

from typing import Any, Optional

import numpy as np
import numpy.typing as npt

__version__: str

def map_log_fields(path: str, config: Optional[str] = None) -> dict[str, Any]: ...
def corridor_scans() -> list[tuple[npt.NDArray[np.float32], float, float, tuple[float, float, float], float]]: ...

class Grid:
    def __init__(self, resolution: Optional[float] = None, config: Optional[str] = None) -> None: ...
    def insert_scan(
        self,
        ranges: npt.NDArray[np.float32],
        angle_min: float,
        angle_increment: float,
        pose: tuple[float, float, float],
        stamp: float,
    ) -> None: ...
    def insert_points(self, points: npt.NDArray[np.float64], pose: tuple[float, float, float], stamp: float) -> None: ...
    def arrays(self) -> dict[str, Any]: ...
    def to_npz(self, path: str) -> None: ...
