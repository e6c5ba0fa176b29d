"""Vehicle files (docs/vehicle-files.md): the trailer's file against the Python builder,
units, templates and mirroring, static preloads, and every bad input with its file,
table and key. Nothing here compiles a simulation."""

import copy
import dataclasses
import math
import re
import tomllib
from pathlib import Path
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.multibody import forces as fc
from jaxrail.multibody import generalized_forces
from jaxrail.profiles import s1002
from jaxrail.vehicles import read_vehicle_data, trailer, trailer_values
from jaxrail.vehicles import element_kinds as ek
from jaxrail.vehicles.from_file import vehicle_from_data, vehicle_from_file, vehicle_names
from jaxrail.vehicles.load_path import static_loads
from jaxrail.vehicles.units import dimension_of, parse_unit, to_si
from jaxrail.vehicles.vehicle_file import data_folder, read_vehicle_model
from jaxrail.vehicles.wheels import ShiftedProfile, wheel_profile

G = 9.81
DOCS = Path(__file__).parents[2] / "docs" / "vehicle-files.md"


def _same_tree(a, b):
    leaves_a, tree_a = jax.tree.flatten(a)
    leaves_b, tree_b = jax.tree.flatten(b)
    assert tree_a == tree_b
    for x, y in zip(leaves_a, leaves_b):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


# ---- the trailer ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def trailers():
    return trailer(), vehicle_from_file("trailer", formulation="joints")


def test_trailer_file_builds_the_python_trailer(trailers):
    (v_py, p_py), (v_file, p_file) = trailers
    assert v_file.name == v_py.name == "trailer"
    assert v_file.system.body_names == v_py.system.body_names
    assert v_file.system.joint_groups == v_py.system.joint_groups  # names, kinds, bodies
    assert v_file.system.force_groups == v_py.system.force_groups
    assert v_file.wheelsets == v_py.wheelsets and v_file.axleboxes == v_py.axleboxes
    assert v_file == v_py
    _same_tree(p_file.system, p_py.system)  # every number of SystemParams
    np.testing.assert_array_equal(p_file.layout, p_py.layout)
    _same_tree((p_file.wheel, p_file.contact), (p_py.wheel, p_py.contact))
    _same_tree(p_file, p_py)


def test_trailer_file_carries_every_number_source_and_tag():
    data = tomllib.loads((data_folder() / "trailer.toml").read_text())
    for key, entry in read_vehicle_data().items():
        group, name = key.split(".")
        assert data["parameters"][group][name] == entry, key


def test_parameter_overrides_follow_into_the_preloads():
    values = trailer_values(carbody__mass=30000.0, primary__vertical_stiffness=1.0e6)
    _, p_py = trailer(values=values)
    _, p_file = vehicle_from_file("trailer", formulation="joints", parameters={
        "carbody.mass": 30000.0, "primary.vertical_stiffness": 1.0e6})
    _same_tree(p_file.system, p_py.system)


def test_builtin_names():
    assert "trailer" in vehicle_names() and "manchester_trailer" not in vehicle_names()
    with pytest.raises(ValueError, match="trailer"):
        vehicle_from_file("no-such-vehicle")


# ---- the bogie, the single and the suspended wheelset ------------------------------------


def _bitwise_same(file_built, python_built):
    """Same bodies, joints, elements, wheelsets and every number, to the bit (signed
    zeros included)."""
    (v_file, p_file), (v_py, p_py) = file_built, python_built
    assert v_file.system.body_names == v_py.system.body_names
    assert v_file.system.joint_groups == v_py.system.joint_groups  # names, kinds, bodies
    assert v_file.system.force_groups == v_py.system.force_groups
    assert v_file.wheelsets == v_py.wheelsets and v_file.axleboxes == v_py.axleboxes
    assert v_file == v_py
    leaves_file, tree_file = jax.tree.flatten(p_file)
    leaves_py, tree_py = jax.tree.flatten(p_py)
    assert tree_file == tree_py
    for a, b in zip(leaves_file, leaves_py):
        a, b = np.asarray(a), np.asarray(b)
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes(), (a, b)


def _python_builders():
    from jaxrail.vehicles import bogie, single_wheelset
    from jaxrail.vehicles.suspended_wheelset import suspended_wheelset

    return {"bogie": bogie, "suspended-wheelset": suspended_wheelset,
            "single-wheelset": lambda: single_wheelset(s1002())}


@pytest.mark.parametrize("name", ["bogie", "single-wheelset", "suspended-wheelset"])
def test_builtin_file_builds_the_python_vehicle(name):
    assert name in vehicle_names()
    _bitwise_same(vehicle_from_file(name, formulation="joints"), _python_builders()[name]())


@pytest.mark.parametrize("direction", ["left", "right"])
def test_suspended_wheelset_file_with_a_curve_radius(direction):
    from jaxrail.vehicles.suspended_wheelset import suspended_wheelset, suspended_wheelset_file

    built = suspended_wheelset_file(650.0, direction, formulation="joints")
    _bitwise_same(built, suspended_wheelset(curve_radius=650.0, direction=direction))
    kinds = {n: g.kind for g in built[0].system.joint_groups for n in g.names}
    assert kinds == {"axle_1": "revolute", "guide": "revolute"}
    with pytest.raises(ValueError, match="curve_radius must be > 0 m"):
        suspended_wheelset_file(-1.0)


