"""The 11-body trailer: parameter file, topology, and the first second of the paper's
example (2 mm misalignment, still on the straight) run by `jaxrail simulate`: the
command's results file, summary and figures, and the physics in that file (static
loads, suspension deflections, the misalignment decaying, a derailment restart), and
IMEX against Tsit5 on the first 0.4 s.

One run for the module: the command is called in-process, and the derailment restart
and the IMEX run of the comparison reuse its compiled programs (same vehicle structure,
track and options); the Tsit5 run is the module's one other trailer program. The static
loads are computed here by hand from the Manchester benchmark masses of
shared/reference/vehicle.md, not from jaxrail."""

import dataclasses
import json
import re
from pathlib import Path

import h5py
import jax
import numpy as np
import pytest

from jaxrail.cli import main
from jaxrail.multibody.forces import element_deformation
from jaxrail.results import read_results
from jaxrail.scenarios import load_scenario
from jaxrail.simulation import DerailmentLimits, simulate
from jaxrail.vehicles import read_vehicle_data, trailer, trailer_values
from jaxrail.vehicles.parameters import set_values_and_track

G = 9.81
CARBODY, BOGIE, UNSPRUNG = 32000.0, 2615.0, 1813.0  # [kg], reference [V-src]
WEIGHT = (CARBODY + 2 * BOGIE + 4 * UNSPRUNG) * G
PRIMARY_KZ, SECONDARY_KZ = 1.22e6, 430e3  # [N/m] per element [V-src]


def test_every_value_has_a_source_and_tag():
    entries = read_vehicle_data()
    assert len(entries) == len(trailer_values())  # nothing dropped
    for key, entry in entries.items():
        assert entry["source"].strip() and entry["unit"].strip(), key
    checked = {k: e["value"] for k, e in entries.items() if e["tag"] == "V-src"}
    assert checked["carbody.mass"] == CARBODY and checked["bogie.mass"] == BOGIE
    assert checked["primary.vertical_stiffness"] == PRIMARY_KZ
    assert checked["secondary.vertical_stiffness"] == SECONDARY_KZ
    values = trailer_values()
    assert values["wheelset.mass"] + values["axlebox.mass"] == UNSPRUNG


def test_unknown_override_is_named():
    with pytest.raises(ValueError, match="carbody.mas"):
        trailer_values(carbody__mas=1.0)


def test_topology_is_the_papers_11_bodies():
    vehicle, params = trailer()
    names = vehicle.system.body_names
    assert len(names) == 11
    assert sum(n.startswith("wheelset") for n in names) == 4
    assert sum(n.startswith("axlebox") for n in names) == 4
    assert sum(n.startswith("bogie") for n in names) == 2
    # 11 normalisations + 4 revolute joints x 5 equations
    assert vehicle.system.n_constraints == 11 + 4 * 5
    assert params.system.forces["bushing"].stiffness.shape == (12, 6)
    assert [names[i] for i in vehicle.wheelsets] == [f"wheelset_{k}" for k in range(1, 5)]


# The paper's example for its first second: the leading wheelset starts 27.6 m into the
# track and runs 18.3 m, short of the transition at 50 m.
SCENARIO, DURATION = "paper-curve", 1.0
COMPARED = 0.4  # [s] of IMEX against Tsit5: the leading wheelset reaches 34.9 m
# its run and the README example's (the same program, run again) at LLVM level 1
pytestmark = pytest.mark.usefixtures("integrations_at_level_1")


@pytest.fixture(scope="module")
def command_run(tmp_path_factory, integrations_at_level_1):
    """`jaxrail simulate` on the first second: (directory, exit code, results file read
    back, summary)."""
    where = tmp_path_factory.mktemp("paper-curve-start")
    code = main(["simulate", SCENARIO, "--duration", str(DURATION),
                 "--out", str(where / "run.h5"), "--summary", str(where / "summary.json"),
                 "--plots", str(where / "figures"), "--quiet"])
    return where, code, read_results(where / "run.h5"), json.loads(
        (where / "summary.json").read_text())


def test_command_writes_results_summary_and_figures(command_run):
    """A results file that opens without jaxrail, a JSON summary with the documented
    schema, figures."""
    where, code, run, data = command_run
    assert code == 0
    assert data["status"] == "successful"
    assert data["simulated_time_s"] == DURATION
    assert data["steps"] > 0 and data["rhs_evaluations"] > data["steps"]
    assert data["wall_time_s"] > 0 and data["real_time_factor"] > 0
    assert len(data["wheels"]) == 8 and len(data["wheelsets"]) == 4
    first = data["wheels"][0]
    assert (first["wheelset"], first["side"]) == (1, "left")
    for wheel in data["wheels"]:
        # still on straight track: loads about W/8, no flange contact
        assert 40e3 < wheel["max_normal_force_N"] < 120e3
        assert wheel["flange_contact_fraction"] == 0.0
        assert isinstance(wheel["multi_patch_intervals_s"], list)
    assert all(0.0 < w["max_lateral_displacement_m"] <= 2.0e-3 + 1e-9 for w in data["wheelsets"])
    with h5py.File(where / "run.h5", "r") as results:
        time = results["time"][...]
        assert time[0] == 0.0 and time[-1] == DURATION
        assert results["time"].attrs["units"] == "s"
        lateral = results["wheelset/lateral"]
        assert lateral.attrs["units"] == "m" and lateral.shape == (len(time), 4)
        assert results["contact/normal_force"].attrs["units"] == "N"
    for name in ("contact_positions", "lateral_displacements", "forces", "derailment_ratio"):
        assert (where / "figures" / f"{name}.png").stat().st_size > 1000


