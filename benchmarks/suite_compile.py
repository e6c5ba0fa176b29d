"""How long does the test suite spend compiling? Runs the suite (of the working tree,
or of a git revision checked out into a temporary worktree) with empty compilation
caches and prints JSON: the suite's wall time and exit code, and JAX's compile events
(XLA's backend compile, tracing, lowering) summed over every Python process of the run
(pytest's workers and the processes the tests start; ``_suite_compile/sitecustomize.py``),
per test file and for the costliest tests.

    python benchmarks/suite_compile.py [--revision REV] [--out FILE] [-- pytest args]

The events are wall-clock seconds as JAX reports them, so run it on a quiet machine
and compare revisions in one session (the load is in the JSON).
"""

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from _worktree import ROOT, revision_tree

SITE = Path(__file__).resolve().parent / "_suite_compile"  # its sitecustomize.py
FIELDS = ("compile_s", "compile_cpu_s", "trace_s", "lower_s", "programs")


def _summed(reports):
    """Per test, the fields summed over the processes' lines ``[test, field, seconds]``
    (``programs``: the XLA compiles counted)."""
    tests = defaultdict(lambda: dict.fromkeys(FIELDS, 0.0))
    for lines in reports:
        for test, field, seconds in lines:
            if field == "program":
                continue
            tests[test][field] += seconds
            if field == "compile_s":
                tests[test]["programs"] += 1
    return tests


def repeated_programs(reports, top=30):
    """Programs (JAX's persistent-cache keys) that the run compiled more than once, in
    one process or several: ``repeated_s``, the seconds of every compile of a key but
    its first (what sharing identical programs would save), and the costliest ones
    with the tests that compiled them; and the programs by their compile time
    (``by_compile_time``: how many took under 0.1 s, 0.1-1 s, ..., and their seconds)."""
    compiles = defaultdict(list)
    for lines in reports:
        for test, field, value in lines:
            if field == "program":
                key, name, seconds = value
                compiles[key].append((seconds, name, test))
    repeated = []
    for key, seen in compiles.items():
        if len(seen) > 1:
            extra = sum(s for s, _, _ in seen) - seen[0][0]
            repeated.append((extra, seen))
    repeated.sort(key=lambda item: -item[0])
    seconds = [s for seen in compiles.values() for s, _, _ in seen]
    bounds = (0.1, 1.0, 10.0, 30.0, float("inf"))
    by_time = {(f"under_{b:g}_s" if b < bounds[-1] else f"{lo:g}_s_and_over"): {
        "programs": sum(lo <= s < b for s in seconds),
        "compile_s": round(sum(s for s in seconds if lo <= s < b), 1)}
        for lo, b in zip((0.0,) + bounds[:-1], bounds)}
    return {"keyed_programs": sum(len(seen) for seen in compiles.values()),
            "by_compile_time": by_time,
            "distinct_programs": len(compiles),
            "keyed_compile_s": round(sum(s for seen in compiles.values() for s, _, _ in seen), 1),
            "repeated_s": round(sum(extra for extra, _ in repeated), 1),
            "most_repeated": [{"repeated_s": round(extra, 2), "module": seen[0][1],
                               "compiles": len(seen),
                               "tests": sorted({test for _, _, test in seen})}
                              for extra, seen in repeated[:top]]}


def summarise(reports, top=30):
    """The suite's totals, per file and the ``top`` costliest tests, from the
    processes' reports."""
    tests = _summed(reports)
    files = defaultdict(lambda: dict.fromkeys(FIELDS, 0.0))
    for nodeid, entry in tests.items():
        for field in FIELDS:
            files[nodeid.split("::")[0]][field] += entry[field]
    total = {field: sum(entry[field] for entry in tests.values()) for field in FIELDS}

    def ranked(table):
        rows = sorted(table.items(), key=lambda kv: -kv[1]["compile_s"])[:top]
        return [{"name": name, **{f: round(v, 2) for f, v in entry.items()}}
                for name, entry in rows]
    return {"total": {f: round(v, 1) for f, v in total.items()},
            "processes": len(reports), "files": ranked(files), "tests": ranked(tests),
            "repeated": repeated_programs(reports, top)}


def run_suite(tree: Path, pytest_args, out: Path):
    cache = out.parent / "cache"  # empty, and removed with the scratch folder
    env = dict(os.environ, SUITE_COMPILE_OUT=str(out), JAXRAIL_CACHE_DIR=str(cache),
               JAX_COMPILATION_CACHE_DIR=str(cache / "xla"),
               PYTHONPATH=os.pathsep.join([str(tree), str(SITE)]))
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", *pytest_args], cwd=tree, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - start
    tail = done.stdout.strip().splitlines()[-1:] if done.stdout.strip() else []
    return {"wall_s": round(wall, 1), "returncode": done.returncode, "summary": tail}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--revision", help="a git revision instead of the working tree")
    parser.add_argument("--out", help="also write the JSON here")
    parser.add_argument("pytest_args", nargs="*")
    args = parser.parse_args()
    load = os.getloadavg()
    with tempfile.TemporaryDirectory() as scratch, (
            revision_tree(args.revision, Path(scratch) / "tree") if args.revision
            else contextlib.nullcontext(ROOT)) as tree:
        events = Path(scratch) / "events"
        run = run_suite(tree, args.pytest_args, events)
        reports = [[json.loads(line) for line in p.read_text().splitlines() if line]
                   for p in sorted(events.glob("*.jsonl"))]
    result = {"revision": args.revision or "working tree", **run,
              "load_at_start": [round(x, 2) for x in load],
              "load_at_end": [round(x, 2) for x in os.getloadavg()],
              **summarise(reports)}
    text = json.dumps(result, indent=1)
    if args.out:
        Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
