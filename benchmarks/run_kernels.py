"""Where a whole run's time goes, kernel by kernel: a built-in scenario (default the
paper's curve, IMEX, on the design track) run for ``--duration`` seconds under XLA's
thunk trace (:func:`jaxrail._kernel_profile.kernel_profile`), per step attempt.

With loops as kernels (``--loop-kernels``, as ``jaxrail simulate`` runs) each IMEX
step's stage loop is one kernel, so the rest of the list is what a step does around
it: diffrax's step-size control, the saved outputs, the stop events, the kept load
Jacobian's turn, the progress report. Each kernel comes with its HLO instruction's
``op_name`` (the JAX operations it came from). Tracing costs a few hundred ns per
kernel, so read shares and counts; ``untraced_us_per_step`` is the same run without
the trace's events, the run's own wall time over its step attempts.

Prints JSON. The process restarts itself with the trace flag (and the threshold).
Usage: ``python benchmarks/run_kernels.py [--contact table] [--duration 2]
[--loop-kernels] [--top 40]``.
"""

import argparse
import dataclasses
import json
import os
import re
import sys

from jaxrail._kernel_profile import TRACE_FLAG, kernel_profile, tracing_enabled
from jaxrail.compilation.loop_kernels import THRESHOLD_FLAG

_OP_NAME = re.compile(r'^\s*(?:ROOT )?%(\S+) = .*?op_name="([^"]*)"', re.M)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="paper-curve")
    parser.add_argument("--contact", default="table", choices=("table", "online"))
    parser.add_argument("--duration", type=float, default=2.0, help="simulated [s]")
    parser.add_argument("--loop-kernels", action="store_true")
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args()
    if not tracing_enabled():  # both flags are read when the backend starts
        flags = [os.environ.get("XLA_FLAGS", ""), TRACE_FLAG]
        if args.loop_kernels:
            flags.append(THRESHOLD_FLAG)
        os.environ["XLA_FLAGS"] = " ".join(flags).strip()
        os.execv(sys.executable, [sys.executable, *sys.argv])

    from jaxrail import enable_float64
    enable_float64()
    from jaxrail.compilation.cache import PROCESS_CACHE
    from jaxrail.scenarios import load_scenario
    from jaxrail.simulation import simulate

    scenario = dataclasses.replace(load_scenario(args.scenario), irregularities=None)
    vehicle, params, track = scenario.build()
    model = scenario.contact_model(vehicle, params, track, args.contact)

    def run():
        return simulate(vehicle, params, track, args.duration, scenario.speed,
                        scenario.misalignment, options=scenario.solver_options(args.duration),
                        contact_model=model)

    first = run()
    result = run()  # compiled: the wall time of the run alone
    attempts = int(result.accepted_steps) + int(result.rejected_steps)
    profile = kernel_profile(run, attempts, top=args.top)
    names = _op_names(PROCESS_CACHE.values())
    for kernel in profile["kernels"]:
        kernel["op_name"] = names.get(kernel["name"])
    print(json.dumps({
        "benchmark": "run_kernels", "scenario": scenario.name, "contact": args.contact,
        "duration_s": args.duration, "loop_kernels": args.loop_kernels,
        "status": result.status, "compile_time_s": round(float(first.compile_time_s), 1),
        "step_attempts": attempts,
        "untraced_us_per_step": round(1e6 * float(result.wall_time_s) / attempts, 1),
        "per_step": profile, "load": os.getloadavg()}, indent=1))


def _op_names(programs) -> dict:
    """{instruction: op_name} of the compiled ``programs`` (the run's among them),
    from their optimised HLO."""
    names = {}
    for program in programs:
        compiled = getattr(program, "compiled", program)  # a traced-program-cache run
        if not hasattr(compiled, "as_text"):
            continue
        for name, op in _OP_NAME.findall(compiled.as_text()):
            names[name] = op.split("/while/body/")[-1]
    return names


if __name__ == "__main__":
    main()
