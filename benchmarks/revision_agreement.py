"""Do two revisions of jaxrail compute the same run? A refactor must move no number.

Runs each scenario for ``--duration`` seconds with this working tree and with the
revision ``--against`` (checked out into a temporary ``git worktree``), each in its own
process, and prints JSON: per scenario and contact mode, the largest difference of the
bodies' positions [m] and Euler parameters [-] over every output, of their rates, the
wall times (whole process; the run without compiling, and its real-time factor; the
compile time), and both runs' statuses and step counts. The two revisions run one after
the other, so the machine's load is alike for both (the load is printed), each with
jaxrail's persistent compilation cache off (compiled cold).
Usage: ``python benchmarks/revision_agreement.py --against b86628e [--duration 3]
[--scenarios paper-curve paper-curve-irregular] [--contacts table online]``.
"""

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from _worktree import ROOT, revision_tree  # benchmarks/_worktree.py, beside this script


RUN = """
import sys, time, numpy as np
sys.path.insert(0, {root!r})
import jaxrail
jaxrail.enable_float64()
from jaxrail.scenarios import load_scenario, run_scenario
start = time.perf_counter()
result = run_scenario(load_scenario({scenario!r}), duration={duration!r}, contact={contact!r})[0]
np.savez({out!r}, q=np.asarray(result.q), qdot=np.asarray(result.qdot), t=np.asarray(result.t),
         wall=time.perf_counter() - start, status=str(result.status),
         run_wall=float(result.wall_time_s), compile=float(result.compile_time_s),
         steps=int(result.accepted_steps), module=jaxrail.__file__)
"""


def start(root, scenario, duration, contact, out, core=None):
    """One run in a process of its own, with ``root``'s jaxrail first on the path (on
    CPU ``core`` alone where given): the Popen."""
    # compiled cold in both: a program cached on disk by an earlier run would hide one
    # revision's compile time
    env = dict(os.environ, PYTHONPATH=str(root), JAXRAIL_COMPILATION_CACHE="off")
    code = RUN.format(root=str(root), scenario=scenario, duration=duration, contact=contact,
                      out=str(out))
    pin = [] if core is None else ["taskset", "-c", str(core)]
    return subprocess.Popen(pin + [sys.executable, "-c", code], env=env,
                            cwd=tempfile.gettempdir())


def finish(process, out):
    if process.wait() != 0:
        raise RuntimeError(f"run failed ({process.returncode}): {out}")
    return np.load(out)


def run_pair(roots, scenario, duration, contact, folder, parallel):
    """{label: run} of both revisions, one after the other or side by side."""
    outs = {label: Path(folder) / f"{label}-{scenario}-{contact}.npz" for label in roots}
    if not parallel:
        return {label: finish(start(root, scenario, duration, contact, outs[label]),
                              outs[label]) for label, root in roots.items()}
    processes = {label: start(root, scenario, duration, contact, outs[label], core)
                 for core, (label, root) in enumerate(roots.items())}
    return {label: finish(p, outs[label]) for label, p in processes.items()}


def compare(a, b) -> dict:
    """Largest differences of positions, Euler parameters and rates between two runs."""
    n = a["q"].shape[1] // 7
    qa, qb = a["q"].reshape(-1, n, 7), b["q"].reshape(-1, n, 7)
    va, vb = a["qdot"].reshape(-1, n, 7), b["qdot"].reshape(-1, n, 7)
    return {"max_position_difference_m": float(np.max(np.abs(qa[..., :3] - qb[..., :3]))),
            "max_euler_parameter_difference": float(np.max(np.abs(qa[..., 3:] - qb[..., 3:]))),
            "max_velocity_difference_m_s": float(np.max(np.abs(va[..., :3] - vb[..., :3]))),
            "outputs": int(qa.shape[0]), "same_times": bool(np.array_equal(a["t"], b["t"]))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--against", required=True, help="git revision to compare with")
    parser.add_argument("--revision", help="a git revision instead of the working tree")
    parser.add_argument("--parallel", action="store_true",
                        help="both revisions at once, one core each")
    parser.add_argument("--duration", type=float, default=3.0)
    parser.add_argument("--scenarios", nargs="+", default=["paper-curve", "paper-curve-irregular"])
    parser.add_argument("--contacts", nargs="+", default=["table", "online"])
    args = parser.parse_args()
    out = {"benchmark": "revision_agreement", "against": args.against,
           "working_tree": subprocess.run(["git", "rev-parse", args.revision or "HEAD"],
                                          cwd=ROOT, check=True, capture_output=True,
                                          text=True).stdout.strip(),
           "working_tree_edits": args.revision is None, "parallel": args.parallel,
           "duration_s": args.duration, "load_before": os.getloadavg(), "runs": []}
    with tempfile.TemporaryDirectory() as folder:
        roots = {"against": Path(folder) / "other", "working": ROOT}
        if args.revision is not None:
            roots["working"] = Path(folder) / "revision"
        trees = [(roots["against"], args.against)] + (
            [] if args.revision is None else [(roots["working"], args.revision)])
        with contextlib.ExitStack() as checked_out:
            for tree, revision in trees:
                checked_out.enter_context(revision_tree(revision, tree))
            for scenario in args.scenarios:
                for contact in args.contacts:
                    runs = run_pair(roots, scenario, args.duration, contact, folder,
                                    args.parallel)
                    row = {"scenario": scenario, "contact": contact,
                           **compare(runs["against"], runs["working"])}
                    for label, r in runs.items():
                        row[label] = {"wall_s": float(r["wall"]), "status": str(r["status"]),
                                      "run_wall_s": float(r["run_wall"]),
                                      "compile_s": float(r["compile"]),
                                      "real_time_factor": args.duration / float(r["run_wall"]),
                                      "accepted_steps": int(r["steps"]),
                                      "jaxrail": str(r["module"])}
                    out["runs"].append(row)
                    print(json.dumps(row), file=sys.stderr)
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
