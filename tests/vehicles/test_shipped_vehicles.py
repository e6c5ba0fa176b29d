"""The vehicles shipped as files (issue 52, item 3): the complete Manchester benchmark
coach (``coach``) and the two-axle freight wagon with friction damping (``wagon``).

Each builds from its file with every number sourced and tagged, has the element kinds
its suspension needs, stands at rest on straight track (the static equilibrium of
:func:`jaxrail.vehicles.initial_state`: wheel loads summing to the weight, left equal
to right, no body accelerating) and runs 0.2 s of its scenario. Two programs per
vehicle, the run's (rest pose and integration), serve both: the rest is checked with
them on the scenario's track made ideal.
"""

import tomllib

import diffrax
import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.compilation import compile_program
from jaxrail.multibody.anti_roll_bar import roll_stiffness
from jaxrail.scenarios import BUILTIN, load_scenario, run_scenario
from jaxrail.simulation import simulate
from jaxrail.vehicles import initial_state, vehicle_from_file, vehicle_names
from jaxrail.vehicles import element_kinds as ek
from jaxrail.vehicles.quantities import TAGS
from jaxrail.vehicles.load_path import static_loads
from jaxrail.vehicles.vehicle_file import data_folder, read_vehicle_model

G = 9.81
SCENARIOS = {"coach": "coach-curve-irregular", "wagon": "wagon-straight-irregular"}
MASSES = {"coach": 32000.0 + 2 * 2615.0 + 4 * 1813.0,  # the benchmark's bodies [kg]
          "wagon": 2 * 22500.0}  # two axles of 22.5 t
WHEELSETS = {"coach": 4, "wagon": 2}
LOAD_TOLERANCE = 1e-6  # relative: the rest pose's bisections and Newton step
REST_TOLERANCE = 1e-8  # [m/s^2]: accelerations of the bodies at rest (seen: 1.2e-10)
RUN = 0.2  # [s] of each scenario
AT_REST = 0.01  # [s]: the run at rest whose first outputs are the rest's loads


def _file(name):
    with open(data_folder() / f"{name}.toml", "rb") as stream:
        return tomllib.load(stream)


@pytest.fixture(scope="module", params=sorted(SCENARIOS))
def shipped(request):
    """(name, vehicle, params) of a shipped vehicle file."""
    return (request.param, *vehicle_from_file(request.param))


def test_shipped_files_are_builtin_vehicles_with_scenarios():
    assert {"coach", "wagon", "trailer"} <= set(vehicle_names())
    for name, scenario in SCENARIOS.items():
        assert scenario in BUILTIN
        assert load_scenario(scenario).model == name


# ---- every number sourced ---------------------------------------------------------------


def _bare_numbers(node, path=""):
    """Paths of numbers written without a quantity table (the loader refuses any but 0
    and directions; this walks the raw TOML to be sure none slipped through), and the
    quantity tables met on the way."""
    if isinstance(node, dict):
        if "value" in node:
            return [], [(path, node)]
        bare, tables = [], []
        for key, value in node.items():
            b, t = _bare_numbers(value, f"{path}.{key}" if path else key)
            bare, tables = bare + b, tables + t
        return bare, tables
    if isinstance(node, list):
        bare, tables = [], []
        for k, value in enumerate(node):
            b, t = _bare_numbers(value, f"{path}[{k}]")
            bare, tables = bare + b, tables + t
        return bare, tables
    if isinstance(node, bool):
        return [], []
    if isinstance(node, (int, float)):
        return [path], []
    return [], []


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_every_number_has_unit_source_and_tag(name):
    data = _file(name)
    bare, tables = _bare_numbers(data)
    # bare numbers: zeros (zero in every unit) and direction fields (axis*, frame*) only
    for path in bare:
        key = path.split(".")[-1].split("[")[0]
        value = eval_path(data, path)
        assert value == 0 or ek.is_direction(key), f"{name}: {path} = {value} has no unit"
    assert len(tables) > 20
    for path, table in tables:
        assert set(table) == {"value", "unit", "source", "tag"}, path
        assert table["tag"] in TAGS, path
        assert isinstance(table["source"], str) and len(table["source"].strip()) > 5, path
        units = table["unit"] if isinstance(table["unit"], list) else [table["unit"]]
        assert all(isinstance(u, str) and u.strip() for u in units), path


def eval_path(data, path):
    """The raw value at a dotted path with [k] indices."""
    node = data
    for part in path.split("."):
        key, *indices = part.replace("]", "").split("[")
        node = node[key]
        for k in indices:
            node = node[int(k)]
    return node


