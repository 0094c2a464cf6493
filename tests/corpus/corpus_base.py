"""The shared part of the bad-input corpus (make_corpus.py): the case registry, the
simulated room every log fixture shows, and byte-level mutation helpers."""

from __future__ import annotations

import math
import random
from pathlib import Path


HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent

CASES: list[dict] = []
OUT = Path("corpus")  # set by make_corpus.main


def case(name: str, args: list[str], expect: str, **extra) -> Path:
    """Registers a case and returns its (new) directory."""
    assert not any(c["name"] == name for c in CASES), name
    d = OUT / name.replace("/", "__")
    d.mkdir(parents=True)
    CASES.append({"name": name, "args": args, "expect": expect, **extra})
    return d


def log_case(name: str, file: str, data: bytes, expect: str, names=(), doctor=None, **extra) -> Path:
    """A log file `file` holding `data`, run through `map` (and `doctor`)."""
    if doctor is None:
        doctor = {"error": "fail", "no_map": "fail", "map": "ok", "either": "any"}[expect]
    names = ["{case}/" + file, *names] if expect == "error" else list(names)
    d = case(name, ["map", "--out", "{case}/out", "{case}/" + file], expect, names=names, doctor=doctor, **extra)
    (d / file).write_bytes(data)
    return d


# ---------------------------------------------------------------------------------------
# The base scene: a robot driving through a 8 m x 5 m room with a box in it.

WALLS = [
    ((0.0, 0.0), (8.0, 0.0)),
    ((8.0, 0.0), (8.0, 5.0)),
    ((8.0, 5.0), (0.0, 5.0)),
    ((0.0, 5.0), (0.0, 0.0)),
    ((4.0, 1.0), (4.6, 1.0)),
    ((4.6, 1.0), (4.6, 1.6)),
    ((4.6, 1.6), (4.0, 1.6)),
    ((4.0, 1.6), (4.0, 1.0)),
]
N_SCANS = 40


def cast(x: float, y: float, a: float) -> float:
    best = 81.91  # CARMEN's no-return
    dx, dy = math.cos(a), math.sin(a)
    for (x1, y1), (x2, y2) in WALLS:
        ex, ey = x2 - x1, y2 - y1
        den = dx * ey - dy * ex
        if abs(den) < 1e-12:
            continue
        t = ((x1 - x) * ey - (y1 - y) * ex) / den
        u = ((x1 - x) * dy - (y1 - y) * dx) / den
        if t > 0 and 0 <= u <= 1:
            best = min(best, t)
    return best


def pose(i: int) -> tuple[float, float, float]:
    return 1.0 + 0.05 * i, 2.5 + 0.01 * i, 0.01 * i


def flaser(i: int, dx: float = 0.0) -> str:
    x, y, th = pose(i)
    ranges = " ".join(f"{cast(x, y, th + math.radians(-90 + k)):.3f}" for k in range(180))
    t = 1000.0 + 0.1 * i
    return f"FLASER 180 {ranges} {x + dx:.4f} {y:.4f} {th:.4f} {x + dx:.4f} {y:.4f} {th:.4f} {t:.6f} corpus {t:.6f}"


def odom(i: int) -> str:
    x, y, th = pose(i)
    t = 1000.0 + 0.1 * i - 0.05
    return f"ODOM {x:.4f} {y:.4f} {th:.4f} 0.5 0 0 {t:.6f} corpus {t:.6f}"


def carmen_lines() -> list[str]:
    lines = []
    for i in range(N_SCANS):
        lines.append(odom(i))
        lines.append(flaser(i))
    return lines


def text(lines: list[str]) -> bytes:
    return ("\n".join(lines) + "\n").encode()



WORLD = str(REPO / "worlds" / "corridor.toml")

# The config sections a simulated world does not exercise (its poses are true: no
# estimator, no SLAM, no clock faults): their values are swept over a bag instead.
BAG_SECTIONS = ("estimator", "slam", "log")


def example_numeric_keys() -> tuple[str, list[str], list[tuple[int, str, str]]]:
    """configs/example.toml, its lines, and its numeric keys as (line index, key, section)."""
    example = (REPO / "configs" / "example.toml").read_text()
    lines = example.split("\n")
    numeric, current = [], ""
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("["):
            current = s.strip("[]")
        if s.startswith("#") or "=" not in s or s.startswith("["):
            continue
        key, value = (p.strip() for p in s.split("=", 1))
        try:
            float(value.split("#")[0].strip())
        except ValueError:
            continue
        numeric.append((i, key, current))
    return example, lines, numeric


def patched(data: bytes, at: int, value: bytes) -> bytes:
    return data[:at] + value + data[at + len(value):]


def random_flips(prefix: str, file: str, data: bytes, n: int) -> None:
    rng = random.Random(prefix)
    for i in range(n):
        b = bytearray(data)
        for _ in range(8):
            b[rng.randrange(len(b))] = rng.randrange(256)
        log_case(f"{prefix}-{i}", file, bytes(b), "either")