@pytest.mark.parametrize("name", ["bogie", "suspended-wheelset"])
def test_builtin_file_carries_the_trailers_numbers(name):
    """The trailer's parameters by name, so that a scenario's ``[vehicle] data`` replaces
    them; the suspended wheelset's own primary longitudinal stiffness apart."""
    data = tomllib.loads((data_folder() / f"{name}.toml").read_text())
    own = {"primary.longitudinal_stiffness"} if name == "suspended-wheelset" else set()
    for key, entry in read_vehicle_data().items():
        group, field = key.split(".")
        if key not in own:
            assert data["parameters"][group][field] == entry, key
    if own:
        assert data["parameters"]["primary"]["longitudinal_stiffness"]["value"] == 1.0e6


@pytest.mark.parametrize("name", ["bogie", "suspended-wheelset"])
def test_builtin_file_takes_trailer_values_as_the_python_builder_does(name):
    values = trailer_values(carbody__mass=30000.0, primary__vertical_damping=5000.0)
    builder = _python_builders()[name]
    _bitwise_same(vehicle_from_file(name, parameters=values, formulation="joints"),
                  builder(values=values))


# ---- units --------------------------------------------------------------------------------

UNITS = [  # (value, unit, SI value): hand conversions
    (1435.0, "mm", 1.435), (5.0, "cm", 0.05), (2.0, "km", 2000.0), (0.46, "m", 0.46),
    (20.0, "t", 20000.0), (1613.0, "kg", 1613.0),
    (1.0, "N", 1.0), (2.5, "kN", 2500.0), (1.5, "MN", 1.5e6),
    (430.0, "N/m", 430.0), (430.0, "kN/m", 430e3), (1.22, "MN/m", 1.22e6),
    (2.0, "N/mm", 2000.0), (1.22, "kN/mm", 1.22e6),
    (4000.0, "N s/m", 4000.0), (4.0, "kN s/m", 4000.0),
    (1e5, "N m/rad", 1e5), (100.0, "kN m/rad", 1e5), (0.94, "MN m/rad", 0.94e6),
    (1e3, "N m s/rad", 1e3), (1.0, "kN m s/rad", 1e3),
    (1120.0, "kg m^2", 1120.0), (1.97, "t m^2", 1970.0), (1.97, "t m²", 1970.0),
    (1.0, "rad", 1.0), (5.0, "mrad", 0.005), (180.0, "deg", math.pi),
    (2.0, "s", 2.0), (5.0, "ms", 0.005), (36.0, "Hz", 36.0),
    (18.3, "m/s", 18.3), (36.0, "km/h", 10.0), (9.81, "m/s^2", 9.81),
    (2e5, "Pa", 2e5), (200.0, "kPa", 2e5), (2.0, "bar", 2e5),
    (0.5, "m^3", 0.5), (50.0, "l", 0.05), (0.4, "-", 0.4),
]


@pytest.mark.parametrize("value,unit,si", UNITS)
def test_unit_conversion(value, unit, si):
    np.testing.assert_allclose(to_si(value, parse_unit(unit)), si, rtol=1e-15)


def test_exact_conversions_and_dimensions():
    assert to_si(1435.0, parse_unit("mm")) == 1.435  # the float the literal gives
    assert dimension_of("kN/mm") == dimension_of("N/m") == (1, 0, -2)
    assert dimension_of("kN s/m") == dimension_of("N s/m") == (1, 0, -1)
    assert dimension_of("N m/rad") == dimension_of("N m") == (1, 2, -2)  # angles are 1
    assert dimension_of("t m^2") == (1, 2, 0) and dimension_of("Hz") == (0, 0, -1)
    assert dimension_of("km/h") == (0, 1, -1) and dimension_of("bar") == (1, -1, -2)


@pytest.mark.parametrize("unit", ["furlong", "N//m", "m^x", "", "kN/", 3])
def test_bad_units(unit):
    with pytest.raises(ValueError, match="unit"):
        parse_unit(unit)


# ---- templates, mirroring, static loads ----------------------------------------------------


def q(value, unit):
    return {"value": value, "unit": unit, "source": "test", "tag": "A"}


def axle_template(frame):
    """An axle: axlebox body, wheelset, revolute joint, primary bushings to ``frame``."""
    return {
        "body": [{"name": "axlebox", "mass": q(200, "kg"), "inertia": q([200, 4, 200], "kg m^2"),
                  "at": [0, 0, "r0"]}],
        "wheelset": [{"name": "wheelset", "mass": q(1.6, "t"),
                      "inertia": q([1120, 112, 1120], "kg m^2"), "nominal_radius": "r0",
                      "profile": "S1002", "back_to_back": q(1360, "mm"),
                      "axlebox": "axlebox"}],
        "joint": [{"name": "axle", "kind": "revolute", "body_i": "axlebox",
                   "body_j": "wheelset", "at": [0, 0, "r0"], "axis": [0, 1, 0]}],
        "element": [{"name": "primary", "kind": "bushing", "body_i": "axlebox", "body_j": frame,
                     "at": [0, q(1.0, "m"), "r0"], "mirror": True,
                     "stiffness": q([30, 4, 1.2, 0, 100, 0],
                                    ["MN/m"] * 3 + ["kN m/rad"] * 3),
                     "damping": [0, 0, q(4, "kN s/m"), 0, q(1, "kN m s/rad"), 0],
                     "preload": "static"}],
    }


