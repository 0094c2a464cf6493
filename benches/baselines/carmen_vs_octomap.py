#!/usr/bin/env python3
"""Compare fusemap maps of a corrected CARMEN log with OctoMap on the same scans.

usage: carmen_vs_octomap.py LOG.gz WORKDIR OCTOMAP_BENCH MAPDIR...

OCTOMAP_BENCH is ../shared/anchors/octomap_bench.cpp built as its header says; each MAPDIR
is the --out of `fusemap map --config C LOG` with `[map] origin = [0.0, 0.0]` in C, so
that fusemap's cells are OctoMap's keys. The figures of docs/BENCHMARKS.md ("The lidar's
own faults") came from this script.
Writes WORKDIR/scans.bin (the anchors' SCAN2D01 format, FLASER poses and ranges, grid
corners on multiples of 0.05 m), runs octomap_bench --hit 0.9 --miss 0.4 --clamp-min 0.12
--clamp-max 0.97 --raw, and for each fusemap output directory prints its occupied / free
cell counts and the share of cells (known to either map) whose class (occupied > 0.65,
free < 0.25, else unknown) agrees with OctoMap's.
"""
import gzip, math, struct, subprocess, sys, os
import numpy as np

RES, RMIN, RMAX = 0.05, 0.1, 10.0


def read_flaser(path):
    scans = []
    with gzip.open(path, "rt", errors="replace") as f:
        for line in f:
            t = line.split()
            if not t or t[0] != "FLASER":
                continue
            n = int(t[1])
            r = [float(v) for v in t[2:2 + n]]
            x, y, th = (float(v) for v in t[2 + n:5 + n])
            scans.append((x, y, th, r))
    return scans


def main():
    log, work, bench, maps = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    scans = read_flaser(log)
    n = len(scans[0][3])
    inc = math.radians(180.0 / n) if n in (180, 360) else math.radians(180.0 / (n - 1))
    amin = -math.pi / 2
    xs = [s[0] for s in scans]
    ys = [s[1] for s in scans]
    ox = math.floor((min(xs) - RMAX - 1) / RES) * RES
    oy = math.floor((min(ys) - RMAX - 1) / RES) * RES
    w = int(math.ceil((max(xs) + RMAX + 1 - ox) / RES))
    h = int(math.ceil((max(ys) + RMAX + 1 - oy) / RES))
    os.makedirs(work, exist_ok=True)
    sf = os.path.join(work, "scans.bin")
    with open(sf, "wb") as f:
        f.write(struct.pack("<8s4q7d", b"SCAN2D01", len(scans), n, w, h, amin, inc, RMIN, RMAX, RES, ox, oy))
        for x, y, th, r in scans:
            f.write(struct.pack("<%dd" % (n + 3), x, y, th, *r))
    raw = os.path.join(work, "octomap.raw")
    out = subprocess.run([bench, sf, "--hit", "0.9", "--miss", "0.4", "--clamp-min", "0.12", "--clamp-max", "0.97",
                          "--raw", raw], capture_output=True, text=True, check=True).stdout
    lo = np.fromfile(raw, dtype=np.float32).reshape(h, w)
    p = 1.0 - 1.0 / (1.0 + np.exp(lo.astype(np.float64)))
    ref = np.full((h, w), 0, np.int8)  # 0 unknown, 1 free, 2 occupied
    ref[p > 0.65] = 2
    ref[p < 0.25] = 1
    ref[np.isnan(lo)] = 0
    print(f"{os.path.basename(log)}: {len(scans)} scans x {n} beams; OctoMap occupied {int((ref == 2).sum())}, "
          f"free {int((ref == 1).sum())}")
    for m in maps:
        z = np.load(os.path.join(m, "map.npz"))
        occ, known, origin = z["occupancy"], z["known"], z["origin"]
        fx, fy = int(round((origin[0] - ox) / RES)), int(round((origin[1] - oy) / RES))
        cls = np.zeros((h, w), np.int8)
        fh, fw = occ.shape
        sub = np.zeros((fh, fw), np.int8)
        sub[(occ > 0.65) & known] = 2
        sub[(occ < 0.25) & known] = 1
        # Place fusemap's raster into the comparison grid (cells outside it stay unknown).
        y0, x0 = max(0, fy), max(0, fx)
        y1, x1 = min(h, fy + fh), min(w, fx + fw)
        cls[y0:y1, x0:x1] = sub[y0 - fy:y1 - fy, x0 - fx:x1 - fx]
        lost = int((sub == 2).sum()) - int((cls == 2).sum())
        either = (cls != 0) | (ref != 0)
        agree = ((cls == ref) & either).sum() / either.sum()
        occ_both = ((cls == 2) & (ref == 2)).sum()
        print(f"  {os.path.basename(m.rstrip('/')):<16} occupied {int((cls == 2).sum()):7d} free {int((cls == 1).sum()):8d}  "
              f"class agreement with OctoMap {100 * agree:.3f} %  occupied in both {int(occ_both)} "
              f"(OctoMap's occupied cells also occupied here: {100 * occ_both / max(1, (ref == 2).sum()):.2f} %)"
              + (f"  [{lost} occupied cells outside the grid]" if lost else ""))


main()
