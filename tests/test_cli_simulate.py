"""`jaxrail simulate` end to end on the first 0.3 s of the paper's example: a results
file that opens without jaxrail, a JSON summary with the documented schema, figures."""

import json
import subprocess
import sys

import h5py
import numpy as np


def test_simulate_paper_curve_for_a_short_while(tmp_path):
    out, summary, plots = tmp_path / "run.h5", tmp_path / "summary.json", tmp_path / "figures"
    command = [sys.executable, "-m", "jaxrail.cli", "simulate", "paper-curve", "--duration",
               "0.3", "--out", str(out), "--summary", str(summary), "--plots", str(plots),
               "--quiet"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr[-3000:]
    data = json.loads(summary.read_text())
    assert data["status"] == "successful"
    assert data["simulated_time_s"] == 0.3
    assert data["steps"] > 0 and data["rhs_evaluations"] > data["steps"]
    assert data["wall_time_s"] > 0 and data["real_time_factor"] > 0
    assert len(data["wheels"]) == 8 and len(data["wheelsets"]) == 4
    first = data["wheels"][0]
    assert (first["wheelset"], first["side"]) == (1, "left")
    for wheel in data["wheels"]:
        # the first 0.3 s are on straight track: loads about W/8, no flange contact
        assert 40e3 < wheel["max_normal_force_N"] < 120e3
        assert wheel["flange_contact_fraction"] == 0.0
        assert isinstance(wheel["multi_patch_intervals_s"], list)
    assert all(0.0 < w["max_lateral_displacement_m"] <= 2.0e-3 + 1e-9 for w in data["wheelsets"])
    with h5py.File(out, "r") as results:
        time = results["time"][...]
        assert time[0] == 0.0 and time[-1] == 0.3
        assert results["time"].attrs["units"] == "s"
        lateral = results["wheelset/lateral"]
        assert lateral.attrs["units"] == "m" and lateral.shape == (len(time), 4)
        assert np.isclose(lateral[0, 0], 2e-3, atol=1e-6)
        assert results["contact/normal_force"].attrs["units"] == "N"
    for name in ("contact_positions", "lateral_displacements", "forces", "derailment_ratio"):
        assert (plots / f"{name}.png").stat().st_size > 1000