def test_run_with_misalignment_is_successful(command_run):
    _, _, run, _ = command_run
    assert bool(np.all(run["valid"]))
    for name in ("bodies/q", "bodies/qdot", "contact/normal_force", "contact/vertical_force"):
        assert np.all(np.isfinite(run[name])), name
    assert float(np.max(run["constraint_violation"])) < 1e-7  # [m], rtol 1e-4
    lateral = run["wheelset/lateral"]
    assert np.allclose(lateral[0], 2e-3, atol=1e-6)
    assert np.max(np.abs(lateral[-1])) < 2e-3  # gravitational stiffness pulls it back


def test_wheel_loads_are_weight_over_8(command_run):
    _, _, run, _ = command_run
    vertical = run["contact/vertical_force"]  # (T, 4 wheelsets, 2 wheels)
    # the start: every wheel carries W/8 although the vehicle is 2 mm off centre
    assert np.allclose(vertical[0], WEIGHT / 8, rtol=1e-3)
    assert np.allclose(vertical[-1], WEIGHT / 8, rtol=0.01)
    assert abs(vertical[-1].sum() / WEIGHT - 1.0) < 2e-3


def test_suspension_carries_the_static_loads(command_run):
    _, _, run, _ = command_run
    vehicle, params, _ = load_scenario(SCENARIO).build()
    q = run["bodies/q"][-1]  # (bodies, 7)
    bushing = params.system.forces["bushing"]
    group = next(g for g in vehicle.system.force_groups if g.kind == "bushing")
    loads = {"primary": (CARBODY + 2 * BOGIE) * G / 8, "secondary": CARBODY * G / 4}
    stiffness = {"primary": PRIMARY_KZ, "secondary": SECONDARY_KZ}
    for k, name in enumerate(group.names):
        element = jax.tree.map(lambda x: x[k], bushing)
        s = element_deformation("bushing", q[group.body_i[k]], q[group.body_j[k]], element)
        force = np.asarray(element.stiffness * s + element.preload)
        kind = name.split("_")[0]
        assert abs(-force[2] / loads[kind] - 1.0) < 0.01, name
        # static deflection implied by the parameter file: load / k
        deflection = -float(element.preload[2]) / float(element.stiffness[2]) - float(s[2])
        assert abs(deflection / (loads[kind] / stiffness[kind]) - 1.0) < 0.01, name
    # the carbody stays where the equilibrium put it
    assert np.max(np.abs(run["bodies/qdot"][:, 0, 2])) < 2e-3


def test_a_derailment_stops_the_run_and_keeps_the_results_so_far(command_run):
    _, _, first, _ = command_run
    # Restart from the run's state when every wheelset is within 0.9 mm of the
    # centreline, with a lateral limit of 0.9 mm: the swing that follows (to 1.1 mm on
    # the other side) must stop the run.
    limit = 0.9e-3
    lateral = np.max(np.abs(first["wheelset/lateral"]), axis=1)  # (T,)
    start = int(np.argmax(lateral < limit))
    assert 0 < start and limit < np.max(lateral[start:])
    scenario = load_scenario(SCENARIO)
    vehicle, params, track = scenario.build()
    restart = (first["bodies/q"][start].reshape(-1), first["bodies/qdot"][start].reshape(-1))
    result = simulate(vehicle, params, track, DURATION, scenario.speed, scenario.misalignment,
                      options=scenario.solver_options(DURATION),
                      limits=DerailmentLimits(lateral=limit), initial=restart)
    assert float(result.compile_time_s) == 0.0  # new limits and start: the command's program
    assert result.status == "derailed"
    valid = np.asarray(result.valid)
    stop = int(np.argmin(valid))
    assert stop >= 1 and not np.any(valid[stop:])
    # The results so far follow the first run (shifted by the restart time) to about the
    # solver tolerance, and the run stopped where the first one crossed the limit. The
    # event is checked at the end of each step, so an output inside the step that crossed
    # may lie beyond the limit by what the wheelset moves in one step.
    tolerance = 2e-6  # [m]
    assert np.allclose(result.wheelset_lateral[:stop],
                       first["wheelset/lateral"][start:start + stop], atol=tolerance)
    assert np.max(np.abs(np.asarray(result.wheelset_lateral[:stop]))) <= limit + tolerance
    assert np.max(lateral[start:start + stop + 1]) > limit - tolerance
    assert np.all(np.isnan(np.asarray(result.wheels.normal_force[stop:])))


