"""Summary, HDF5 results file and curve figures, on a small hand-built result (no
simulation: the expected numbers below are worked out by hand from the arrays)."""

import json
import math
import os
import subprocess
import sys

import diffrax
import h5py
import numpy as np
import pytest

from jaxrail.plots.curve import (
    plot_contact_positions,
    plot_derailment_ratio,
    plot_forces,
    plot_lateral_displacements,
)
from jaxrail.results import (
    nadal_limit,
    read_results,
    summarize,
    write_results,
    write_summary,
)
from jaxrail.simulation import SimulationResult, WheelOutputs

T, W, P, N_BODIES = 8, 2, 3, 3
LEFT, RIGHT = 0, 1


def synthetic_result():
    """8 output times 0.0 .. 0.7 s; the run stopped (derailed) after t = 0.6 s, so the
    last row is not valid: its floats are NaN, its time inf (as diffrax leaves it) and,
    as in simulate(), its flags are left unmasked (active, to check they are ignored).

    Leading wheelset, right wheel: patch counts 1 2 2 1 2 1 2 | 2 (invalid), slot 1 at
    contact angles 1.2 (t1, t2), 0.5 (t4), -0.9 (t6). Leading left wheel: never in
    contact, unloaded. Wheelset 2: one tread patch on each wheel throughout."""
    t = np.linspace(0.0, 0.7, T)
    t[-1] = np.inf
    valid = np.array([True] * 7 + [False])
    shape = (T, W, 2, P)
    active = np.zeros(shape, bool)
    angle = np.full(shape, 1.5)  # garbage in inactive slots must be ignored
    normal = np.zeros(shape)
    y_wheel = np.full(shape, -0.07)
    surface = np.zeros(shape, np.int32)
    # leading right wheel: slot 0 tread always, slot 1 at t1, t2, t4, t6 and t7
    active[:, 0, RIGHT, 0] = True
    angle[:, 0, RIGHT, 0] = 0.03
    normal[:, 0, RIGHT, 0] = np.linspace(40e3, 47e3, T)
    y_wheel[:, 0, RIGHT, 0] = 0.004
    for i, a in [(1, 1.2), (2, 1.2), (4, 0.5), (6, -0.9), (7, 1.2)]:
        active[i, 0, RIGHT, 1] = True
        angle[i, 0, RIGHT, 1] = a
        normal[i, 0, RIGHT, 1] = 60e3 + 10e3 * i  # 120 kN at t6 is the valid maximum
        y_wheel[i, 0, RIGHT, 1] = -0.035
        surface[i, 0, RIGHT, 1] = 1
    normal[3, 0, RIGHT, 2] = 9e5  # an inactive slot's value must not count
    # wheelset 2: one patch per wheel
    active[:, 1, :, 0] = True
    angle[:, 1, :, 0] = 0.02
    normal[:, 1, :, 0] = 50e3
    y_wheel[:, 1, :, 0] = 0.001
    # Y on the wheel from the rail, towards its field side (simulate's convention)
    lateral_force = np.zeros((T, W, 2))
    vertical_force = np.zeros((T, W, 2))
    vertical_force[:, 0, RIGHT] = 50e3
    lateral_force[:, 0, RIGHT] = -5e3
    lateral_force[2, 0, RIGHT] = -25e3  # Nadal Y/Q = 0.5, the maximum
    vertical_force[3, 0, RIGHT], lateral_force[3, 0, RIGHT] = 500.0, -400.0  # < 1 kN: skip
    vertical_force[:, 1, :] = 50e3
    lateral_force[:, 1, :] = 1e3  # Y/Q = -0.02
    lateral = np.array([[0.0, 0.0], [-2e-3, 1e-3], [-7e-3, 2e-3], [-5e-3, 2.5e-3],
                        [-3e-3, -3e-3], [1e-3, 0.0], [2e-3, 1e-3], [0.0, 0.0]])

    def floats(x):
        x = np.array(x, dtype=np.float64)
        x[~valid] = np.nan
        return x

    wheels = WheelOutputs(
        active=active, surface=surface, y_wheel=floats(y_wheel), y_rail=floats(0.5 * y_wheel),
        penetration=floats(np.where(active, 1e-4, 0.0)), contact_angle=floats(angle),
        normal_force=floats(normal), creep_force_x=floats(0.1 * normal),
        creep_force_y=floats(-0.05 * normal), creepage_x=floats(np.full(shape, 1e-3)),
        creepage_y=floats(np.full(shape, -2e-3)), spin=floats(np.full(shape, 0.01)),
        semi_axis_a=floats(np.full(shape, 6e-3)), semi_axis_b=floats(np.full(shape, 5e-3)),
        lateral_force=floats(lateral_force), vertical_force=floats(vertical_force))
    # the rails under wheelset 1 on a flexible track: the right one pressed down most at
    # t7, after the run stopped (not counted), and at t6 before it
    deflection = np.zeros((T, W, 2, 2))
    deflection[:, 0, RIGHT, 1] = -7e-4
    deflection[6, 0, RIGHT, 1], deflection[7, 0, RIGHT, 1] = -9e-4, -2e-3
    deflection[:, 0, RIGHT, 0] = 3e-5
    q = np.tile(np.array([1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0]), N_BODIES)[None] \
        + np.arange(T)[:, None] * 1e-3
    q[~valid] = np.inf
    qdot = np.full_like(q, 0.5)
    qdot[~valid] = np.inf
    qddot = np.where(valid[:, None], 0.25, np.nan) + 0.0 * q
    return SimulationResult(
        t=t, q=q, qdot=qdot, qddot=qddot, valid=valid, wheelset_lateral=floats(lateral),
        wheelset_vertical=floats(np.full((T, W), 1e-5)), wheelset_yaw=floats(np.full((T, W), 2e-4)),
        irregularity=floats(np.full((T, W, 4), 1e-3)), rail_deflection=floats(deflection),
        wheels=wheels, constraint_violation=floats(np.full(T, 1e-9)),
        result=diffrax.RESULTS.successful, derailed=np.asarray(True), steps=np.asarray(100),
        accepted_steps=np.asarray(90), rejected_steps=np.asarray(10),
        rhs_evaluations=np.asarray(800), jacobian_evaluations=np.asarray(100),
        wall_time_s=np.asarray(2.0), compile_time_s=np.asarray(np.nan))