def wagon(carbody_x=0.0):
    """A two-axle wagon: wheelsets directly under the carbody."""
    return {
        "vehicle": {"name": "wagon"},
        "parameters": {"r0": q(460, "mm"), "a": q(4.5, "m"),
                       "carbody": {"mass": q(20, "t"), "x": q(carbody_x, "m")}},
        "body": [{"name": "carbody", "mass": "carbody.mass",
                  "inertia": q([30, 150, 150], "t m^2"), "at": ["carbody.x", 0, q(1.5, "m")]}],
        "use": [{"template": "axle", "x": ["a", "-a"]}],
        "template": {"axle": axle_template("carbody")},
    }


def coach(axles_x=("b", "-b")):
    """A bogie coach; three axles per bogie with ``axles_x = ("b", 0, "-b")``."""
    return {
        "vehicle": {"name": "coach"},
        "parameters": {"r0": q(0.46, "m"), "a": q(9.5, "m"), "b": q(1.28, "m"),
                       "m_c": q(32, "t"), "m_b": q(2615, "kg")},
        "body": [{"name": "carbody", "mass": "m_c", "inertia": q([56.8, 1970, 1970], "t m^2"),
                  "at": [0, 0, q(2.0, "m")]}],
        "use": [{"template": "bogie", "x": ["a", "-a"]}],
        "template": {
            "bogie": {
                "body": [{"name": "bogie", "mass": "m_b", "inertia": q([1722, 1476, 3067], "kg m^2"),
                          "at": [0, 0, q(0.6, "m")]}],
                "element": [{"name": "secondary", "kind": "bushing", "body_i": "bogie",
                             "body_j": "carbody", "at": [0, q(1.0, "m"), q(0.8, "m")],
                             "mirror": True, "stiffness": q([160, 160, 430, 0, 0, 0], "kN/m"),
                             "preload": "static"}],
                "use": [{"template": "axle", "x": list(axles_x)}]},
            "axle": axle_template("bogie")},
    }


def _rest(vehicle, params):
    """(q, qdot) of the nominal layout at rest, every body unrotated."""
    n = vehicle.system.n_bodies
    quaternion = jnp.tile(jnp.array([1.0, 0.0, 0.0, 0.0]), (n, 1))
    return jnp.concatenate([params.layout, quaternion], axis=1).reshape(-1), jnp.zeros(7 * n)


def _check_sprung_equilibrium(vehicle, params, sprung):
    """At the nominal layout the sprung bodies feel no net force or moment: their
    weight is balanced by the static preloads exactly."""
    q0, v0 = _rest(vehicle, params)
    g = generalized_forces(vehicle.system, params.system, 0.0, q0, v0).reshape(-1, 7)
    weight = float(jnp.max(params.system.bodies.mass)) * G
    for name in sprung:
        np.testing.assert_allclose(g[vehicle.system.body_names.index(name)], 0.0,
                                   atol=1e-9 * weight, err_msg=name)


def test_two_axle_wagon():
    vehicle, params = vehicle_from_data(wagon(), where="wagon.toml", formulation="joints")
    assert vehicle.system.body_names == ("carbody", "axlebox_1", "axlebox_2", "wheelset_1",
                                         "wheelset_2")
    assert vehicle.wheelsets == (3, 4) and vehicle.axleboxes == (1, 2)
    (group,) = vehicle.system.force_groups
    assert group.names == ("primary_1_left", "primary_1_right", "primary_2_left",
                           "primary_2_right")
    assert group.body_i == (1, 1, 2, 2) and group.body_j == (0, 0, 0, 0)
    assert vehicle.system.joint_groups[0].names == ("axle_1", "axle_2")
    bushing = params.system.forces["bushing"]
    np.testing.assert_array_equal(bushing.point_i, [[0, 1, 0], [0, -1, 0]] * 2)
    np.testing.assert_array_equal(bushing.point_j, [[4.5, 1, -1.04], [4.5, -1, -1.04],
                                                    [-4.5, 1, -1.04], [-4.5, -1, -1.04]])
    np.testing.assert_array_equal(bushing.preload[:, 2], -20000.0 * G / 4)
    np.testing.assert_array_equal(bushing.stiffness[0], [30e6, 4e6, 1.2e6, 0, 1e5, 0])
    np.testing.assert_array_equal(params.layout[:, 0], [0, 4.5, -4.5, 4.5, -4.5])
    np.testing.assert_array_equal(params.layout[1:, 2], 0.46)


