"""Does XLA's small-while-loop hoisting pay on jaxrail's real integration loop?

On the CPU XLA runs a program as one thunk per fused operation; its
``SmallWhileLoopHoistingPass`` compiles a whole ``while`` loop into one kernel instead,
if the loop's bytes accessed are under ``xla_cpu_small_while_loop_byte_threshold``
(settable only through ``XLA_FLAGS``: as a per-program option XLA refuses it, "not a
valid message value") and the loop holds no custom call, scatter, sort or custom
fusion. jaxrail's IMEX loop holds three kinds of them: LAPACK (the joints' Cholesky
solve, the stage matrix's inverse, the projection's solve), YNNPACK's custom fusions of
the larger dots, and the progress report's FFI call. Each variant runs the paper's
curve (trailer, S1002 on UIC60 1:40, table mode, IMEX, rigid rails) in a process of
its own:

- ``today``: jaxrail as it is, XLA's default flags;
- ``ynn-off``: ``today`` without YNNPACK's fusions (a per-program option);
- ``threshold``: ``today`` with the threshold raised (the loop still holds LAPACK);
- ``hoistable``: the loop's blockers removed (the solves in plain operations,
  ``benchmarks/_plain_linalg.py``; YNNPACK fusions off, a per-program option; no
  progress report), default flags;
- ``hoisted``: ``hoistable`` with the threshold raised: the integration loop is one
  kernel.

Prints JSON: per variant the compile time, the run times of ``--runs`` calls of the
compiled run (after the first, which compiles), steps, µs per step (median and
fastest), whether the integration loop became one kernel (the
optimised program's entry computation holds no ``while``), and the largest difference
of the wheelsets' lateral displacements from ``today`` [mm]; the ratios to ``today``
and the load.

    python benchmarks/loop_hoisting.py [--duration 1] [--runs 5] [--variants today hoisted]
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

VARIANTS = ("today", "ynn-off", "threshold", "hoistable", "hoisted")
THRESHOLD = "--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold=10000000000"


def child(variant, duration, runs):
    if variant in ("threshold", "hoisted"):
        os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + THRESHOLD).strip()
    os.environ["JAXRAIL_COMPILATION_CACHE"] = "off"
    import jax
    import jax.numpy as jnp
    import numpy as np
    from jax._src import stages

    from jaxrail import enable_float64
    enable_float64()
    import jaxrail._compiler
    import jaxrail._time_report
    from jaxrail.scenarios import load_scenario, run_scenario

    entries = []  # (length, entry computation) of each compiled program
    compile_lowered = stages.Lowered.compile

    def recording(self, *args, **kwargs):
        compiled = compile_lowered(self, *args, **kwargs)
        text = compiled.as_text() or ""
        entries.append((len(text), text[text.find("\nENTRY"):]))
        return compiled

    stages.Lowered.compile = recording
    if variant in ("hoistable", "hoisted"):
        sys.path.insert(0, str(Path(__file__).parent))
        import _plain_linalg as plain
        jax.scipy.linalg.cho_factor, jax.scipy.linalg.cho_solve = plain.cho_factor, plain.cho_solve
        jnp.linalg.inv, jnp.linalg.solve = plain.inv, plain.solve
        jaxrail._compiler._CPU_OPTIONS["xla_cpu_experimental_ynn_fusion_type"] = ""
        jaxrail._time_report.report_time = lambda t: None
    if variant == "ynn-off":
        jaxrail._compiler._CPU_OPTIONS["xla_cpu_experimental_ynn_fusion_type"] = ""
    scenario = load_scenario("paper-curve")
    first, *_ = run_scenario(scenario, duration, contact="table")
    walls = []
    for _ in range(runs):
        second, *_ = run_scenario(scenario, duration, contact="table")
        walls.append(float(second.wall_time_s))
    entry = max(entries)[1]
    steps = int(second.accepted_steps) + int(second.rejected_steps)
    print(json.dumps({
        "variant": variant, "status": second.status,
        "compile_s": round(float(first.compile_time_s), 2),
        "run_s": [round(w, 3) for w in walls], "steps": steps,
        "us_per_step": round(1e6 * float(np.median(walls)) / steps, 1),
        "us_per_step_min": round(1e6 * min(walls) / steps, 1),
        "loop_in_one_kernel": " while(" not in entry and "xla_cpu_small_call" in entry,
        "lateral": np.asarray(second.wheelset_lateral).tolist()}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0)
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--child", choices=VARIANTS)
    args = parser.parse_args()
    if args.child:
        return child(args.child, args.duration, args.runs)
    import numpy as np
    load = [os.getloadavg()[0]]
    rows = []
    for variant in args.variants:
        command = [sys.executable, __file__, "--child", variant, "--duration",
                   str(args.duration), "--runs", str(args.runs)]
        out = subprocess.run(command, capture_output=True, text=True)
        if out.returncode:
            rows.append({"variant": variant, "error": out.stderr[-2000:]})
            continue
        rows.append(json.loads(out.stdout.splitlines()[-1]))
        load.append(os.getloadavg()[0])
    laterals = {r["variant"]: np.asarray(r.pop("lateral")) for r in rows if "lateral" in r}
    base = next((r for r in rows if r["variant"] == "today" and "error" not in r), None)
    for r in rows:
        if base is not None and "error" not in r:
            r["lateral_vs_today_mm"] = float(1e3 * np.max(np.abs(
                laterals[r["variant"]] - laterals["today"])))
            r["step_time_vs_today"] = round(r["us_per_step"] / base["us_per_step"], 3)
            r["step_time_min_vs_today"] = round(r["us_per_step_min"] / base["us_per_step_min"], 3)
            r["compile_vs_today"] = round(r["compile_s"] / base["compile_s"], 3)
    print(json.dumps({"scenario": "paper-curve", "contact": "table", "integrator": "IMEX",
                      "duration_s": args.duration, "variants": rows,
                      "load_1min": [round(x, 2) for x in load]}, indent=1))


if __name__ == "__main__":
    main()
