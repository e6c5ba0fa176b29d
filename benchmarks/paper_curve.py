"""Benchmark of the paper's example: the trailer through the 300 m left curve at 18.3 m/s
for 41 s, with the simplified and the real S1002 profiles (built-in scenarios
``paper-curve-simplified`` and ``paper-curve``).

Prints JSON per profile kind, track (``--tracks smooth german-low``: the design track,
or the same with a realisation of that irregularity spectrum, seed 7, 3-150 m), contact
model (``--contacts online table``), track support (``--supports rigid flexible``: rigid
rails, or the co-moving flexible track with its default values) and integrator
(``--integrators tsit5 imex``; ``imex-jN``: IMEX with a new load Jacobian every N
accepted steps instead of 8), all in one process, each irregular run's wall time over
its smooth twin's and each flexible run's over its rigid twin's: compile time, wall
time, simulated time, real-time factor, steps accepted and rejected, right-hand-side
evaluations and load Jacobians (as the run counted them), status; for every run after
the first of a profile and contact model, its largest differences from that first run
(leading wheelset lateral displacement [mm], outer wheel's normal force [% of its
largest], also outside impacts (from 0.05 s before to 0.25 s after a patch steeper than
0.3 rad appears on that wheel), and the intervals with two patches on a wheel of the
leading wheelset). Compile times: cold (the runs use a new, empty persistent compilation
cache) and cached (the same programs in a new process that finds them in that cache:
``cached_compile_time_s``, from a run of 1 ms with the same options). With ``--save
DIR`` it also keeps each run (``DIR/<scenario>.pkl``, the SimulationResult as numpy
arrays, for experiments/paper_curve/figures.py), its results file (``.h5``) and summary
(``.json``). Each run also reports its leading wheelset's largest lateral displacement,
its outer wheel's largest Q and Y/Q and the largest rail deflections.
Usage: ``python benchmarks/paper_curve.py [--duration 41] [--save DIR]
[--scenarios paper-curve-simplified paper-curve] [--tracks smooth german-low]
[--contacts online] [--supports rigid] [--integrators tsit5 imex]
[--formulations joints auto]``; ``--formulations joints auto`` runs each case with the
vehicle file's joints (eq. 19, the reference) and with the wheelsets carrying their
axleboxes (no joints), the second compared with the first.
"""

import argparse
import dataclasses
import itertools
import json
import os
import pickle
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

import jax
import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail._files import write_atomically  # noqa: E402
from jaxrail.results import summarize  # noqa: E402
from jaxrail.scenarios import load_scenario, run_scenario  # noqa: E402
from jaxrail.scenarios.irregularities import IrregularitySpec  # noqa: E402
from jaxrail.simulation import simulate  # noqa: E402