def test_off_centre_carbody_gets_balanced_shares():
    """A carbody 0.9 m ahead of the middle: equal shares would pitch it, the minimum-norm
    shares carry 20 t x (4.5 +- 0.9) / 9 / 2 on each side."""
    model = read_vehicle_model(wagon(carbody_x=0.9), "wagon.toml")
    loads = static_loads(model, G)
    np.testing.assert_allclose(loads["primary_1_left"][0], 20000 * G * 5.4 / 9 / 2, rtol=1e-12)
    np.testing.assert_allclose(loads["primary_2_right"][0], 20000 * G * 3.6 / 9 / 2, rtol=1e-12)
    vehicle, params = vehicle_from_data(wagon(carbody_x=0.9), where="wagon.toml")
    _check_sprung_equilibrium(vehicle, params, ["carbody"])


@pytest.mark.parametrize("axles_x", [("b", "-b"), ("b", 0, "-b")], ids=["2-axle", "3-axle"])
def test_bogie_coach(axles_x):
    vehicle, params = vehicle_from_data(coach(axles_x), where="coach.toml",
                                        formulation="joints")
    n = len(axles_x)
    names = vehicle.system.body_names
    assert names == (("carbody", "bogie_1", "bogie_2")
                     + tuple(f"axlebox_{k}" for k in range(1, 2 * n + 1))
                     + tuple(f"wheelset_{k}" for k in range(1, 2 * n + 1)))
    (group,) = vehicle.system.force_groups
    primary = [f"primary_{k}_{s}" for k in range(1, 2 * n + 1) for s in ("left", "right")]
    assert group.names == tuple(primary + ["secondary_1_left", "secondary_1_right",
                                           "secondary_2_left", "secondary_2_right"])
    frames = [names.index(f"bogie_{1 + (k >= n)}") for k in range(2 * n) for _ in "lr"]
    assert group.body_j[:4 * n] == tuple(frames)
    a, b = 9.5, 1.28
    offsets = [b, 0.0, -b] if n == 3 else [b, -b]
    axle_x = [a + x for x in offsets] + [-a + x for x in offsets]
    wheelsets = [names.index(f"wheelset_{k}") for k in range(1, 2 * n + 1)]
    assert vehicle.wheelsets == tuple(wheelsets)
    np.testing.assert_array_equal(params.layout[np.array(wheelsets), 0], axle_x)
    preload = params.system.forces["bushing"].preload[:, 2]
    np.testing.assert_allclose(preload[4 * n:], -32000 * G / 4, rtol=1e-14)
    np.testing.assert_allclose(preload[:4 * n], -(2615 + 16000) * G / (2 * n), rtol=1e-14)
    if n == 3:  # (each check compiles the force elements' operations for its sizes)
        _check_sprung_equilibrium(vehicle, params, ["carbody", "bogie_1", "bogie_2"])


def test_mirrored_bodies_and_fields():
    """Side frames written once for the left: the right copy at -y with its products
    of inertia, axes, frames and six-entry preload mirrored, and elements joined to
    the same side's copy."""
    data = wagon()
    frame = [[1, 0, 0], [0, 0.6, -0.8], [0, 0.8, 0.6]]
    data["body"].append({"name": "side", "mass": q(300, "kg"), "mirror": True,
                         "inertia": q([[50, 5, 0], [5, 60, 2], [0, 2, 70]], "kg m^2"),
                         "at": [0, q(1.2, "m"), q(0.7, "m")]})
    data["element"] = [
        {"name": "hanger", "kind": "bushing", "body_i": "carbody", "body_j": "side",
         "at": [0, q(1.2, "m"), q(0.9, "m")], "mirror": True, "frame_i": frame,
         "stiffness": q([1, 1, 1, 0, 0, 0], "MN/m"),
         "preload": [0, q(100, "N"), 0, q(10, "N m"), q(3, "N m"), q(5, "N m")]},
        {"name": "stop", "kind": "bump_stop", "body_i": "carbody", "body_j": "side_left",
         "at": [0, q(1.2, "m"), q(0.7, "m")], "axis_i": [0, 1, 0], "clearance": q(25, "mm"),
         "stiffness": q(2, "MN/m")}]
    model = read_vehicle_model(data, "sides.toml")
    bodies = {b.name: b for b in model.bodies}
    assert bodies["side_left"].position == (0.0, 1.2, 0.7)
    assert bodies["side_right"].position == (0.0, -1.2, 0.7)
    np.testing.assert_array_equal(bodies["side_right"].inertia,
                                  [[50, -5, 0], [-5, 60, -2], [0, -2, 70]])
    links = {e.name: e for e in model.elements}
    left, right = links["hanger_left"], links["hanger_right"]
    assert (left.body_j, right.body_j) == ("side_left", "side_right")
    assert right.at_i == (0.0, -1.2, 0.9)
    reflect = np.diag([1.0, -1.0, 1.0])
    np.testing.assert_array_equal(right.values["frame_i"], reflect @ np.array(frame) @ reflect)
    assert np.linalg.det(right.values["frame_i"]) > 0
    np.testing.assert_array_equal(right.values["preload"], [0, -100, 0, -10, 3, -5])
    assert links["stop"].body_j == "side_left"
    mirrored_stop = ek.mirrored(fc.BumpStop, "axis_i", [0.0, 1.0, 0.0])
    assert mirrored_stop == [0.0, -1.0, 0.0]