@pytest.fixture(scope="module")
def result():
    return synthetic_result()


@pytest.fixture(scope="module")
def summary(result):
    return summarize(result, friction=0.4)


def wheel(summary, wheelset, side):
    (found,) = [w for w in summary["wheels"] if w["wheelset"] == wheelset and w["side"] == side]
    return found


# --- summary -----------------------------------------------------------------------

def test_run_level_values(summary):
    assert summary["status"] == "derailed"
    assert summary["simulated_time_s"] == pytest.approx(0.6, abs=1e-12)
    assert summary["wall_time_s"] == 2.0
    assert summary["compile_time_s"] is None  # NaN in the result
    assert summary["real_time_factor"] == pytest.approx(0.3, rel=1e-12)
    assert summary["steps"] == 100 and summary["rhs_evaluations"] == 800
    assert summary["jacobian_evaluations"] == 100
    assert summary["nadal_limit"] == pytest.approx(1.118384, abs=1e-6)


def test_wheel_order_is_wheelset_then_left_right(summary):
    order = [(w["wheelset"], w["side"]) for w in summary["wheels"]]
    assert order == [(1, "left"), (1, "right"), (2, "left"), (2, "right")]
    assert [w["wheelset"] for w in summary["wheelsets"]] == [1, 2]


def test_multi_patch_intervals_stop_at_the_last_valid_time(summary):
    # counts 1 2 2 1 2 1 2 | 2: runs t1-t2, t4, t6; t7 is after the stop
    got = wheel(summary, 1, "right")["multi_patch_intervals_s"]
    expected = [[0.1, 0.2], [0.4, 0.4], [0.6, 0.6]]
    assert len(got) == len(expected)
    np.testing.assert_allclose(got, expected, atol=1e-12)
    assert wheel(summary, 2, "left")["multi_patch_intervals_s"] == []


def test_tread_and_flange_intervals_need_one_patch_each_side_of_the_threshold(summary):
    # slot 0 on the tread throughout; slot 1 beyond 0.6 rad at t1, t2, t6 (t4: 0.5 rad)
    got = wheel(summary, 1, "right")["tread_and_flange_intervals_s"]
    np.testing.assert_allclose(got, [[0.1, 0.2], [0.6, 0.6]], atol=1e-12)
    assert wheel(summary, 2, "right")["tread_and_flange_intervals_s"] == []


def test_flange_fraction_counts_active_patches_beyond_the_threshold(summary):
    # |angle| > 0.6 at t1, t2 (1.2) and t6 (-0.9), not t4 (0.5): 3 of 7 valid times
    assert wheel(summary, 1, "right")["flange_contact_fraction"] == pytest.approx(3 / 7)
    assert wheel(summary, 2, "right")["flange_contact_fraction"] == 0.0
    assert summarize(synthetic_result(), flange_angle_threshold=0.4)["wheels"][1][
        "flange_contact_fraction"] == pytest.approx(4 / 7)