def test_imex_follows_tsit5_on_the_trailer(command_run):
    """The first 0.4 s from the paper's 2 mm misalignment, on the first straight: IMEX
    (steps of about 1 ms, a new Jacobian every 8 accepted steps) against Tsit5 (about
    0.35 ms), lateral displacements within 0.05 mm and wheel loads within 2 %. The IMEX
    run has the command's options, so it takes the command's programs (rest pose and
    run); the Tsit5 run differs in the integrator only, one new program. Both keep the
    command's 51 outputs (static), here every 8 ms: coarser than the 401 (every 1 ms)
    this comparison had when it ran on the ``straight`` scenario with its own programs;
    the bounds are the same."""
    scenario = load_scenario(SCENARIO)
    vehicle, params, track = scenario.build()
    options = scenario.solver_options(DURATION)
    assert options.integrator == "imex"  # the scenario's, as the command ran it
    imex = simulate(vehicle, params, track, COMPARED, scenario.speed, scenario.misalignment,
                    options=options)
    assert float(imex.compile_time_s) == 0.0  # the command's programs
    reference = simulate(vehicle, params, track, COMPARED, scenario.speed,
                         scenario.misalignment,
                         options=dataclasses.replace(options, integrator="tsit5"))
    assert imex.status == "successful" == reference.status
    lateral = np.abs(np.asarray(imex.wheelset_lateral) - np.asarray(reference.wheelset_lateral))
    assert np.max(lateral) < 5e-5
    loads = [np.nansum(np.asarray(r.wheels.normal_force), axis=-1) for r in (reference, imex)]
    assert np.max(np.abs(loads[1] - loads[0])) < 0.02 * np.max(loads[0])
    assert int(imex.accepted_steps) < 0.5 * int(reference.accepted_steps)
    # the evaluations each run reports (counted: tests/multibody/test_evaluations.py):
    # a Jacobian every 8 accepted steps, again at each rejected attempt of such a step
    assert int(imex.rhs_evaluations) == 8 * int(imex.steps)
    assert (int(imex.accepted_steps) / 8 <= int(imex.jacobian_evaluations)
            <= int(imex.accepted_steps) / 8 + 1 + int(imex.rejected_steps))
    assert int(reference.rhs_evaluations) == 6 * int(reference.steps) + 1


def test_gauge_and_wheelbase_change_without_recompiling(command_run):
    """The gauge (the track's) and the wheelbase (the vehicle's) are numbers: a run with
    others takes the command's program, and its wheelsets sit where the new wheelbase
    puts them."""
    scenario = load_scenario(SCENARIO)
    vehicle, params, track = scenario.build()
    changed, moved = set_values_and_track(vehicle, params, track, ("track_gauge", "wheelbase"),
                                          np.array([1.440, 2.8]))
    result = simulate(vehicle, changed, moved, 0.05, scenario.speed, scenario.misalignment,
                      options=scenario.solver_options(DURATION))
    assert float(result.compile_time_s) == 0.0
    assert result.status == "successful"
    x = np.asarray(result.q[0]).reshape(-1, 7)[np.asarray(vehicle.wheelsets), 0]
    assert np.allclose(-np.diff(x), [2.8, 19.0 - 2.8, 2.8], atol=1e-6)


def test_readme_simulation_example_runs(command_run, capsys):
    """The README's first Python example, as written, in this process: it asks for the
    programs of ``command_run`` (the same scenario, duration and options), so it
    compiles nothing more."""
    readme = Path(__file__).parents[2] / "README.md"
    example = re.findall(r"```python\n(.*?)```", readme.read_text(), re.S)[0]
    capsys.readouterr()
    exec(compile(example, "README.md", "exec"), {})
    assert capsys.readouterr().out.startswith("successful 1.0")


def test_outputs_hold_the_accelerations_an_accelerometer_reads(command_run):
    """bodies/qddot against central differences of bodies/qdot for the carbody (smooth
    above its suspension), and the carbody floor's vertical reading, +g on average."""
    from jaxrail.standards.floor import floor_accelerations

    _, _, run, _ = command_run
    t, q, qdot, qddot = (run[k] for k in ("time", "bodies/q", "bodies/qdot", "bodies/qddot"))
    assert np.all(np.isfinite(qddot))
    carbody = 0  # the trailer's body order: carbody first
    central = (qdot[2:, carbody, :3] - qdot[:-2, carbody, :3]) / (t[2:] - t[:-2])[:, None]
    np.testing.assert_allclose(qddot[1:-1, carbody, :3], central, atol=0.02)
    vertical = floor_accelerations(q, qdot, qddot, carbody, (0.0, 0.0, -0.8))[:, 2]
    assert np.mean(vertical) == pytest.approx(9.81, rel=2e-3)