def test_docs_example_builds():
    text = DOCS.read_text()
    example = re.search(r"## A complete example.*?```toml\n(.*?)```", text, re.S).group(1)
    vehicle, params = vehicle_from_data(tomllib.loads(example), where="docs example")
    # its wheelsets carry their axleboxes (formulation "auto")
    assert vehicle.system.body_names == ("carbody", "wheelset_1", "wheelset_2")
    assert vehicle.system.axle_bodies == vehicle.wheelsets == (1, 2)
    np.testing.assert_array_equal(params.system.forces["bushing"].preload[:, 2], -49050.0)


def test_back_to_back_moves_the_profile():
    assert wheel_profile("S1002", 0.46, 1.360) == s1002(0.46)
    wheel = wheel_profile("S1002", 0.46, 1.370)
    (surface,) = wheel.surfaces
    assert isinstance(surface, ShiftedProfile) and surface.shift == pytest.approx(0.005)
    for y in (-0.03, 0.0, 0.02):
        np.testing.assert_allclose(surface.height(y + 0.005), s1002().surfaces[0].height(y),
                                   rtol=0, atol=1e-12)
    assert surface.domain[0] == pytest.approx(s1002().surfaces[0].domain[0] + 0.005)


# ---- bad input ------------------------------------------------------------------------------


def _set(path, value):
    def change(data):
        *keys, last = path
        for key in keys:
            data = data[key]
        if value is DELETE:
            del data[last]
        else:
            data[last] = value
    return change


DELETE = object()
AXLE = ("template", "axle")
ELEMENT, JOINT, WHEELSET = AXLE + ("element", 0), AXLE + ("joint", 0), AXLE + ("wheelset", 0)


def _loose_body(data):
    data["body"].append({"name": "loose", "mass": q(10, "kg"), "inertia": q([1, 1, 1], "kg m^2"),
                         "at": [0, 0, q(3, "m")]})


def _spring_static(data):
    data["template"]["axle"]["element"].append(
        {"name": "spring", "kind": "spring_damper", "body_i": "axlebox", "body_j": "carbody",
         "at": [0, 0, "r0"], "stiffness": q(1, "MN/m"), "free_length": 0,
         "preload": "static"})