def test_tags_are_honest_where_the_benchmark_gives_no_value():
    """The coach's values the benchmark's tables (as found) do not give are assumed (A);
    those read in TTB-2D are V-src; the wagon is not a published vehicle (A and R only)."""
    coach = _file("coach")["parameters"]
    for group in ("yaw_damper", "traction_rod"):
        assert {t["tag"] for t in coach[group].values()} == {"A"}, group
    assert coach["secondary"]["reservoir_stiffness"]["tag"] == "A"
    assert coach["secondary"]["orifice_damping"]["tag"] == "A"
    for group, key in (("carbody", "mass"), ("bogie", "mass"), ("wheelset", "benchmark_mass"),
                       ("secondary", "vertical_stiffness"), ("primary", "vertical_damping")):
        assert coach[group][key]["tag"] == "V-src" and "TTB-2D" in coach[group][key]["source"]
    _, tables = _bare_numbers(_file("wagon"))
    assert {t["tag"] for _, t in tables} <= {"A", "R"}


# ---- the vehicles ----------------------------------------------------------------------


def test_bodies_masses_and_element_kinds(shipped):
    name, vehicle, params = shipped
    # each wheelset carries its axleboxes (the files' axle joints folded away)
    assert vehicle.n_wheelsets == WHEELSETS[name] == len(vehicle.system.axle_bodies)
    assert vehicle.system.axle_bodies == vehicle.wheelsets and not vehicle.system.joint_groups
    np.testing.assert_allclose(float(jnp.sum(params.system.bodies.mass)), MASSES[name],
                               rtol=1e-12)
    groups = {g.kind: g.names for g in vehicle.system.force_groups}
    if name == "coach":
        assert set(groups) == {"bushing", "air_spring", "maxwell_damper", "anti_roll_bar",
                               "table_spring", "traction_rod"}
        dampers = groups["maxwell_damper"]
        assert sum(n.startswith("yaw_damper") for n in dampers) == 4
        assert sum(n.startswith("lateral_damper") for n in dampers) == 4
        assert len(groups["air_spring"]) == 4
        assert len(groups["anti_roll_bar"]) == len(groups["table_spring"]) == 2
        assert len(groups["traction_rod"]) == 2
        assert vehicle.system.body_names[:3] == ("carbody", "bogie_1", "bogie_2")
    else:
        assert set(groups) == {"bushing", "friction_damper"}
        assert len(groups["friction_damper"]) == 12  # vertical, lateral, longitudinal x 4
        assert vehicle.system.body_names == ("carbody", "wheelset_1", "wheelset_2")


def test_coach_element_values():
    """The benchmark's numbers reach the elements: the air springs carry a quarter of the
    carbody each, the bump stop's table is the reference's (0.6 kN at 30 mm, 230 kN at
    65 mm with 25 mm free play), the anti-roll bar's roll stiffness is 940 kN m/rad, the
    yaw damper has its series stiffness and blow-off table, the rods and dampers are
    unloaded at the nominal layout (free length = the distance between their points)."""
    vehicle, params = vehicle_from_file("coach")
    forces = params.system.forces
    np.testing.assert_allclose(forces["air_spring"].preload, -32000.0 * G / 4, rtol=1e-14)
    np.testing.assert_allclose(forces["air_spring"].vertical_stiffness, 430e3)
    stop = forces["table_spring"]
    np.testing.assert_allclose(stop.clearance, 0.025)
    u, f = np.asarray(stop.displacement[0]), np.asarray(stop.force[0])
    np.testing.assert_allclose(f[np.isclose(u, 0.030 - 0.025)], 600.0)
    np.testing.assert_allclose(f[np.isclose(u, 0.065 - 0.025)], 230e3)
    np.testing.assert_allclose(roll_stiffness(forces["anti_roll_bar"]), 940e3, rtol=1e-12)
    maxwell = forces["maxwell_damper"]
    names = next(g.names for g in vehicle.system.force_groups if g.kind == "maxwell_damper")
    yaw = np.array([n.startswith("yaw_damper") for n in names])
    np.testing.assert_allclose(maxwell.series_stiffness[yaw], 4e6)
    np.testing.assert_allclose(np.asarray(maxwell.forces)[yaw][:, -1], 25.75e3)
    layout = {n: p for n, p in zip(vehicle.system.body_names, np.asarray(params.layout))}
    for kind in ("maxwell_damper", "traction_rod"):
        group = next(g for g in vehicle.system.force_groups if g.kind == kind)
        e = forces[kind]
        for k, (i, j) in enumerate(zip(group.body_i, group.body_j)):
            a = layout[vehicle.system.body_names[i]] + np.asarray(e.point_i[k])
            b = layout[vehicle.system.body_names[j]] + np.asarray(e.point_j[k])
            np.testing.assert_allclose(np.linalg.norm(b - a), e.free_length[k], rtol=1e-14)


