"""The Monte Carlo table's EN 14363 and EN 12299 columns on hand-built runs (no
simulation): constant wheel forces whose 2 m means are known, a swaying carbody whose
N_MV has a closed form, the same numbers as the assessment of the run's results file,
NaN (and no exception) for records too short, and the same columns in every row."""

import diffrax
import numpy as np
import pytest

from jaxrail.montecarlo import read_table, write_table
from jaxrail.montecarlo.summary import (en12299_columns, en14363_columns, sample_row,
                                        snake)
from jaxrail.results import write_results
from jaxrail.simulation import SimulationResult, WheelOutputs
from jaxrail.standards import en14363
from jaxrail.standards.comfort import comfort_of_file, trailer_floor_points
from jaxrail.standards.from_result import assess_result, comfort_of_result

BODIES = ("carbody", "wheelset_1", "wheelset_2")
Q0, Y_LEFT, Y_RIGHT = 80e3, 4e3, 20e3  # [N]: Nadal Y on each rail, positive outward
SWAY, SWAY_HZ = 0.5, 1.0  # carbody lateral acceleration amplitude [m/s^2] and frequency
WD_AT_1_HZ = 1.011  # ISO 2631-1 Table 3, Wd weighting factor at 1 Hz (its precision)
HUNT_HZ, HUNT_N = 6.0, 3e3  # a Sum Y oscillation for the instability rms