def test_maxima_ignore_inactive_slots_and_invalid_times(summary):
    right = wheel(summary, 1, "right")
    assert right["max_normal_force_N"] == 120e3  # t6; not 9e5 (inactive), not 130e3 (t7)
    assert right["max_Y_over_Q"] == pytest.approx(0.5, abs=1e-12)  # not 0.8 at Q < 1 kN
    assert wheel(summary, 2, "left")["max_Y_over_Q"] == pytest.approx(-0.02, abs=1e-12)
    left = wheel(summary, 1, "left")
    assert left["max_normal_force_N"] == 0.0 and left["max_Y_over_Q"] is None
    assert summary["wheelsets"][0]["max_lateral_displacement_m"] == pytest.approx(7e-3)
    assert summary["wheelsets"][1]["max_lateral_displacement_m"] == pytest.approx(3e-3)
    assert right["max_rail_deflection_vertical_m"] == pytest.approx(9e-4)  # not t7's 2 mm
    assert right["max_rail_deflection_lateral_m"] == pytest.approx(3e-5)
    assert left["max_rail_deflection_vertical_m"] == 0.0  # a rigid rail's


def test_schema_keys_and_json(summary, tmp_path):
    assert {"status", "simulated_time_s", "wall_time_s", "compile_time_s",
            "real_time_factor", "steps", "rhs_evaluations", "wheels", "wheelsets",
            "nadal_limit", "schema_version"} <= set(summary)
    for w in summary["wheels"]:
        assert set(w) == {"wheelset", "side", "max_normal_force_N", "max_Y_over_Q",
                          "multi_patch_intervals_s", "tread_and_flange_intervals_s",
                          "flange_contact_fraction", "max_rail_deflection_lateral_m",
                          "max_rail_deflection_vertical_m"}
    assert set(summary["wheelsets"][0]) == {"wheelset", "max_lateral_displacement_m"}
    text = json.dumps(summary, allow_nan=False)  # raises on NaN or numpy types
    assert json.loads(text) == summary
    write_summary(tmp_path / "s.json", summary)
    assert json.loads((tmp_path / "s.json").read_text()) == summary


def test_nadal_limit_against_hand_values():
    tan70 = math.tan(math.radians(70.0))
    assert nadal_limit(0.4) == pytest.approx((tan70 - 0.4) / (1 + 0.4 * tan70), rel=1e-14)
    assert nadal_limit(0.0, math.radians(45.0)) == pytest.approx(1.0, rel=1e-14)
    assert nadal_limit(0.3, math.radians(60.0)) == pytest.approx(0.9424, abs=1e-4)


def test_batched_result_is_refused():
    batched = synthetic_result()
    batched = SimulationResult(**{f: getattr(batched, f) for f in batched.__dataclass_fields__}
                               | {"t": np.stack([batched.t, batched.t])})
    with pytest.raises(ValueError, match="result"):
        summarize(batched)


# --- HDF5 results file ---------------------------------------------------------------

BODIES = ["carbody", "bogie", "wheelset"]


@pytest.fixture(scope="module")
def results_file(result, tmp_path_factory):
    path = tmp_path_factory.mktemp("h5") / "run.h5"
    write_results(path, result, metadata={
        "scenario": "paper-curve", "description": "synthetic", "body_names": BODIES,
        "speed_m_s": 18.3, "closed": True, "options": {"rtol": 1e-4}})
    return path