def test_air_spring_static_preload_and_nominal_length_in_the_loader():
    """``preload = "static"`` sets an air spring's scalar vertical preload (negative: it
    pushes an upper body j up, as a bushing's); ``free_length = "nominal"`` is the
    distance between the element's points; coinciding points are refused by key."""
    assert ek.STATIC_PRELOADS["air_spring"]({}, 1000.0, True) == {"preload": -1000.0}
    assert ek.STATIC_PRELOADS["air_spring"]({}, 1000.0, False) == {"preload": 1000.0}
    model = read_vehicle_model(_file("coach"), "coach.toml")
    loads = static_loads(model, G)
    assert loads["air_spring_1_left"] == pytest.approx((32000.0 * G / 4, True), rel=1e-14)
    data = _file("coach")
    rod = next(e for e in data["template"]["bogie"]["element"] if e["name"] == "traction_rod")
    rod["at_j"] = rod["at_i"]
    with pytest.raises(ValueError, match=r"coach\.toml: \[template\.bogie\.element\[6\] "
                                         r"'traction_rod'\] free_length: \"nominal\""):
        read_vehicle_model(data, "coach.toml")


# ---- 0.2 s of each scenario, and at rest on its track ----------------------------------


@pytest.fixture(scope="module")
def short_run(shipped):
    """(scenario, result, vehicle, params, track) of the first 0.2 s of the vehicle's
    scenario, as ``run_scenario`` runs it (its rest pose and integration compiled)."""
    scenario = load_scenario(SCENARIOS[shipped[0]])
    result, vehicle, params, track = run_scenario(scenario, duration=RUN)
    return scenario, result, vehicle, params, track


def test_static_equilibrium_at_rest(shipped, short_run):
    """The rest on the scenario's own track, its irregularity scaled to 0 (the same
    structure, so the same programs): the vehicle stands on the first straight. The
    rest state is the run's rest-pose program at speed 0 without misalignment; its
    wheel loads (the vertical force on each wheel) and accelerations are the first
    outputs of a run from it, the run's integration program: nothing new compiled."""
    name = shipped[0]
    scenario, _, vehicle, params, track = short_run
    ideal = eqx.tree_at(lambda t: t.irregularity.scale, track, jnp.float64(0.0))
    model = scenario.contact_model(vehicle, params, ideal)
    zero = jnp.float64(0.0)
    rest, seconds = compile_program(initial_state, vehicle, params, ideal, zero, zero, None,
                                    model)
    assert seconds == 0.0  # the run's rest pose
    state = rest(vehicle, params, ideal, zero, zero, None, model)
    result = simulate(vehicle, params, ideal, AT_REST, 0.0, 0.0,
                      options=scenario.solver_options(RUN), initial=state,
                      contact_model=model)
    assert float(result.compile_time_s) == 0.0  # the run's integration
    assert bool(result.valid[0])
    np.testing.assert_array_equal(result.q[0], state.q)  # the first output is the rest
    wheel_loads = np.asarray(result.wheels.vertical_force[0])  # (W, 2)
    qddot = np.asarray(result.qddot[0]).reshape(-1, 7)
    weight = MASSES[name] * G
    assert np.all(np.isfinite(np.asarray(state.q))) and np.all(np.isfinite(qddot))
    assert wheel_loads.shape == (WHEELSETS[name], 2)
    np.testing.assert_allclose(float(np.sum(wheel_loads)), weight, rtol=LOAD_TOLERANCE)
    np.testing.assert_allclose(wheel_loads[:, 0], wheel_loads[:, 1],  # left = right
                               rtol=LOAD_TOLERANCE)
    np.testing.assert_allclose(wheel_loads, weight / (2 * WHEELSETS[name]),
                               rtol=LOAD_TOLERANCE)
    # the preloads hold every body where the layout puts it: nothing accelerates
    np.testing.assert_allclose(qddot[:, :3], 0.0, atol=REST_TOLERANCE)
    if name == "coach":  # the internal states of the air springs and Maxwell dampers
        assert set(state.elements) == {"air_spring", "maxwell_damper"}
    else:
        assert state.elements == {}


def test_short_run_of_the_scenario(shipped, short_run):
    name = shipped[0]
    _, result, vehicle, _, _ = short_run
    assert result.result == diffrax.RESULTS.successful
    assert not bool(result.derailed)
    assert bool(np.all(np.asarray(result.valid)))
    for field in ("q", "qdot", "qddot", "wheelset_lateral"):
        assert np.all(np.isfinite(np.asarray(getattr(result, field)))), field
    vertical = np.asarray(result.wheels.vertical_force)
    assert np.all(np.isfinite(vertical)) and vertical.shape[1] == vehicle.n_wheelsets
    # every wheel stays on its rail, loaded within a factor of its static share (the
    # coach's least loaded wheel fell to 0.46 of it, entering the irregular track)
    share = MASSES[name] * G / (2 * vehicle.n_wheelsets)
    assert 0.2 * share < np.min(np.abs(vertical)) and np.max(np.abs(vertical)) < 2.0 * share