OUTER = 1  # the right wheel is the outer one in the paper's left curve
IMPACT_ANGLE = 0.3  # [rad] a patch steeper than this is off the tread (tread: < 0.1 rad)
IMPACT = (0.05, 0.25)  # [s] before and after such a patch appears: the impact's transient


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=None, help="[s] (default 41)")
    parser.add_argument("--save", type=Path, default=None, help="keep the runs in DIR")
    parser.add_argument("--scenarios", nargs="+",
                        default=["paper-curve-simplified", "paper-curve"])
    parser.add_argument("--tracks", nargs="+", default=["smooth", "german-low"],
                        help="smooth, an irregularity spectrum (seed 7, 3-150 m), or "
                        "'scenario': the scenario's own")
    parser.add_argument("--contacts", nargs="+", default=["online"],
                        choices=("online", "table"))
    parser.add_argument("--integrators", nargs="+", default=["tsit5", "imex"],
                        type=_integrator, help="tsit5, imex (a new load Jacobian every 8 "
                        "accepted steps) or imex-jN (every N)")
    parser.add_argument("--supports", nargs="+", default=["rigid"],
                        choices=("rigid", "flexible", "scenario"))
    parser.add_argument("--formulations", nargs="+", default=["auto"],
                        choices=("auto", "joints"), help="auto: the wheelsets carry their "
                        "axleboxes (no joints); joints: eq. (19) with the axle joints")
    parser.add_argument("--no-cached-compile", action="store_true",
                        help="skip the cached-compile child runs")
    parser.add_argument("--progress", action="store_true")
    parser.add_argument("--cached-child", nargs=6, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.cached_child:
        print(json.dumps(_compile_only(*args.cached_child, args.duration)))
        return
    cache = os.environ.get("JAX_COMPILATION_CACHE_DIR") or tempfile.mkdtemp(prefix="xla-")
    os.environ["JAX_COMPILATION_CACHE_DIR"] = cache
    jax.config.update("jax_compilation_cache_dir", cache)
    runs = []
    for name in args.scenarios:
        for track in args.tracks:
            for contact in args.contacts:
                first = None
                for support in args.supports:
                    for integrator, formulation in itertools.product(args.integrators,
                                                                     args.formulations):
                        scenario = _scenario(name, track, integrator, support, formulation)
                        result, vehicle, params, _ = run_scenario(
                            scenario, args.duration, args.progress, contact=contact)
                        runs.append(_report(name, scenario, contact, integrator, result,
                                            first))
                        runs[-1].update(track=track, support=support, formulation=formulation,
                                        bodies=vehicle.system.n_bodies,
                                        constraint_rows=vehicle.system.n_constraints)
                        if not args.no_cached_compile:
                            runs[-1]["cached_compile_time_s"] = _cached_compile(
                                name, track, contact, integrator, support, formulation,
                                args.duration)
                        print(json.dumps(runs[-1]), flush=True)
                        first = result if first is None else first
                        if args.save is not None:
                            _save(args.save, f"{name}-{track}-{contact}-{support}-{integrator}"
                                  f"-{formulation}", scenario, result, vehicle, params)
    print(json.dumps({"benchmark": "paper_curve", "runs": runs,
                      "irregular_over_smooth_wall_time": _irregular_over_smooth(runs),
                      "flexible_over_rigid_wall_time": _flexible_over_rigid(runs),
                      "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                                  "load": os.getloadavg()}}, indent=2))


def _integrator(text):
    """An ``--integrators`` entry: tsit5, imex or imex-jN (N >= 1)."""
    if text in ("tsit5", "imex") or (text.startswith("imex-j") and text[6:].isdigit()
                                      and int(text[6:]) >= 1):
        return text
    raise argparse.ArgumentTypeError(f"{text!r} is not tsit5, imex or imex-jN")


def _scenario(name, track, integrator, support="rigid", formulation="auto"):
    """The built-in scenario ``name`` with ``integrator`` (tsit5, imex, or imex-jN: a new
    load Jacobian every N accepted steps) on the design track ("smooth") or on a
    realisation of the spectrum ``track`` (seed 7, 3-150 m) or the scenario's own
    ("scenario"), on rigid rails, the flexible track or the scenario's (``support``), with the vehicle's ``formulation`` (auto or joints)."""
    every = {} if not integrator.startswith("imex-j") else {"jacobian_every": int(integrator[6:])}
    scenario = load_scenario(name)
    flexible = scenario.flexible if support == "scenario" else (
        {} if support == "flexible" else None)
    scenario = dataclasses.replace(scenario, integrator=integrator[:4] if every
                                   else integrator, **every, flexible=flexible,
                                   formulation=formulation)
    if track == "scenario":
        return scenario
    if track == "smooth":
        return dataclasses.replace(scenario, irregularities=None)
    return dataclasses.replace(scenario, irregularities=IrregularitySpec(
        "spectrum", spectrum=track, seed=7))


def _irregular_over_smooth(runs):
    """{scenario/track/contact/support/integrator/formulation: wall time over the smooth
    run's}."""
    key = lambda r: (r["scenario"], r["contact"], r["support"], r["integrator"],  # noqa: E731
                     r["formulation"])
    smooth = {key(r): r["wall_time_s"] for r in runs if r["track"] == "smooth"}
    return {"/".join((r["scenario"], r["track"], *key(r)[1:])): round(
        r["wall_time_s"] / smooth[key(r)], 3)
        for r in runs if r["track"] != "smooth" and key(r) in smooth}


def _flexible_over_rigid(runs):
    """{scenario/track/contact/integrator/formulation: a flexible run's wall time over its
    rigid twin's}."""
    key = lambda r: (r["scenario"], r["track"], r["contact"], r["integrator"],  # noqa: E731
                     r["formulation"])
    rigid = {key(r): r["wall_time_s"] for r in runs if r["support"] == "rigid"}
    return {"/".join(key(r)): round(r["wall_time_s"] / rigid[key(r)], 3)
            for r in runs if r["support"] == "flexible" and key(r) in rigid}


def _compile_only(name, track, contact, integrator, support, formulation, duration):
    """compile_time_s of a 1 ms run with the options of a ``duration`` run."""
    scenario = _scenario(name, track, integrator, support, formulation)
    vehicle, params, track = scenario.build()
    duration = scenario.duration if duration is None else duration
    result = simulate(vehicle, params, track, 1e-3, scenario.speed, scenario.misalignment,
                      options=scenario.solver_options(duration),
                      contact_model=scenario.contact_model(vehicle, params, track, contact))
    return {"compile_time_s": float(result.compile_time_s), "status": result.status}


def _cached_compile(name, track, contact, integrator, support, formulation, duration):
    """Compile time [s] of the same programs in a new process (the cache filled)."""
    command = [sys.executable, __file__, "--cached-child", name, track, contact, integrator,
               support, formulation]
    if duration is not None:
        command += ["--duration", str(duration)]
    out = subprocess.run(command, stdout=subprocess.PIPE, text=True, check=True)
    return round(json.loads(out.stdout.strip().splitlines()[-1])["compile_time_s"], 1)


def _outer_force(result):
    return np.nansum(np.asarray(result.wheels.normal_force)[:, 0, OUTER], axis=-1)


def _report(name, scenario, contact, integrator, result, reference):
    wall = float(result.wall_time_s)
    report = {
        "scenario": name, "wheel": scenario.wheel, "contact": contact,
        "integrator": integrator, "status": result.status,
        "compile_time_s": round(float(result.compile_time_s), 1),
        "wall_time_s": round(wall, 1), "simulated_time_s": result.simulated_time_s,
        "real_time_factor": round(result.simulated_time_s / wall, 4),
        "steps_accepted": int(result.accepted_steps),
        "steps_rejected": int(result.rejected_steps),
        "mean_step_ms": round(1e3 * result.simulated_time_s / int(result.accepted_steps), 3),
        "rhs_evaluations": int(result.rhs_evaluations),
        "jacobian_evaluations": int(result.jacobian_evaluations),
        "jacobian_every": scenario.jacobian_every if scenario.integrator == "imex" else None,
        "max_constraint_violation_m": float(np.nanmax(result.constraint_violation)),
        "any_nan_in_valid_outputs": bool(np.any(np.isnan(
            np.asarray(result.wheelset_lateral)[np.asarray(result.valid)]))),
        **_peaks(result),
    }
    if reference is not None:
        valid = np.asarray(result.valid) & np.asarray(reference.valid)
        lateral = [np.asarray(r.wheelset_lateral)[valid, 0] for r in (reference, result)]
        force = [_outer_force(r)[valid] for r in (reference, result)]
        t = np.asarray(result.t)[valid]
        onsets = sorted(set(_flange_onsets(reference, valid)) | set(_flange_onsets(result, valid)))
        calm = np.ones_like(t, dtype=bool)
        for onset in onsets:
            calm &= ~((t > onset - IMPACT[0]) & (t < onset + IMPACT[1]))
        difference = 100 * np.abs(force[1] - force[0]) / np.max(force[0])
        intervals = [_two_patch_intervals(r) for r in (reference, result)]
        report["vs_first"] = {
            "max_leading_lateral_difference_mm": float(1e3 * np.max(np.abs(
                lateral[1] - lateral[0]))),
            "max_outer_normal_force_difference_percent": float(np.max(difference)),
            "outer_flange_onsets_s": onsets,
            "max_outer_normal_force_difference_outside_onsets_percent": float(
                np.max(difference[calm])),
            "outer_max_normal_force_N": [float(np.max(f)) for f in force],
            "leading_two_patch_intervals_s": intervals,
            "max_two_patch_interval_end_difference_s": _interval_difference(*intervals),
        }
    return report


def _peaks(result):
    """The leading wheelset's largest lateral displacement [mm], its outer wheel's
    largest Q [N] and Y/Q, and the largest rail deflections under any wheel [mm]."""
    summary = summarize(result)
    outer = [w for w in summary["wheels"] if w["wheelset"] == 1][OUTER]
    valid = np.asarray(result.valid)
    deflection = np.abs(np.asarray(result.rail_deflection)[valid])
    lateral = summary["wheelsets"][0]["max_lateral_displacement_m"]
    return {"leading_max_lateral_mm": None if lateral is None else 1e3 * lateral,
            "outer_max_Q_N": float(np.nanmax(
                np.asarray(result.wheels.vertical_force)[valid, 0, OUTER])),
            "outer_max_Y_over_Q": outer["max_Y_over_Q"],
            "max_rail_deflection_mm": {"lateral": float(1e3 * np.max(deflection[..., 0])),
                                       "vertical": float(1e3 * np.max(deflection[..., 1]))}}


def _flange_onsets(result, valid):
    """Times [s] at which the leading wheelset's outer wheel comes onto its flange root
    or flange (a patch steeper than ``IMPACT_ANGLE`` appears): impacts."""
    active = np.asarray(result.wheels.active, dtype=bool)[valid, 0, OUTER]
    angle = np.abs(np.asarray(result.wheels.contact_angle))[valid, 0, OUTER]
    flange = np.any(active & (angle > IMPACT_ANGLE), axis=-1)
    t = np.asarray(result.t)[valid]
    return [float(t[k]) for k in np.flatnonzero(flange[1:] & ~flange[:-1]) + 1]


def _two_patch_intervals(result):
    """The leading wheelset's wheels' intervals [s] with two or more patches."""
    wheels = summarize(result)["wheels"]
    return {w["side"]: w["multi_patch_intervals_s"] for w in wheels if w["wheelset"] == 1}


def _interval_difference(first, second):
    """Largest difference [s] of the interval ends, wheel by wheel, when both runs have
    the same number of intervals on each wheel (else None)."""
    ends = []
    for side in first:
        if len(first[side]) != len(second[side]):
            return None
        ends += [abs(a - b) for x, y in zip(first[side], second[side]) for a, b in zip(x, y)]
    return max(ends, default=0.0)


def _save(directory, name, scenario, result, vehicle, params):
    from jaxrail import __version__
    from jaxrail.results import write_results

    directory.mkdir(parents=True, exist_ok=True)
    host = jax.tree.map(np.asarray, result)
    write_atomically(directory / f"{name}.pkl",
                     lambda path: Path(path).write_bytes(pickle.dumps(host)))
    write_results(directory / f"{name}.h5", result, metadata={
        "scenario": name, "description": scenario.description,
        "jaxrail_version": __version__, "body_names": list(vehicle.system.body_names)})
    summary = summarize(result, friction=float(params.contact.friction))
    write_atomically(directory / f"{name}.json",
                     lambda path: Path(path).write_text(json.dumps(summary, indent=2)))


if __name__ == "__main__":
    main()
