"""The ``jaxrail geometry`` command, run in-process: JSON schema, CSV, plot, errors.

All runs use the same profiles and shift count, so the analysis compiles once."""

import csv
import io
import json
import math

import numpy as np
import pytest

from jaxrail.cli import main

BASE = ["geometry", "--wheel", "s1002", "--rail", "uic60", "--inclination", "1:40",
        "--gauge", "1435", "--shift-from", "-10", "--shift-to", "10", "--shift-step", "0.5"]
PATCH_KEYS = {"y_track_mm", "y_wheel_mm", "rolling_radius_mm", "contact_angle_rad",
              "penetration_mm"}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """JSON to a file with a plot, and CSV to stdout (both from one compilation)."""
    directory = tmp_path_factory.mktemp("geometry")
    out, plot = directory / "geometry.json", directory / "geometry.png"
    assert main(BASE + ["--out", str(out), "--plot", str(plot)]) == 0
    return json.loads(out.read_text()), plot


def test_json_schema(run):
    report, _ = run
    assert set(report) >= {"settings", "rows", "conicity"}
    settings = report["settings"]
    assert settings["wheel"] == "s1002" and settings["rail"] == "uic60"
    assert settings["inclination"] == "1:40" and settings["gauge_mm"] == 1435.0
    assert settings["yaw_per_shift"] == 0.0
    rows = report["rows"]
    assert [row["shift_mm"] for row in rows] == [k / 2 for k in range(-20, 21)]
    for row in rows:
        assert isinstance(row["roll_rad"], float) and isinstance(row["delta_r_mm"], float)
        for side in ("left", "right"):
            assert 1 <= len(row[side]) <= 3
            for patch in row[side]:
                assert set(patch) == PATCH_KEYS
                assert all(isinstance(v, float) and math.isfinite(v) for v in patch.values())
                # mm, not m: rolling radius near 460 mm, contact on the rail head
                assert 450.0 < patch["rolling_radius_mm"] < 490.0  # flange up to ~483
                assert 0.0 < patch["penetration_mm"] < 1e-2
                sign = 1.0 if side == "left" else -1.0
                assert 700.0 < sign * patch["y_track_mm"] < 800.0
                assert -60.0 < patch["y_wheel_mm"] < 60.0


def test_json_values(run):
    """dr is antisymmetric over a symmetric range; a left shift makes the left wheel
    larger (dr > 0); dr equals the difference of the main patches' radii; a centred
    wheelset touches near the taping line (y_wheel within a few mm)."""
    rows = run[0]["rows"]
    delta_r = np.array([row["delta_r_mm"] for row in rows])
    np.testing.assert_allclose(delta_r, -delta_r[::-1], atol=1e-7)
    assert delta_r[20] == pytest.approx(0.0, abs=1e-7)
    assert delta_r[21] > 0.1 and delta_r[22] > delta_r[21]
    roll = np.array([row["roll_rad"] for row in rows])
    np.testing.assert_allclose(roll, -roll[::-1], atol=1e-10)
    for row in rows:
        main_radius = [max(row[s], key=lambda p: p["penetration_mm"])["rolling_radius_mm"]
                       for s in ("left", "right")]
        assert row["delta_r_mm"] == pytest.approx(main_radius[0] - main_radius[1], abs=1e-9)
    centred = max(rows[20]["left"], key=lambda p: p["penetration_mm"])
    assert abs(centred["y_wheel_mm"]) < 10.0


def test_json_conicity(run):
    """All amplitudes 1..6 mm are covered by -10..10 mm; the values are those of
    equivalent_conicity on the reported dr, in the usual range for S1002/UIC60 1:40."""
    from jaxrail.geometry import equivalent_conicity

    report = run[0]
    entries = report["conicity"]
    assert [c["amplitude_mm"] for c in entries] == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    assert all(isinstance(c["tan_gamma_e"], float) for c in entries)
    shifts = 1e-3 * np.array([row["shift_mm"] for row in report["rows"]])
    delta_r = 1e-3 * np.array([row["delta_r_mm"] for row in report["rows"]])
    expected = equivalent_conicity(shifts, delta_r, 1e-3 * np.arange(1.0, 7.0))
    np.testing.assert_allclose([c["tan_gamma_e"] for c in entries], expected, rtol=1e-6)
    assert 0.1 < entries[2]["tan_gamma_e"] < 0.3


def test_csv_and_plot(run, capsys):
    _, plot = run
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert main(BASE + ["--format", "csv"]) == 0
    lines = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert lines[0] == ["shift_mm", "side", "patch", "y_track_mm", "y_wheel_mm",
                        "rolling_radius_mm", "contact_angle_rad", "penetration_mm",
                        "roll_rad", "delta_r_mm", "converged"]
    report = run[0]
    assert len(lines) - 1 == sum(len(r["left"]) + len(r["right"]) for r in report["rows"])
    first = lines[1]
    assert float(first[0]) == -10.0 and first[1] == "left" and first[2] == "0"
    assert float(first[3]) == report["rows"][0]["left"][0]["y_track_mm"]
    assert first[10] == "true"


@pytest.mark.parametrize("change, option", [
    (["--wheel", "s1003"], "--wheel"),
    (["--wheel", "uic60"], "--wheel"),
    (["--rail", "s1002"], "--rail"),
    (["--inclination", "1:30"], "--inclination"),
    (["--shift-step", "0"], "--shift-step"),
    (["--shift-step", "-1"], "--shift-step"),
    (["--shift-from", "2", "--shift-to", "2"], "--shift-from"),
    (["--shift-from", "11"], "--shift-from"),
    (["--gauge", "-1435"], "--gauge"),
])
def test_bad_input(change, option, capsys, tmp_path):
    out = tmp_path / "never.json"
    assert main(BASE + change + ["--out", str(out)]) == 2
    assert option in capsys.readouterr().err
    assert not out.exists()
