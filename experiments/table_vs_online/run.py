"""Table mode against the paper's search (online mode): the same scenario, the same
solver, both contact models, one process.

Runs a scenario for ``--duration`` seconds with each contact model, prints JSON with the
differences the table must keep small (leading wheelset lateral displacement, the
outer wheel's largest normal force, the largest Y/Q, the outer wheel's multi-patch
intervals) and both runs' wall and compile times, and writes a figure of the two side
by side (lateral displacement and the outer wheel's normal force of the leading
wheelset). Saves both results (pickle) in ``--out`` when given.

Usage: ``python experiments/table_vs_online/run.py paper-curve --duration 8
--figure docs/figures/table_vs_online_real.png``.
"""

import argparse
import json
import pickle
from pathlib import Path

import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.results import derailment_ratio, summarize  # noqa: E402
from jaxrail.scenarios import load_scenario, run_scenario  # noqa: E402

OUTER = 1  # the right wheel is the outer one in the paper's left curve


def _outer_patches(result):
    """Time histories of the leading wheelset's outer wheel: normal force (T,) [N] and
    the number of active patches (T,)."""
    wheels = result.wheels
    force = np.nansum(np.asarray(wheels.normal_force)[:, 0, OUTER], axis=1)
    active = np.asarray(wheels.active)[:, 0, OUTER].sum(axis=1)
    return force, active


def compare(online, table):
    """The differences between two results of the same scenario and output times."""
    valid = np.asarray(online.valid) & np.asarray(table.valid)
    lateral = np.asarray(online.wheelset_lateral)[:, 0], np.asarray(table.wheelset_lateral)[:, 0]
    force = _outer_patches(online)[0], _outer_patches(table)[0]
    ratio = [np.nanmax(np.abs(derailment_ratio(r)[valid])) for r in (online, table)]
    summaries = [summarize(r) for r in (online, table)]
    intervals = [s["wheels"][OUTER]["multi_patch_intervals_s"] for s in summaries]
    difference = np.abs(lateral[0] - lateral[1])
    worst = int(np.argmax(np.where(valid, difference, -1.0)))
    # the largest normal force on any wheel (the sum of its patches)
    largest = [float(np.max(np.nansum(np.asarray(r.wheels.normal_force)[valid], axis=-1)))
               for r in (online, table)]
    return {
        "max_leading_lateral_difference_mm": float(1e3 * difference[worst]),
        "max_leading_lateral_difference_at_s": float(np.asarray(online.t)[worst]),
        "outer_max_normal_force_N": [float(np.max(f[valid])) for f in force],
        "outer_max_normal_force_difference_percent": float(
            100 * (np.max(force[1][valid]) / np.max(force[0][valid]) - 1)),
        "max_normal_force_any_wheel_N": largest,
        "max_normal_force_any_wheel_difference_percent": float(100 * (largest[1] / largest[0] - 1)),
        "max_Y_over_Q": [float(x) for x in ratio],
        "max_Y_over_Q_difference": float(ratio[1] - ratio[0]),
        "outer_multi_patch_intervals_s": intervals,
        "status": [s["status"] for s in summaries],
        "wall_time_s": [s["wall_time_s"] for s in summaries],
        "compile_time_s": [s["compile_time_s"] for s in summaries],
        "steps": [s["steps"] for s in summaries],
        "real_time_factor": [s["real_time_factor"] for s in summaries],
    }


def figure(online, table, path, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for label, result, style in (("online (paper's search)", online, "-"),
                                 ("table", table, "--")):
        t = np.asarray(result.t)
        axes[0].plot(t, 1e3 * np.asarray(result.wheelset_lateral)[:, 0], style, label=label)
        axes[1].plot(t, 1e-3 * _outer_patches(result)[0], style, label=label)
    axes[0].set(xlabel="time [s]", ylabel="leading wheelset lateral [mm]")
    axes[1].set(xlabel="time [s]", ylabel="outer wheel normal force [kN]")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(title)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenario", help="a built-in scenario or a .toml file")
    parser.add_argument("--duration", type=float, default=8.0, help="simulated time [s]")
    parser.add_argument("--figure", help="write the comparison figure (PNG) here")
    parser.add_argument("--out", type=Path, help="save both results (pickle) in this folder")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    results = {mode: run_scenario(scenario, args.duration, contact=mode)[0]
               for mode in ("online", "table")}
    report = {"scenario": scenario.name, "duration_s": args.duration,
              **compare(results["online"], results["table"])}
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        for mode, result in results.items():
            (args.out / f"{scenario.name}_{mode}.pkl").write_bytes(pickle.dumps(result))
    if args.figure:
        figure(results["online"], results["table"], args.figure,
               f"{scenario.name}: table against the paper's search, {args.duration:g} s")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
