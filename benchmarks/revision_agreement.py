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
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

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


def run(root, scenario, duration, contact, out):
    """One run in a process of its own, with ``root``'s jaxrail first on the path."""
    # compiled cold in both: a program cached on disk by an earlier run would hide one
    # revision's compile time
    env = dict(os.environ, PYTHONPATH=str(root), JAXRAIL_COMPILATION_CACHE="off")
    code = RUN.format(root=str(root), scenario=scenario, duration=duration, contact=contact,
                      out=str(out))
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=tempfile.gettempdir())
    return np.load(out)


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
    parser.add_argument("--duration", type=float, default=3.0)
    parser.add_argument("--scenarios", nargs="+", default=["paper-curve", "paper-curve-irregular"])
    parser.add_argument("--contacts", nargs="+", default=["table", "online"])
    args = parser.parse_args()
    out = {"benchmark": "revision_agreement", "against": args.against,
           "working_tree": subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, check=True,
                                          capture_output=True, text=True).stdout.strip(),
           "duration_s": args.duration, "load_before": os.getloadavg(), "runs": []}
    with tempfile.TemporaryDirectory() as folder:
        other = Path(folder) / "other"
        subprocess.run(["git", "worktree", "add", "--detach", str(other), args.against],
                       cwd=ROOT, check=True, capture_output=True)
        try:
            for scenario in args.scenarios:
                for contact in args.contacts:
                    runs = {label: run(root, scenario, args.duration, contact,
                                       Path(folder) / f"{label}-{scenario}-{contact}.npz")
                            for label, root in (("against", other), ("working", ROOT))}
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
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(other)], cwd=ROOT,
                           check=False, capture_output=True)
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
