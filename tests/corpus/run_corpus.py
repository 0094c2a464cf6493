#!/usr/bin/env python3
"""Run fusemap's bad-input corpus (written by make_corpus.py) and check every outcome.

Usage:
    run_corpus.py --fusemap BIN CORPUS_DIR [--jobs N] [--only SUBSTRING]

Each case runs `fusemap ARGS` (and, where the case says, `fusemap doctor LOG`) under a
1 GiB address-space limit (setrlimit RLIMIT_AS), a CPU-time limit and a wall-clock
limit, and is checked for:

* no crash: not killed by a signal (abort, segfault, the limits), no panic, no
  allocation failure, exit status 0, 1 (an error) or 2 (a command-line value refused);
* peak resident memory (the child's own ru_maxrss, from wait4) under 1 GiB;
* the expected outcome (make_corpus.py's docstring): a map and its summary, or one
  `error: ` line naming the file and what was wrong, with no map written;
* inputs untouched: every file of the case's directory outside `out/` has the size and
  modification time it had before, and no file appeared beside them (no SQLite -wal or
  -shm);
* for `doctor`: it fails where `map` fails on the log, and succeeds where `map` maps;
* for `validate` and `calibrate`, run on every log case of `map` with the same config:
  no crash, no change to the inputs, a refusal wherever `map` refuses, and one `error: `
  line whenever they refuse.

Prints one line per failed check and a summary (cases, runs, the largest peak RSS and
the longest run); exits 1 when any check failed.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import fcntl
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

GIB = 1 << 30
MEMORY_LIMIT = GIB
CPU_SECONDS = 60
WALL_SECONDS = 30
ENV = {**os.environ, "NO_COLOR": "1", "RUST_BACKTRACE": "0"}


class Run:
    def __init__(self, status: int, stdout: str, stderr: str, maxrss: int, seconds: float, timed_out: bool):
        self.status, self.stdout, self.stderr = status, stdout, stderr
        self.maxrss, self.seconds, self.timed_out = maxrss, seconds, timed_out


def limits(fsize: int | None):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
        resource.setrlimit(resource.RLIMIT_CPU, (CPU_SECONDS, CPU_SECONDS))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        if fsize is not None:
            # As a full disk: writes past the size fail (EFBIG), no signal.
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
    return apply


def run(argv: list[str], cwd: Path, fsize: int | None = None) -> Run:
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.monotonic()
        p = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out, stderr=err, cwd=cwd, env=ENV,
                             preexec_fn=limits(fsize))
        timed_out = threading.Event()

        def kill() -> None:
            timed_out.set()
            p.kill()

        timer = threading.Timer(WALL_SECONDS, kill)
        timer.start()
        _, status, usage = os.wait4(p.pid, 0)
        timer.cancel()
        p.returncode = 0  # reaped here, not by Popen
        seconds = time.monotonic() - start
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace")
        stderr = err.read().decode("utf-8", "replace")
    code = os.waitstatus_to_exitcode(status)
    return Run(code, stdout, stderr, usage.ru_maxrss * 1024, seconds, timed_out.is_set())


def snapshot(d: Path) -> dict[str, tuple[int, int]]:
    seen = {}
    for root, dirs, files in os.walk(d):
        rel_root = Path(root).relative_to(d)
        if rel_root.parts[:1] == ("out",):
            continue
        dirs[:] = [x for x in dirs if not (rel_root == Path(".") and x == "out")]
        for f in files:
            st = os.lstat(Path(root) / f)
            seen[str(rel_root / f)] = (st.st_size, st.st_mtime_ns)
    return seen


def map_files(out: Path) -> dict[str, bytes]:
    if not out.is_dir():
        return {}
    return {f.name: f.read_bytes() for f in out.iterdir() if f.is_file() and not f.name.startswith(".")}


def dotted(obj, key: str):
    for part in key.split("."):
        if isinstance(obj, list) and part.isdigit() and int(part) < len(obj):
            obj = obj[int(part)]
        elif isinstance(obj, dict) and part in obj:
            obj = obj[part]
        else:
            return None
    return obj


def crashed(r: Run) -> str | None:
    if r.timed_out:
        return f"hung: killed after {WALL_SECONDS} s"
    if r.status < 0:
        return f"killed by signal {-r.status}"
    for marker in ("panicked", "memory allocation of", "RUST_BACKTRACE", "stack overflow"):
        if marker in r.stderr:
            return f"stderr shows `{marker}`"
    if r.status not in (0, 1, 2):
        return f"exit status {r.status}"
    if r.maxrss >= MEMORY_LIMIT:
        return f"peak RSS {r.maxrss >> 20} MiB"
    return None


def check_case(fusemap: str, corpus: Path, c: dict) -> tuple[list[str], list[Run]]:
    """Checks one case. An output directory the case's runs create is removed afterwards,
    so that running the corpus again starts each case from what the generator wrote."""
    d = corpus / c["dir"]
    made_out = not (d / "out").exists()
    try:
        return check_case_in(fusemap, d, c)
    finally:
        if made_out and (d / "out").is_dir():
            shutil.rmtree(d / "out", ignore_errors=True)


def check_case_in(fusemap: str, d: Path, c: dict) -> tuple[list[str], list[Run]]:
    sub = lambda s: s.replace("{case}", str(d))  # noqa: E731
    args = [sub(a) for a in c["args"]]
    problems: list[str] = []
    runs: list[Run] = []
    out = d / "out"
    setup = c.get("setup")
    lock_file = None
    if setup in ("good_run_first", "fsize"):
        world = str(Path(__file__).resolve().parent.parent.parent / "worlds" / "corridor.toml")
        first = run([fusemap, "map", "--world", world, "--out", str(out)], d)
        if first.status != 0:
            return [f"the good run before the case failed: {first.stderr.strip()}"], [first]
    old_set = map_files(out)
    if setup == "lock":
        out.mkdir(exist_ok=True)
        lock_file = open(out / ".fusemap.lock", "a")
        fcntl.flock(lock_file, fcntl.LOCK_EX)
    before = snapshot(d)
    try:
        r = run([fusemap, *args], d, fsize=64 << 10 if setup == "fsize" else None)
    finally:
        if lock_file:
            lock_file.close()
    runs.append(r)
    after = snapshot(d)
    if before != after:
        changed = sorted(set(before.items()) ^ set(after.items()))
        problems.append(f"inputs changed: {changed[:4]}")
    why = crashed(r)
    if why:
        return [why, *problems, f"stderr: {r.stderr.strip()[-400:]}"], runs
    if c.get("max_seconds") and r.seconds > c["max_seconds"]:
        problems.append(f"took {r.seconds:.2f} s, more than {c['max_seconds']} s")
    expect = c["expect"]
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    files = map_files(out)
    has_map = any(n.startswith("map.") for n in files)
    if expect == "either":
        expect = "map" if r.status == 0 else "error"
    if expect == "map" and c.get("writes") == "bag":
        # `simulate`: the bag and its truth.
        if r.status != 0:
            problems.append(f"expected a bag, got exit {r.status}: {r.stderr.strip()[-300:]}")
        elif not (out / "bag" / "metadata.yaml").is_file() or "truth.yaml" not in files:
            problems.append(f"exit 0 but the output holds {sorted(files)}")
    elif expect == "map":
        if r.status != 0:
            problems.append(f"expected a map, got exit {r.status}: {r.stderr.strip()[-300:]}")
        elif not has_map or "summary.json" not in files:
            problems.append(f"exit 0 but the output holds {sorted(files)}")
        else:
            summary = json.loads(files["summary.json"])
            for key, want in c.get("summary", {}).items():
                got = dotted(summary, key)
                if got != want:
                    problems.append(f"summary.json {key} is {got}, expected {want}")
            notes = " | ".join(summary.get("notes", []))
            for n in c.get("notes", []):
                if n not in notes:
                    problems.append(f"no note says `{n}`: {notes[:300]}")
    else:
        want = 2 if expect == "usage" else 1
        if r.status != want:
            problems.append(f"expected exit {want}, got {r.status}")
        errors = [line for line in lines if line.startswith("error: ")]
        if expect == "usage":
            lines = lines[:1]  # the command-line parser adds a hint line
        if expect in ("error", "usage") and (len(lines) != 1 or len(errors) != 1):
            problems.append(f"expected one `error: ` line, got: {r.stderr.strip()[-500:]}")
        elif not errors:
            problems.append(f"no `error: ` line: {r.stderr.strip()[-500:]}")
        text = errors[-1] if errors else r.stderr
        for n in c.get("names", []):
            if sub(n) not in text:
                problems.append(f"the error does not name `{sub(n)}`: {text[:500]}")
        if expect == "no_map" and "summary.json" not in files:
            problems.append("a run with no map wrote no summary.json")
        if old_set and setup != "good_run_first":
            if files != old_set:
                problems.append("a failed run changed the previous output set")
        elif has_map or "truth.yaml" in files:
            problems.append(f"a failed run left map files: {sorted(files)}")
    for rel in c.get("absent", []):
        if (d / rel).exists():
            problems.append(f"{rel} is still there")
    if c.get("keeps_old_set") and r.status != 0 and map_files(out) != old_set:
        problems.append("the stopped run did not leave the previous set whole")
    if "doctor" in c:
        dargs = [sub(a) for a in c.get("doctor_args", ["doctor", c["args"][-1]])]
        dr = run([fusemap, *dargs], d)
        runs.append(dr)
        why = crashed(dr)
        if why:
            problems.append(f"doctor: {why}: {dr.stderr.strip()[-300:]}")
        elif c["doctor"] == "fail" and dr.status != 1:
            problems.append("doctor exits 0 on a log that map refuses")
        elif c["doctor"] == "ok" and dr.status != 0:
            problems.append(f"doctor fails on a log that map maps: {dr.stderr.strip()[-300:]}")
        elif c["doctor"] == "any" and (dr.status == 0) != (r.status == 0):
            problems.append(f"doctor exits {dr.status} but map exits {r.status}")
    problems += check_validate_and_calibrate(fusemap, c, d, args, r, runs)
    return problems, runs


def check_validate_and_calibrate(fusemap: str, c: dict, d: Path, args: list[str], r: Run, runs: list[Run]) -> list[str]:
    """A log case of `map` also runs `validate` and `calibrate` on the same log and
    config (into out/validate, out/calibrate): neither may crash; each refuses a log that
    `map` refuses; where `map` maps, each runs or refuses with one `error: ` line (a log too
    short to hold a period out is refused, with the reason)."""
    if args[:1] != ["map"] or "--world" in args or "--crop" in args or c.get("setup") or "--out" not in args:
        return []
    if c["name"].startswith("output/"):
        return []  # the case is about map's output directory, which these do not share
    problems = []
    for cmd in ("validate", "calibrate"):
        xargs = [cmd, *args[1:]]
        xargs[xargs.index("--out") + 1] = str(d / "out" / cmd)
        before = snapshot(d)
        x = run([fusemap, *xargs], d)
        runs.append(x)
        if snapshot(d) != before:
            problems.append(f"{cmd}: inputs changed")
        why = crashed(x)
        errors = [line for line in x.stderr.splitlines() if line.startswith("error: ")]
        if why:
            problems.append(f"{cmd}: {why}: {x.stderr.strip()[-300:]}")
        elif r.status != 0 and x.status == 0:
            problems.append(f"{cmd} exits 0 on a log that map refuses")
        elif x.status != 0 and len(errors) != 1:
            problems.append(f"{cmd}: expected one `error: ` line, got: {x.stderr.strip()[-300:]}")
    return problems


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("corpus", type=Path)
    ap.add_argument("--fusemap", required=True)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--only", default="")
    a = ap.parse_args()
    a.fusemap = str(Path(a.fusemap).resolve())
    cases = [c for c in json.loads((a.corpus / "manifest.json").read_text()) if a.only in c["name"]]
    start = time.monotonic()
    failed = 0
    all_runs: list[tuple[str, Run]] = []
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        results = pool.map(lambda c: (c, check_case(a.fusemap, a.corpus, c)), cases)
        for c, (problems, runs) in results:
            all_runs += [(c["name"], r) for r in runs]
            if problems:
                failed += 1
                print(f"FAIL {c['name']}: " + "; ".join(problems), flush=True)
    biggest = max(all_runs, key=lambda nr: nr[1].maxrss)
    longest = max(all_runs, key=lambda nr: nr[1].seconds)
    print(f"{len(cases)} cases, {len(all_runs)} runs, {failed} failed, in {time.monotonic() - start:.1f} s; "
          f"largest peak RSS {biggest[1].maxrss / 2**20:.0f} MiB ({biggest[0]}); "
          f"longest run {longest[1].seconds:.2f} s ({longest[0]})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
