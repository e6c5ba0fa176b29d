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
- ``hoistable``: the loop's blockers removed (the solves in plain operations,
  ``benchmarks/_plain_linalg.py``; YNNPACK fusions off, a per-program option; no
  progress report), default flags;
- ``hoisted``: ``hoistable`` with the threshold raised: the integration loop is one
  kernel;
- ``inner``: ``today`` with the threshold raised, nothing else changed (with it
  jaxrail's programs leave YNNPACK's fusions out, :mod:`jaxrail.compilation.loop_kernels`,
  as ``jaxrail simulate`` runs): for a vehicle without joints the engine's IMEX loop
  holds no LAPACK call, so XLA may hoist the loops inside the step loop (the stages')
  while the progress report keeps the step loop itself apart.

Prints JSON: per variant the compile time, the run times of ``--runs`` calls of the
compiled run (after the first, which compiles), steps, µs per step (median and
fastest), whether the integration loop became one kernel (in the largest optimised
program, :func:`_loop_in_one_kernel`), how many loops XLA made kernels of and how many
custom calls are left in it (:func:`_kernels_and_calls`), the largest difference of the wheelsets' lateral
displacements from ``today``'s over all output times [mm], the ratios to ``today`` and
the load.
The "hoistable" variants' rest pose solves with the plain operations too (they replace
``jnp.linalg.solve`` everywhere); it runs once per run, outside the loop.

    python benchmarks/loop_hoisting.py [--duration 1] [--runs 5] [--contact table|online] [--variants today inner]
    python benchmarks/loop_hoisting.py --toy   (the stage matrix's inverse in a small loop)
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from _variants import run_variant  # benchmarks/_variants.py, beside this script
from jaxrail.compilation.loop_kernels import THRESHOLD_FLAG

VARIANTS = ("today", "ynn-off", "hoistable", "hoisted", "inner")
THRESHOLD = THRESHOLD_FLAG


def _with_threshold():
    """This process's ``XLA_FLAGS`` with the hoisting threshold raised."""
    return (os.environ.get("XLA_FLAGS", "") + " " + THRESHOLD).strip()


def _loop_in_one_kernel(text):
    """Whether an optimised program's entry computation (``as_text()``) runs no ``while``
    itself and calls a kernel XLA made of one (``xla_cpu_small_call``)."""
    entry = text[text.find("\nENTRY"):]
    return " while(" not in entry and "xla_cpu_small_call" in entry


def _kernels_and_calls(text):
    """(loops XLA compiled into one kernel, other custom calls: LAPACK, FFI, YNNPACK's
    fusions) in an optimised program's text."""
    return text.count('xla_cpu_small_call="true"'), (text.count(" custom-call(")
                                                      + text.count("kind=kCustom"))


def child(variant, duration, runs, contact):
    if variant in ("hoisted", "inner"):
        os.environ["XLA_FLAGS"] = _with_threshold()
    os.environ["JAXRAIL_COMPILATION_CACHE"] = "off"
    import jax
    import jax.numpy as jnp
    import numpy as np
    from jax._src import stages

    from jaxrail import enable_float64
    enable_float64()
    import jaxrail.compilation.compiler
    import jaxrail._time_report
    from jaxrail.scenarios import load_scenario, run_scenario

    programs = []  # every compiled program, read after the runs (outside the timings)
    compile_lowered = stages.Lowered.compile

    def recording(self, *args, **kwargs):
        compiled = compile_lowered(self, *args, **kwargs)
        programs.append(compiled)
        return compiled

    stages.Lowered.compile = recording
    if variant in ("hoistable", "hoisted"):
        sys.path.insert(0, str(Path(__file__).parent))
        import _plain_linalg as plain
        jax.scipy.linalg.cho_factor, jax.scipy.linalg.cho_solve = plain.cho_factor, plain.cho_solve
        jnp.linalg.inv, jnp.linalg.solve = plain.inv, plain.solve
        jaxrail._time_report.report_time = lambda t: None
    if variant in ("ynn-off", "hoistable", "hoisted"):
        jaxrail.compilation.compiler._CPU_OPTIONS["xla_cpu_experimental_ynn_fusion_type"] = ""
    scenario = load_scenario("paper-curve")
    first, *_ = run_scenario(scenario, duration, contact=contact)
    walls = []
    for _ in range(runs):
        second, *_ = run_scenario(scenario, duration, contact=contact)
        walls.append(float(second.wall_time_s))
    integration = max((p.as_text() or "" for p in programs), key=len)
    steps = int(second.accepted_steps) + int(second.rejected_steps)
    print(json.dumps({
        "variant": variant, "status": second.status,
        "compile_s": round(float(first.compile_time_s), 2),
        "run_s": [round(w, 3) for w in walls], "steps": steps,
        "us_per_step": round(1e6 * float(np.median(walls)) / steps, 1),
        "us_per_step_min": round(1e6 * min(walls) / steps, 1),
        "loop_in_one_kernel": _loop_in_one_kernel(integration),
        "loops_hoisted_and_custom_calls": _kernels_and_calls(integration),
        "lateral": np.asarray(second.wheelset_lateral).tolist()}))


def toy_child(runs):
    """A loop of 1000 steps a <- a + 1e-3 a^-1 of a 28 x 28 matrix (the IMEX stage
    matrix's size), with LAPACK's inverse and with the plain-operation one: median ms
    of ``runs`` calls, and whether XLA made the loop one kernel."""
    import statistics
    import time

    import jax
    import jax.numpy as jnp
    sys.path.insert(0, str(Path(__file__).parent))
    import _plain_linalg as plain
    jax.config.update("jax_enable_x64", True)
    a = 3.0 * jnp.eye(28) + 0.01
    out = {}
    for name, inverse in (("lapack", jnp.linalg.inv), ("plain", plain.inv)):
        loop = jax.jit(lambda a: jax.lax.fori_loop(0, 1000, lambda i, a: a + 1e-3 * inverse(a), a))
        compiled = loop.lower(a).compile()
        jax.block_until_ready(compiled(a))
        times = []
        for _ in range(runs):
            start = time.perf_counter()
            jax.block_until_ready(compiled(a))
            times.append(1e3 * (time.perf_counter() - start))
        out[name] = {"ms": round(statistics.median(times), 2),
                     "loop_in_one_kernel": _loop_in_one_kernel(compiled.as_text())}
    print(json.dumps(out))


def toy(runs):
    """:func:`toy_child` with XLA's default flags and with the threshold raised."""
    result = {}
    for name, flags in (("default", os.environ.get("XLA_FLAGS", "")),
                        ("threshold", _with_threshold())):
        env = dict(os.environ, XLA_FLAGS=flags)
        out = subprocess.run([sys.executable, __file__, "--toy-child", "--runs", str(runs)],
                             capture_output=True, text=True, env=env, check=True)
        result[name] = json.loads(out.stdout.splitlines()[-1])
    print(json.dumps({"toy": "1000 inverses of a 28 x 28 matrix in a fori_loop",
                      "flags": result, "load_1min": round(os.getloadavg()[0], 2)}, indent=1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0)
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--contact", choices=("table", "online"), default="table")
    parser.add_argument("--child", choices=VARIANTS)
    parser.add_argument("--toy", action="store_true", help="the inverse in a small loop only")
    parser.add_argument("--toy-child", action="store_true")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    if args.toy_child:
        return toy_child(args.runs)
    if args.toy:
        return toy(args.runs)
    if args.child:
        return child(args.child, args.duration, args.runs, args.contact)
    import numpy as np
    rows = []
    for variant in args.variants:
        command = [sys.executable, __file__, "--child", variant, "--duration",
                   str(args.duration), "--runs", str(args.runs), "--contact", args.contact]
        rows.append(run_variant(command, variant))
    laterals = {r["variant"]: np.asarray(r.pop("lateral")) for r in rows if "lateral" in r}
    base = next((r for r in rows if r["variant"] == "today" and "error" not in r), None)
    for r in rows:
        if base is not None and "error" not in r:
            r["lateral_vs_today_mm"] = float(1e3 * np.max(np.abs(
                laterals[r["variant"]] - laterals["today"])))
            r["step_time_vs_today"] = round(r["us_per_step"] / base["us_per_step"], 3)
            r["step_time_min_vs_today"] = round(r["us_per_step_min"] / base["us_per_step_min"], 3)
            r["compile_vs_today"] = round(r["compile_s"] / base["compile_s"], 3)
    print(json.dumps({"scenario": "paper-curve", "contact": args.contact, "integrator": "IMEX",
                      "duration_s": args.duration, "variants": rows,
                      "load_1min_after": round(os.getloadavg()[0], 2)}, indent=1))


if __name__ == "__main__":
    main()