def test_file_opens_with_h5py_alone_and_has_units_everywhere(results_file):
    script = (
        "import sys, h5py\n"
        f"f = h5py.File({str(results_file)!r}, 'r')\n"
        "names = []\n"
        "f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)\n"
        "missing = [n for n in names\n"
        "           if 'units' not in f[n].attrs or 'description' not in f[n].attrs]\n"
        "assert not missing, missing\n"
        "assert 'jaxrail' not in sys.modules\n"
        "print(len(names), f['contact/normal_force'].attrs['units'], f.attrs['scenario'])\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True, cwd=os.path.dirname(results_file))
    assert out.stdout.split() == ["27", "N", "paper-curve"]  # 27 datasets


def test_layout_units_and_attributes(results_file):
    with h5py.File(results_file, "r") as f:
        assert f["time"].attrs["units"] == "s"
        assert f["wheelset/lateral"].attrs["units"] == "m"
        assert f["wheelset/yaw"].attrs["units"] == "rad"
        assert f["contact/creepage_x"].attrs["units"] == "1"
        assert f["contact/spin"].attrs["units"] == "1/m"
        assert f["constraint_violation"].attrs["units"] == "m"
        assert "patch slot" in f["contact/y_wheel"].attrs["description"]
        assert "0 left, 1 right" in f["contact/lateral_force"].attrs["description"]
        assert f["contact/vertical_force"].shape == (T, W, 2)
        assert f["bodies/q"].shape == (T, N_BODIES, 7)
        assert list(f["bodies/q"].attrs["body_names"]) == BODIES
        assert "Euler parameters" in f["bodies/q"].attrs["description"]
        assert f["valid"].dtype == np.uint8 and f["contact/active"].dtype == np.uint8
        a = f.attrs
        assert (a["status"], a["steps"], a["derailed"]) == ("derailed", 100, 1)
        assert a["description"] == "synthetic" and a["speed_m_s"] == 18.3
        assert json.loads(a["options"]) == {"rtol": 1e-4}
        assert a["jaxrail_version"] and a["created"].startswith("20")


def test_values_round_trip(results_file, result):
    data = read_results(results_file)
    valid = np.asarray(result.valid)
    assert data["valid"].dtype == bool and np.array_equal(data["valid"], valid)
    np.testing.assert_array_equal(data["time"][valid], result.t[valid])
    assert np.all(np.isnan(data["time"][~valid]))  # inf left by diffrax -> NaN
    np.testing.assert_array_equal(data["bodies/q"][valid].reshape(7, -1), result.q[valid])
    assert np.all(np.isnan(data["bodies/qdot"][~valid]))
    np.testing.assert_array_equal(data["bodies/qddot"][valid].reshape(7, -1),
                                  result.qddot[valid])
    assert data["units"]["bodies/qddot"].startswith("m/s^2")
    np.testing.assert_array_equal(data["wheelset/lateral"], result.wheelset_lateral)
    for field in ("normal_force", "contact_angle", "y_wheel", "lateral_force", "spin"):
        np.testing.assert_array_equal(data[f"contact/{field}"], getattr(result.wheels, field))
    np.testing.assert_array_equal(data["contact/active"][valid], result.wheels.active[valid])
    assert not data["contact/active"][~valid].any()  # set in the result, masked in the file
    assert np.all(data["contact/surface"][~valid] == -1)
    assert data["units"]["wheelset/yaw"] == "rad" and data["attrs"]["scenario"] == "paper-curve"


def test_failed_write_leaves_previous_file_intact(results_file, result, monkeypatch, tmp_path):
    target = tmp_path / "run.h5"
    target.write_bytes(results_file.read_bytes())
    before = target.read_bytes()
    calls = []
    original = h5py.Group.create_dataset

    def failing(self, *args, **kwargs):
        calls.append(args[0])
        if len(calls) == 5:
            raise OSError("disk full")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(h5py.Group, "create_dataset", failing)
    with pytest.raises(OSError, match="disk full"):
        write_results(target, result, metadata={"scenario": "other"})
    assert target.read_bytes() == before
    calls.clear()
    with pytest.raises(OSError, match="disk full"):
        write_results(tmp_path / "new.h5", result, metadata={})
    assert sorted(os.listdir(tmp_path)) == ["run.h5"]  # no new file, no temporary left


def test_bad_metadata_is_named(result, tmp_path):
    with pytest.raises(ValueError, match="body_names"):
        write_results(tmp_path / "x.h5", result, metadata={"body_names": ["a", "b"]})
    with pytest.raises(TypeError, match="metadata"):
        write_results(tmp_path / "x.h5", result, metadata=[("scenario", "x")])
    assert not os.listdir(tmp_path)


# --- figures ---------------------------------------------------------------------------

@pytest.mark.parametrize("plot", [plot_contact_positions, plot_lateral_displacements,
                                  plot_forces, plot_derailment_ratio])
def test_figures_are_small_pngs(plot, result, tmp_path):
    path = tmp_path / f"{plot.__name__}.png"
    plot({"simplified profile": result, "real profile": result}, path)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert 5_000 < len(data) < 100_000


def test_figure_arguments_are_checked(result, tmp_path):
    with pytest.raises(ValueError, match="results"):
        plot_forces({}, tmp_path / "x.png")
    with pytest.raises(ValueError, match="wheel"):
        plot_contact_positions({"a": result}, tmp_path / "x.png", wheel=2)
    with pytest.raises(ValueError, match="wheelset"):
        plot_derailment_ratio({"a": result}, tmp_path / "x.png", wheelset=W)
    with pytest.raises(ValueError, match="colour_by"):
        plot_contact_positions({"a": result}, tmp_path / "x.png", colour_by="size")
    assert not os.listdir(tmp_path)