def fake_result(duration=3.0, speed=20.0, rate=50.0, bodies=BODIES, stop=None,
                hunting=False):
    """A run of ``duration`` [s] at ``speed`` [m/s] sampled at ``rate`` [Hz]: every
    wheel carries Q0, the left rails Y_LEFT and the right rails Y_RIGHT (plus a
    HUNT_HZ oscillation of the left ones with ``hunting``), the carbody sways
    laterally. Rows from ``stop`` on were not reached (NaN, time inf)."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    n, n_wheelsets = len(t), sum(b.startswith("wheelset") for b in bodies)
    valid = np.ones(n, bool) if stop is None else np.arange(n) < stop
    q, qdot, qddot = np.zeros((3, n, len(bodies), 7))
    q[:, :, 3] = 1.0  # every body level
    w = 2 * np.pi * SWAY_HZ
    for i, name in enumerate(bodies):
        if name == "carbody":
            q[:, i, 1] = -SWAY / w**2 * np.sin(w * t)
            qdot[:, i, 1] = -SWAY / w * np.cos(w * t)
            qddot[:, i, 1] = SWAY * np.sin(w * t)
        q[:, i, 0], qdot[:, i, 0] = speed * t, speed
    y = np.zeros((n, n_wheelsets, 2))
    y[:, :, 0], y[:, :, 1] = Y_LEFT, Y_RIGHT
    if hunting:
        y[:, :, 0] += HUNT_N * np.sin(2 * np.pi * HUNT_HZ * t)[:, None]
    vertical = np.full((n, n_wheelsets, 2), Q0)
    shape, patch = (n, n_wheelsets, 2, 1), np.zeros((n, n_wheelsets, 2, 1))

    def floats(x):
        x = np.array(x, dtype=np.float64)
        x[~valid] = np.nan
        return x

    wheels = WheelOutputs(
        active=np.ones(shape, bool), surface=np.zeros(shape, np.int32),
        y_wheel=floats(patch), y_rail=floats(patch), penetration=floats(patch + 1e-4),
        contact_angle=floats(patch + 0.02), normal_force=floats(patch + Q0),
        creep_force_x=floats(patch), creep_force_y=floats(patch),
        creepage_x=floats(patch), creepage_y=floats(patch), spin=floats(patch),
        semi_axis_a=floats(patch + 6e-3), semi_axis_b=floats(patch + 5e-3),
        lateral_force=floats(-y), vertical_force=floats(vertical))  # on the wheel: -Y
    states = [x.reshape(n, -1) for x in (q, qdot, qddot)]
    for x in states:
        x[~valid] = np.inf
    t = np.where(valid, t, np.inf)
    zeros = np.zeros((n, n_wheelsets))
    return SimulationResult(
        t=t, q=states[0], qdot=states[1], qddot=np.where(valid[:, None], states[2], np.nan),
        valid=valid, wheelset_lateral=floats(zeros), wheelset_vertical=floats(zeros),
        wheelset_yaw=floats(zeros), irregularity=floats(np.zeros((n, n_wheelsets, 4))),
        rail_deflection=floats(np.zeros((n, n_wheelsets, 2, 2))), wheels=wheels,
        constraint_violation=floats(np.zeros(n)), result=diffrax.RESULTS.successful,
        derailed=np.asarray(stop is not None), steps=np.asarray(10),
        accepted_steps=np.asarray(10), rejected_steps=np.asarray(0),
        rhs_evaluations=np.asarray(40), jacobian_evaluations=np.asarray(1),
        wall_time_s=np.asarray(1.0), compile_time_s=np.asarray(np.nan))


def row_of(result, speed=20.0, bodies=BODIES):
    return sample_row(result, 0.4, speed, bodies)


def standards(row):
    return {k: v for k, v in row.items() if k.startswith(("en14363", "en12299"))}


def test_constant_forces_give_their_2_m_means_and_ratios():
    row = row_of(fake_result())
    prudhomme = 10e3 + 2 * Q0 / 3  # alpha = 1, passenger
    q_lim = min(90e3 + Q0, 200e3)  # 72 km/h: the 200 kN cap
    for k in (1, 2):
        for side, y in (("left", Y_LEFT), ("right", Y_RIGHT)):
            name = f"en14363_y_over_q_2m_wheelset_{k}_{side}"
            assert row[name] == pytest.approx(y / Q0, rel=1e-9)
            assert row[f"{name}_ratio"] == pytest.approx(y / Q0 / 0.8, rel=1e-9)
            assert row[f"en14363_qmax_wheelset_{k}_{side}_N"] == pytest.approx(Q0, rel=1e-9)
            assert row[f"en14363_qmax_wheelset_{k}_{side}_ratio"] == pytest.approx(
                Q0 / q_lim, rel=1e-9)
        assert row[f"en14363_sum_y_2m_wheelset_{k}_N"] == pytest.approx(
            Y_RIGHT - Y_LEFT, rel=1e-9)
        assert row[f"en14363_sum_y_2m_wheelset_{k}_ratio"] == pytest.approx(
            (Y_RIGHT - Y_LEFT) / prudhomme, rel=1e-9)
        assert np.isnan(row[f"en14363_sum_y_rms_wheelset_{k}_N"])  # 60 m < 100 m
    assert row["en14363_passed"] == 1.0
    # Y/Q 0.3125, Sum Y 0.253, Qmax 0.471 of their limits
    assert row["en14363_max_ratio"] == pytest.approx(Q0 / q_lim, rel=1e-9)


def test_columns_equal_assess_channels_on_the_same_channels():
    speed, result = 40.0, fake_result(duration=3.0, speed=40.0, hunting=True)  # 120 m
    row = row_of(result, speed)
    t = np.arange(151) / 50.0
    y = -np.asarray(result.wheels.lateral_force)
    q = np.asarray(result.wheels.vertical_force)
    direct = en14363.assess_channels(t, speed * t, y, q, static_wheel_load=Q0,
                                     max_speed_kmh=3.6 * speed)
    quantities = {c["quantity"] for c in direct["checks"]}
    assert "(Sum Y)rms" in quantities
    for check in direct["checks"]:
        if check["quantity"] in ("Yqst", "Qqst"):  # curves only: not in the table
            continue
        base = f"en14363_{snake(check['quantity'])}_{snake(check['where'])}"
        value = base + ("_N" if check["units"] == "N" else "")
        assert row[value] == pytest.approx(check["value"], rel=1e-9, abs=1e-9)
        assert row[base + "_ratio"] == pytest.approx(check["ratio"], rel=1e-9, abs=1e-12)
    assert row["en14363_sum_y_rms_wheelset_1_N"] > 0.5 * HUNT_N / np.sqrt(2)
    assert row["en14363_passed"] == float(direct["passed"])


def test_every_en14363_column_has_a_value_on_a_long_record():
    row = row_of(fake_result(duration=3.0, speed=40.0, hunting=True), 40.0)
    assert all(np.isfinite(row[k]) for k in en14363_columns(2))


def test_swaying_carbody_has_the_closed_form_mean_comfort():
    row = row_of(fake_result(duration=12.0, speed=20.0))
    names = [f"en12299_nmv_{snake(p)}" for p in trailer_floor_points()]
    assert names == ["en12299_nmv_over_leading_bogie", "en12299_nmv_centre",
                     "en12299_nmv_over_trailing_bogie"]
    for name in names:  # a pure translation: every point alike, 2 blocks of 5 s
        assert row[name] == pytest.approx(6 * SWAY * WD_AT_1_HZ / np.sqrt(2), rel=2e-3)


def test_in_memory_assessment_equals_the_results_files(tmp_path):
    result = fake_result(duration=12.0, speed=20.0, stop=500, hunting=True)
    path = tmp_path / "run.h5"
    write_results(path, result, metadata={"body_names": list(BODIES)})
    options = dict(static_wheel_load=Q0, max_speed_kmh=72.0)
    from_file, in_memory = en14363.assess_file(path, **options), assess_result(
        result, BODIES, **options)
    assert in_memory["run"]["rows_used"] == from_file["file"]["rows_used"] == 500
    assert in_memory["checks"] == from_file["checks"]
    assert in_memory["notes"] == from_file["notes"]
    assert comfort_of_result(result, BODIES) == comfort_of_file(path)


def test_short_records_give_nan_columns_and_no_exception():
    cases = {"1 m travelled": fake_result(duration=1.0, speed=1.0),
             "stopped after 1 m": fake_result(duration=3.0, speed=20.0, stop=3),
             "one row": fake_result(duration=3.0, speed=20.0, stop=1),
             "nothing reached": fake_result(duration=3.0, speed=20.0, stop=0),
             "20 Hz outputs": fake_result(duration=3.0, speed=20.0, rate=20.0)}
    for what, result in cases.items():
        row = standards(row_of(result))
        assert list(row) == en14363_columns(2) + en12299_columns(BODIES), what
        assert all(np.isnan(v) for v in row.values()), what


def test_an_early_stop_is_assessed_on_the_rows_before_it():
    row = row_of(fake_result(duration=3.0, speed=20.0, stop=20))  # 7.6 m
    assert row["en14363_qmax_wheelset_1_left_N"] == pytest.approx(Q0, rel=1e-9)
    assert np.isnan(row["en12299_nmv_centre"])  # 0.4 s: no 5 s block


def test_every_row_of_a_study_has_the_same_columns(tmp_path):
    results = [fake_result(duration=12.0, speed=20.0), fake_result(duration=1.0, speed=1.0),
               fake_result(duration=3.0, speed=40.0, stop=100, hunting=True)]
    rows = [row_of(r) for r in results]
    assert all(list(r) == list(rows[0]) for r in rows)
    table = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    write_table(tmp_path / "table.csv", table)
    back = read_table(tmp_path / "table.csv")
    assert list(back) == list(table)
    assert np.array_equal(back["en14363_max_ratio"], table["en14363_max_ratio"],
                          equal_nan=True)


def test_a_vehicle_without_carbody_has_no_comfort_columns():
    row = row_of(fake_result(bodies=("wheelset",)), bodies=("wheelset",))
    assert not any(k.startswith("en12299") for k in row)
    assert row["en14363_y_over_q_2m_wheelset_1_right"] == pytest.approx(Y_RIGHT / Q0)
