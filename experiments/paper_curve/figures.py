"""The paper's example: figures and numbers for docs/paper-curve.md from the two 41 s
runs kept by ``python benchmarks/paper_curve.py --save DIR``.

Writes docs/figures/paper_curve_*.png (simplified and real profiles side by side) and
prints JSON: per profile kind, the multi-patch intervals of the outer (right) wheel of
the leading wheelset, the time it spends with several patches and in flange contact
while the leading wheelset is in the full curve, and the summary's extreme values.
Usage: ``python experiments/paper_curve/figures.py DIR``.
"""

import argparse
import json
import pickle
from pathlib import Path

import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.plots import curve  # noqa: E402
from jaxrail.results import summarize  # noqa: E402

FIGURES = Path(__file__).resolve().parents[2] / "docs" / "figures"
KINDS = {"simplified profile": "paper-curve-simplified", "real profile": "paper-curve"}
FULL_CURVE = (5.1, 37.1)  # [s] the leading wheelset in the arc (tests/test_scenarios.py)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory", type=Path)
    args = parser.parse_args()
    results = {label: pickle.loads((args.directory / f"{name}.pkl").read_bytes())
               for label, name in KINDS.items()}
    curve.plot_contact_positions(results, FIGURES / "paper_curve_contact_positions.png")
    curve.plot_lateral_displacements(results, FIGURES / "paper_curve_lateral.png")
    curve.plot_forces(results, FIGURES / "paper_curve_forces.png")
    curve.plot_derailment_ratio(results, FIGURES / "paper_curve_derailment_ratio.png")
    report = {}
    for label, result in results.items():
        summary = summarize(result)  # friction 0.4, as in the scenarios
        valid = np.asarray(result.valid)
        t = np.asarray(result.t)
        in_curve = valid & (t >= FULL_CURVE[0]) & (t <= FULL_CURVE[1])
        active = np.asarray(result.wheels.active)[:, 0, 1]  # leading wheelset, right wheel
        angle = np.abs(np.asarray(result.wheels.contact_angle)[:, 0, 1])
        several = active.sum(axis=1) >= 2
        flange = np.any(active & (angle > 0.6), axis=1)
        tread_and_flange = flange & np.any(active & (angle <= 0.6), axis=1)
        outer = summary["wheels"][1]
        report[label] = {
            "status": summary["status"], "simulated_time_s": summary["simulated_time_s"],
            "outer_wheel_multi_patch_intervals_s": outer["multi_patch_intervals_s"],
            "outer_wheel_multi_patch_fraction_in_full_curve": float(several[in_curve].mean()),
            "outer_wheel_flange_fraction_in_full_curve": float(flange[in_curve].mean()),
            "outer_wheel_tread_and_flange_intervals_s": outer["tread_and_flange_intervals_s"],
            "outer_wheel_tread_and_flange_fraction_in_full_curve": float(
                tread_and_flange[in_curve].mean()),
            "outer_wheel_max_Y_over_Q": outer["max_Y_over_Q"],
            "outer_wheel_max_normal_force_N": outer["max_normal_force_N"],
            "leading_wheelset_max_lateral_m": summary["wheelsets"][0]["max_lateral_displacement_m"],
            "mean_leading_lateral_in_full_curve_mm": float(
                1e3 * np.mean(np.asarray(result.wheelset_lateral)[in_curve, 0])),
            # steadiness: a chattering wheelset scatters and loses its outer wheel's contact
            "std_leading_lateral_in_full_curve_mm": float(
                1e3 * np.std(np.asarray(result.wheelset_lateral)[in_curve, 0])),
            "outer_wheel_unloaded_fraction_in_full_curve": float((~active.any(axis=1))[in_curve].mean()),
            "outer_wheel_contact_angle_deg_5_50_95_percent_in_full_curve": [
                round(float(v), 1) for v in np.percentile(
                    np.degrees(angle[in_curve][active[in_curve]]), [5, 50, 95])],
            "y_wheel_of_outer_patches_in_full_curve_mm": sorted({
                round(float(1e3 * y), 1) for y in np.asarray(
                    result.wheels.y_wheel)[:, 0, 1][in_curve & valid][active[in_curve & valid]]
            })[:: max(1, int(active[in_curve].sum()) // 40)],
        }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
