#!/usr/bin/env python3
"""Write fusemap's bad-input corpus: small broken, hostile or unusual inputs, each with
the outcome fusemap must give.

Usage:
    make_corpus.py OUT_DIR

OUT_DIR (which must not exist yet, or be empty) receives one directory per case and
`manifest.json`, a list of cases:

    name     a unique name, `<group>/<what>`
    args     the fusemap command line; `{case}` stands for the case's directory
    expect   "map"       exit 0 with a map (and `summary.json`) in `{case}/out`
             "error"     exit 1, exactly one `error: ` line, no map written
             "no_map"    exit 1 with the reason: the run wrote a summary but no map
             "usage"     exit 2, a command-line value refused by the argument parser
                         (its `error: ` line, then its hint line)
             "either"    a map, or an error as above (mutations whose effect depends
                         on where the damage falls: what matters is that nothing breaks)
    names    strings (with `{case}`) the error line must contain (file, line, key, limit)
    summary  for "map": {dotted key of summary.json: least value} checks
    notes    for "map": strings that one of the summary's notes must contain
    doctor   "fail" (doctor must exit 1: it reports what map refuses), "ok", "any",
             or absent (the case runs no doctor)
    writes   optional: "bag" (`simulate`: success is a bag and its truth, not a map)
    setup    optional: "lock" (another process holds the output directory's lock),
             "fsize" (a file-size limit of 64 KiB stops the run as a full disk would),
             "good_run_first" (a good run fills `{case}/out` first; its files must
             survive a failing run or be replaced by a successful one)

Every case is made here from small fixtures written by this script (a simulated room
seen by a 180-beam lidar), by the third-party ROS writers of tests/fixtures, and by
mutating their bytes: nothing is downloaded. tests/corpus/run_corpus.py runs them.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import corpus_base
import corpus_ros
import corpus_sensors
import corpus_text


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(sys.argv[1]).resolve()
    if out.exists() and any(out.iterdir()):
        print(f"{out}: exists and is not empty", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    corpus_base.OUT = out
    tmp = out / ".fixtures"
    tmp.mkdir()
    corpus_text.carmen_cases()
    corpus_text.config_cases()
    corpus_text.world_cases()
    corpus_text.simulate_sweep()
    corpus_ros.ros1_cases(tmp)
    corpus_ros.mcap_cases(tmp)
    corpus_ros.rosbag2_cases(tmp)
    corpus_sensors.sensor_cases(tmp)
    corpus_text.output_cases()
    for c in corpus_base.CASES:
        c["dir"] = c["name"].replace("/", "__")
    (out / "manifest.json").write_text(json.dumps(corpus_base.CASES, indent=1))
    print(f"{len(corpus_base.CASES)} cases in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