BAD = [  # (id, change, table, key, words in the message)
    ("unknown kind", _set(ELEMENT + ("kind",), "bushin"), "template.axle.element[0]", "kind",
     ["unknown element kind 'bushin'", *fc.FORCE_KINDS]),  # the known ones listed
    ("unknown joint kind", _set(JOINT + ("kind",), "hinge"), "template.axle.joint[0]", "kind",
     ["unknown joint kind", "revolute"]),
    ("unknown body in element", _set(ELEMENT + ("body_j",), "carbdy"),
     "template.axle.element[0]", "body_j", ["unknown body 'carbdy'"]),
    ("unknown body in joint", _set(JOINT + ("body_i",), "axlebx"), "template.axle.joint[0]",
     "body_i", ["unknown body 'axlebx'"]),
    ("element to itself", _set(ELEMENT + ("body_j",), "axlebox"), "template.axle.element[0]",
     "body_j", ["to itself"]),
    ("joint to itself", _set(JOINT + ("body_j",), "axlebox"), "template.axle.joint[0]",
     "body_j", ["to itself"]),
    ("zero mass", _set(("body", 0, "mass"), q(0, "t")), "body[0] 'carbody'", "mass",
     ["positive"]),
    ("negative mass parameter", _set(("parameters", "carbody", "mass"), q(-20, "t")),
     "body[0] 'carbody'", "mass", ["positive"]),
    ("negative inertia", _set(("body", 0, "inertia"), q([30, -1, 150], "t m^2")),
     "body[0] 'carbody'", "inertia", ["positive"]),
    ("indefinite tensor", _set(("body", 0, "inertia"),
                               q([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "t m^2")),
     "body[0] 'carbody'", "inertia", ["positive definite"]),
    ("missing unit", _set(("parameters", "a"), {"value": 4.5, "source": "s", "tag": "A"}),
     "parameters", "a", ["missing unit"]),
    ("unknown unit", _set(("parameters", "a"), q(4.5, "metres")), "parameters", "a",
     ["unknown unit 'metres'"]),
    ("wrong dimension", _set(ELEMENT + ("stiffness",), q([30, 4, 1.2, 0, 0, 0], "MN")),
     "template.axle.element[0] 'primary'", "stiffness", ["force per length"]),
    ("wrong dimension of a position", _set(("use", 0, "x"), ["carbody.mass"]), "use[0]", "x",
     ["length"]),
    ("number without unit", _set(ELEMENT + ("stiffness",), [3e7, 4e6, 1.2e6, 0, 1e5, 0]),
     "template.axle.element[0] 'primary'", "stiffness", ["has no unit"]),
    ("missing source", _set(("parameters", "r0"), {"value": 0.46, "unit": "m", "tag": "A"}),
     "parameters", "r0", ["missing source"]),
    ("unknown tag", _set(("parameters", "r0"), {**q(0.46, "m"), "tag": "guess"}),
     "parameters", "r0", ["tag 'guess'"]),
    ("table not increasing", _set(ELEMENT + ("stiffness",), q([[0, 0], [2, 5], [1, 9]],
                                                               ["mm", "kN"])),
     "template.axle.element[0] 'primary'", "stiffness", ["increase strictly"]),
    ("unsupported body", _loose_body, "body[1] 'loose'", "name",
     ["nothing supports body 'loose'", "singular"]),
    ("wheelset without profile", _set(WHEELSET + ("profile",), DELETE),
     "template.axle.wheelset[0] 'wheelset'", "profile", ["missing"]),
    ("unknown profile", _set(WHEELSET + ("profile",), "S1003"),
     "template.axle.wheelset[0] 'wheelset'", "profile", ["unknown wheel profile 'S1003'"]),
    ("unknown field", _set(ELEMENT + ("stifness",), 0), "template.axle.element[0] 'primary'",
     "stifness", ["unknown key", "stiffness"]),
    ("missing field", _set(ELEMENT + ("stiffness",), DELETE),
     "template.axle.element[0] 'primary'", "stiffness", ["missing"]),
    ("bad expression", _set(("use", 0, "x"), ["__import__('os').getcwd()"]), "use[0]", "x",
     ["only numbers"]),
    ("unknown parameter", _set(("use", 0, "x"), ["a + c"]), "use[0]", "x",
     ["unknown parameter 'c'"]),
    ("parameter cycle", _set(("parameters", "a"), "2 * a"), "parameters", "a",
     ["depends on itself"]),
    ("adding a mass to a length", _set(("use", 0, "x"), ["a + carbody.mass"]), "use[0]", "x",
     ["adds"]),
    ("unknown template", _set(("use", 0, "template"), "axel"), "use[0]", "template",
     ["unknown template 'axel'"]),
    ("unknown template part", _set(AXLE + ("elements",), []), "template.axle", "elements",
     ["unknown part"]),
    ("arithmetic on a vector", lambda d: (d["parameters"].update(v=q([1, 2], "m")),
                                          d["use"][0].update(x=["2 * v"])),
     "use[0]", "x", ["'v' is a vector"]),
    ("mirrored body without side", _set(AXLE + ("body", 0, "mirror"), True),
     "template.axle.joint[0] 'axle'", "body_i", ["mirrored: name axlebox_left or axlebox_right"]),
    ("a rail is the track's", _set(("vehicle", "rail"), "UIC60 1:40"), "vehicle", "rail",
     ["belong to the track", "scenario's [track]"]),
    ("a gauge is the track's", _set(("vehicle", "gauge"), q(1435, "mm")), "vehicle", "gauge",
     ["belong to the track", "scenario's [track]"]),
    ("unknown table", _set(("bodies",), []), "top level", "bodies", ["unknown table"]),
    ("static preload on a spring", _spring_static, "template.axle.element[1] 'spring'",
     "preload", ["static"]),
    ("axlebox not joined", _set(AXLE + ("joint",), []), "template.axle.wheelset[0]",
     "axlebox", ["no joint"]),
]


@pytest.mark.parametrize("change,table,key,words", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_names_file_table_and_key(change, table, key, words):
    data = copy.deepcopy(wagon())
    change(data)
    with pytest.raises(ValueError) as error:
        vehicle_from_data(data, where="bad_wagon.toml")
    message = str(error.value)
    assert message.startswith("bad_wagon.toml: ["), message
    assert f"[{table}" in message and f"] {key}:" in message, message
    for word in words:
        assert word in message, message


def test_kind_check_gets_the_element_prefix(monkeypatch):
    """A kind's own parameter check (here a characteristic table that must increase)
    raises with the element's file, table and key."""

    @dataclasses.dataclass(frozen=True)
    class TableSpring:
        body_i: str
        body_j: str
        point_i: object
        point_j: object
        force: object
        name: str = ""
        kind: ClassVar[str] = "test_table_spring"

    def params(specs, what):
        for s in specs:
            if np.any(np.diff(np.asarray(s.force)[:, 1]) <= 0.0):
                raise ValueError(f"{what} force: the characteristic must be monotone")
        return None

    monkeypatch.setitem(fc.FORCE_KINDS, "test_table_spring",
                        fc.FORCE_KINDS["spring_damper"]._replace(params=params))
    monkeypatch.setitem(ek._registry, "test_table_spring", TableSpring)
    data = wagon()
    data["template"]["axle"]["element"].append(
        {"name": "spring", "kind": "test_table_spring", "body_i": "axlebox",
         "body_j": "carbody", "at": [0, 0, "r0"],
         "force": q([[-10, 5], [0, 0], [10, -5]], ["mm", "kN"])})
    with pytest.raises(ValueError) as error:
        vehicle_from_data(data, where="bad_wagon.toml")
    message = str(error.value)
    assert message.startswith("bad_wagon.toml: [template.axle.element[1] 'spring'] force:")
    assert "monotone" in message


def test_toml_syntax_error_names_the_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[vehicle]\nname = \n")
    with pytest.raises(ValueError, match="broken.toml"):
        vehicle_from_file(path)


# ---- wheelsets that carry their axleboxes (formulation "auto") -------------------------


def test_the_wagon_carries_its_axleboxes():
    vehicle, params = vehicle_from_data(wagon(), where="wagon.toml", formulation="auto")
    assert vehicle.system.body_names == ("carbody", "wheelset_1", "wheelset_2")
    assert vehicle.wheelsets == (1, 2) and vehicle.axleboxes == ()
    assert vehicle.system.axle_bodies == (1, 2) and vehicle.system.joint_groups == ()
    assert vehicle.system.n_constraints == 3  # the Euler parameters' normalisation only
    bodies = params.system.bodies
    np.testing.assert_array_equal(bodies.mass, [20000.0, 1800.0, 1800.0])
    np.testing.assert_array_equal(bodies.inertia[1], np.diag([1320.0, 112.0, 1320.0]))
    (group,) = vehicle.system.force_groups
    assert group.body_i == (1, 1, 2, 2) and group.body_j == (0, 0, 0, 0)
    bushing = params.system.forces["bushing"]
    np.testing.assert_array_equal(bushing.point_i, [[0, 1, 0], [0, -1, 0]] * 2)
    np.testing.assert_array_equal(bushing.preload[:, 2], -20000.0 * G / 4)
    # the rotation about the axle held only the axlebox body: gone with it
    np.testing.assert_array_equal(bushing.stiffness[0], [30e6, 4e6, 1.2e6, 0, 0, 0])
    np.testing.assert_array_equal(bushing.damping[0], [0, 0, 4e3, 0, 0, 0])
    with pytest.raises(ValueError, match="formulation must be one of"):
        vehicle_from_data(wagon(), formulation="twists")


def _refolded(change):
    data = wagon()
    change(data["template"]["axle"])
    return data


@pytest.mark.parametrize("change, words", [
    (lambda t: t["body"][0].update(inertia=q([200, 4, 150], "kg m^2")), "differs about x"),
    (lambda t: t["wheelset"][0].update(inertia=q([[1120, 0, 5], [0, 112, 0], [5, 0, 1120]],
                                                 "kg m^2")), "products of inertia"),
    (lambda t: t["body"][0].update(at=[0, 0, q(0.6, "m")]), "not centred"),
    (lambda t: t["joint"][0].update(axis=[0, 0, 1]), "does not turn about the axle"),
    (lambda t: t["element"][0].update(at=[q(0.1, "m"), q(1.0, "m"), "r0"]), "off the axle"),
])
def test_folding_is_refused_where_it_would_change_the_model(change, words):
    from jaxrail.vehicles.axleboxes import carry_axleboxes
    data = _refolded(change)
    assert words in carry_axleboxes(read_vehicle_model(data, "wagon.toml")).reason
    vehicle, _ = vehicle_from_data(data, where="wagon.toml", formulation="auto")
    assert vehicle.system.n_bodies == 5 and vehicle.system.axle_bodies == ()


def _angular_acceleration(q, qddot, body):
    """omega-dot (3,) [rad/s^2] (global) of ``body``: 2 E(p) pddot (E(pdot) pdot = 0)."""
    from jaxrail.multibody import quaternion as qt
    return 2.0 * qt.e_matrix(q[7 * body + 3:7 * body + 7]) @ qddot[7 * body + 3:7 * body + 7]


def test_folded_accelerations_are_eq_19s_with_the_axle_joints():
    """The wagon without its pitch springs, in a displaced, spinning state: the carbody's
    and the wheelsets' accelerations of the folded wagon are those of eq. (19) with
    the axlebox bodies on their axle joints (each at its axle frame), under the same
    loads on the wheelsets. On a rolled axle the two differ by the elements' pitch
    moment on the axle frame times tan(roll) (jaxrail.multibody.axle_frame), which a
    free axlebox body's pitch takes instead: here the axles are level."""
    from jaxrail.multibody import accelerations
    from jaxrail.multibody import quaternion as qt
    from jaxrail.multibody.axle_frame import axle_rotation
    from jaxrail.multibody.loads import FixedLoads

    def no_pitch_spring(t):
        t["element"][0]["stiffness"] = q([30, 4, 1.2, 0, 0, 0], ["MN/m"] * 3 + ["kN m/rad"] * 3)
        t["element"][0]["damping"] = [0, 0, q(4, "kN s/m"), 0, 0, 0]
    data = _refolded(no_pitch_spring)
    joined, joined_params = vehicle_from_data(data, formulation="joints")
    folded, folded_params = vehicle_from_data(data, formulation="auto")
    rng = np.random.default_rng(11)
    # folded bodies: carbody, wheelset_1, wheelset_2 (joined: + axlebox_1, _2 before them)
    r = np.asarray(folded_params.layout) + rng.normal(0.0, 2e-3, (3, 3))
    angles = rng.normal(0.0, 0.01, (3, 3))  # (roll, spin, yaw) of each body
    angles[1:, 0] = 0.0  # the axles level (see the docstring)
    angles[1:, 1] += (1.1, 2.6)
    p = [qt.multiply(qt.multiply(qt.from_axis_angle((0, 0, 1), a[2]),
                                 qt.from_axis_angle((1, 0, 0), a[0])),
                     qt.from_axis_angle((0, 1, 0), a[1])) for a in angles]
    spin = 18.0 / 0.46  # [rad/s] about each axle; no yaw or roll rate
    v = rng.normal(0.0, 0.02, (3, 3)) + np.array([18.0, 0.0, 0.0])
    w = [np.zeros(3)] + [spin * np.asarray(qt.rotation_matrix(p[k]))[:, 1] for k in (1, 2)]
    pdot = [0.5 * qt.e_matrix(p[k]).T @ w[k] for k in range(3)]
    q_f = jnp.concatenate([jnp.concatenate([jnp.asarray(r[k]), p[k]]) for k in range(3)])
    v_f = jnp.concatenate([jnp.concatenate([jnp.asarray(v[k]), pdot[k]]) for k in range(3)])
    boxes = [jnp.concatenate([jnp.asarray(r[k]), axle_rotation(p[k])]) for k in (1, 2)]
    box_rates = [jnp.concatenate([jnp.asarray(v[k]), jnp.zeros(4)]) for k in (1, 2)]
    q_j = jnp.concatenate([q_f[:7], *boxes, q_f[7:]])
    v_j = jnp.concatenate([v_f[:7], *box_rates, v_f[7:]])
    wheel_forces = rng.normal(0.0, 1e4, (2, 3))
    wheel_torques = rng.normal(0.0, 1e3, (2, 3))
    loads = lambda n: FixedLoads(  # noqa: E731
        jnp.zeros((n, 3)).at[n - 2:].set(wheel_forces),
        jnp.zeros((n, 3)).at[n - 2:].set(wheel_torques))
    a_f, _ = accelerations(folded.system, folded_params.system, 0.0, q_f, v_f, loads(3))
    a_j, _ = accelerations(joined.system, joined_params.system, 0.0, q_j, v_j, loads(5))
    for body_f, body_j in ((0, 0), (1, 3), (2, 4)):
        np.testing.assert_allclose(a_f[7 * body_f:7 * body_f + 3],
                                   a_j[7 * body_j:7 * body_j + 3], rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(_angular_acceleration(q_f, a_f, body_f),
                                   _angular_acceleration(q_j, a_j, body_j), rtol=1e-9,
                                   atol=1e-8)


def test_folded_accelerations_differentiate_as_central_differences():
    """The folded wagon's accelerations at a displaced, spinning, rolled state, in the
    primary longitudinal stiffness and the first wheelset's lateral position and yaw
    rate: forward and reverse mode against central differences (1e-5)."""
    from jaxrail.multibody import accelerations
    from jaxrail.multibody import quaternion as qt

    vehicle, params = vehicle_from_data(wagon(), formulation="auto")
    system = vehicle.system
    rng = np.random.default_rng(4)
    r = np.asarray(params.layout) + rng.normal(0.0, 1e-3, (3, 3))
    p = [qt.multiply(qt.from_axis_angle((1, 0, 0), 0.02 * k),
                     qt.from_axis_angle((0, 1, 0), 1.3 * k)) for k in range(3)]
    q0 = jnp.concatenate([jnp.concatenate([jnp.asarray(r[k]), p[k]]) for k in range(3)])
    spin = [np.zeros(3)] + [18.0 / 0.46 * np.asarray(qt.rotation_matrix(p[k]))[:, 1]
                            for k in (1, 2)]
    v0 = jnp.concatenate([jnp.concatenate([jnp.array([18.0, 0.0, 0.0]),
                                           0.5 * qt.e_matrix(p[k]).T @ spin[k]])
                          for k in range(3)])

    def accelerations_of(x):  # x: (k_x scale, lateral [m], yaw rate [rad/s])
        bushing = params.system.forces["bushing"]
        stiffness = bushing.stiffness.at[:, 0].multiply(x[0])
        sp = eqx.tree_at(lambda s: s.forces["bushing"].stiffness, params.system, stiffness)
        q = q0.at[8].add(x[1])
        turn = 0.5 * qt.e_matrix(q0[10:14]).T @ jnp.array([0.0, 0.0, x[2]])
        return accelerations(system, sp, 0.0, q, v0.at[10:14].add(turn))[0]

    x0 = jnp.array([1.0, 2e-3, 0.05])
    forward = jax.jit(jax.jacfwd(accelerations_of))(x0)
    reverse = jax.jit(jax.jacrev(accelerations_of))(x0)
    steps = (1e-6, 1e-7, 1e-5)
    central = np.stack([(accelerations_of(x0.at[i].add(h)) - accelerations_of(x0.at[i].add(-h)))
                        / (2 * h) for i, h in enumerate(steps)], axis=1)
    scale = np.max(np.abs(central), axis=0)
    np.testing.assert_allclose(forward / scale, central / scale, atol=1e-5)
    np.testing.assert_allclose(reverse / scale, central / scale, atol=1e-5)
