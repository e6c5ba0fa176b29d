"""The modes of the trailer standing on the track, its wheelsets clamped, against a
hand-written model of its vertical plane (carbody on the secondary springs and dampers,
bogies on the primary ones, wheelsets fixed), and its wheel loads at rest; and
``jaxrail vehicle show trailer``, which reports them from the same programs."""

import copy
import json

import jax
import numpy as np
import pytest

from jaxrail.cli import main
from jaxrail.stability import vehicle_modes
from jaxrail.vehicles import trailer_values, vehicle_from_data, vehicle_from_file
from jaxrail.vehicles.from_file import read_toml, vehicle_file_path
from jaxrail.vehicles.trailer import GRAVITY

BOUNCE = 1e-9  # relative: the vertical plane's bounce is the 3D model's (1e-14 measured)
PITCH = 1e-3  # relative: see test_carbody_pitch_matches_the_hand_model
LOADS = 1e-6  # relative


@pytest.fixture(scope="module")
def standing():
    return vehicle_modes(*vehicle_from_file("trailer"))


def _eigenvalues(mass, stiffness, damping):
    """The eigenvalues (Im > 0) of M x'' + C x' + K x = 0, by increasing Im."""
    n = len(mass)
    a = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(mass, stiffness), -np.linalg.solve(mass, damping)]])
    values = np.linalg.eigvals(a)
    values = values[values.imag > 0.0]
    return values[np.argsort(values.imag)]


def _mode(standing, body, motion):
    found = [m for m in standing.modes if m.body == body and m.motion == motion]
    assert len(found) == 1, [(m.body, m.motion) for m in standing.modes]
    return found[0]


def test_carbody_and_bogie_bounce_match_the_hand_model(standing):
    # carbody z and both bogies' z together: 4 secondary springs and dampers between,
    # 8 primary ones under the bogies (on the fixed axles)
    v = trailer_values()
    k2, c2 = v["secondary.vertical_stiffness"], v["secondary.vertical_damping"]
    k1, c1 = v["primary.vertical_stiffness"], v["primary.vertical_damping"]
    mass = np.diag([v["carbody.mass"], 2 * v["bogie.mass"]])

    def matrix(secondary, primary):
        return np.array([[4 * secondary, -4 * secondary],
                         [-4 * secondary, 4 * secondary + 8 * primary]])

    carbody, bogies = _eigenvalues(mass, matrix(k2, k1), matrix(c2, c1))
    for expected, mode in ((carbody, _mode(standing, "carbody", "bounce")),
                           (bogies, _mode(standing, "bogie_1+bogie_2", "bounce, in phase"))):
        assert abs(mode.eigenvalue - expected) < BOUNCE * abs(expected)
        assert abs(mode.frequency_hz - expected.imag / (2 * np.pi)) < BOUNCE * mode.frequency_hz
        assert abs(mode.damping_ratio + expected.real / abs(expected)) < BOUNCE


def test_carbody_pitch_matches_the_hand_model(standing):
    # carbody pitch theta with the bogies' z in anti-phase (zeta up at the leading one):
    # the secondary springs at x = +-a deflect by zeta + a theta. This 2-dof model misses
    # what the 3D model has: the secondary's longitudinal springs 1.2 m below the
    # carbody's centre of mass, which a carbody pitching moves fore and aft, and the
    # preloads' geometric stiffness -m g h (they push up at seats that pitching lifts
    # and lowers as h theta^2 / 2); the 3D model's pitch lies 3.2e-3 away. With the
    # carbody's longitudinal motion x and those two terms (3 dof) it lies 2e-4 away,
    # the rest being the bogies' own pitch and fore-and-aft motion. The nearest other
    # carbody mode (bounce) is 18 % away.
    v = trailer_values()
    k2, c2 = v["secondary.vertical_stiffness"], v["secondary.vertical_damping"]
    k1, c1 = v["primary.vertical_stiffness"], v["primary.vertical_damping"]
    a, m = v["carbody.bogie_half_distance"], v["carbody.mass"]
    h = v["carbody.height"] - v["secondary.height"]
    pitch = _mode(standing, "carbody", "pitch").eigenvalue

    two = np.diag([v["carbody.pitch_inertia"], 2 * v["bogie.mass"]])
    vertical = np.array([a, 1.0])
    two_dof = _eigenvalues(two, 4 * k2 * np.outer(vertical, vertical) + np.diag([0, 8 * k1]),
                           4 * c2 * np.outer(vertical, vertical) + np.diag([0, 8 * c1]))[0]
    assert 1e-3 < abs(pitch - two_dof) / abs(two_dof) < 5e-3

    three = np.diag([m, v["carbody.pitch_inertia"], 2 * v["bogie.mass"]])
    along, vertical = np.array([1.0, -h, 0.0]), np.array([0.0, a, 1.0])
    stiffness = (4 * v["secondary.longitudinal_stiffness"] * np.outer(along, along)
                 + 4 * k2 * np.outer(vertical, vertical)
                 + np.diag([0.0, -m * GRAVITY * h, 8 * k1]))
    damping = 4 * c2 * np.outer(vertical, vertical) + np.diag([0.0, 0.0, 8 * c1])
    three_dof = [x for x in _eigenvalues(three, stiffness, damping) if x.imag > 7.0][0]
    assert abs(pitch - three_dof) < PITCH * abs(three_dof)
    bounce = _mode(standing, "carbody", "bounce").eigenvalue
    assert abs(bounce - pitch) > 100 * PITCH * abs(pitch)


def test_wheel_loads_carry_the_weight(standing):
    loads = standing.wheel_loads_n
    assert loads.shape == (4, 2)
    assert abs(np.sum(loads) / standing.weight_n - 1.0) < LOADS
    np.testing.assert_allclose(loads, standing.weight_n / 8, rtol=LOADS)  # symmetric
    assert standing.total_mass_kg == pytest.approx(44482.0, rel=1e-12)
    assert standing.residual < 1e-8


def test_the_carbodys_modes_are_named(standing):
    names = {m.motion for m in standing.modes if m.body == "carbody"}
    assert names == {"lower sway", "upper sway", "bounce", "pitch", "yaw", "longitudinal"}
    lower, upper = (_mode(standing, "carbody", f"{x} sway") for x in ("lower", "upper"))
    assert lower.frequency_hz < upper.frequency_hz
    # the overdamped pitch of the axlebox bodies on their soft springs was the joint
    # form's only real mode: the wheelsets carry their axleboxes here
    assert [m for m in standing.modes if m.frequency_hz == 0.0] == []


def test_an_off_centre_carbody_loads_its_left_wheels_by_its_moment(standing):
    # the carbody's centre of mass 0.1 m to the left (the file's load path shares its
    # weight out): the rails' vertical forces at the contact points balance the weight's
    # moment about the track's centreline (the lateral forces act at the rail tops)
    path = vehicle_file_path("trailer")
    data = copy.deepcopy(read_toml(path))
    carbody = next(b for b in data["body"] if b["name"] == "carbody")
    carbody["at"][1] = {"value": 0.1, "unit": "m", "source": "a test", "tag": "A"}
    vehicle, params = vehicle_from_data(data, where=str(path), folder=path.parent)
    shifted = vehicle_modes(vehicle, params)  # the fixture's programs: same structure
    loads, arms = shifted.wheel_loads_n, shifted.contact_arms_m
    body = shifted.q.reshape(-1, 7)
    centres = body[np.asarray(vehicle.wheelsets), 1]
    moment = np.sum(loads * (centres[:, None] + arms[..., 1]))
    weight_moment = GRAVITY * np.sum(np.asarray(params.system.bodies.mass) * body[:, 1])
    assert abs(moment / weight_moment - 1.0) < LOADS
    assert abs(np.sum(loads) / shifted.weight_n - 1.0) < LOADS
    assert np.all(loads[:, 0] > 1.1 * loads[:, 1])  # left heavier (1.21 times)
    np.testing.assert_allclose(loads, np.tile(loads[0], (4, 1)), rtol=LOADS)  # alike


def test_show_reports_the_trailers_masses_wheel_loads_and_modes(standing, tmp_path, capsys):
    """``jaxrail vehicle show trailer``: the report (JSON keys and values, the figure).
    It runs here, after the fixture, because it asks for the fixture's two programs
    (the rest pose and the linearisation at it): the command traces neither again."""
    traced = []

    def on_trace(event, seconds, **kwargs):
        if event == "/jax/core/compile/jaxpr_trace_duration":
            traced.append(kwargs.get("fun_name"))

    report, figure = tmp_path / "trailer.json", tmp_path / "trailer.png"
    jax.monitoring.register_event_duration_secs_listener(on_trace)
    try:
        code = main(["vehicle", "show", "trailer", "--json", str(report), "--plot", str(figure)])
    finally:
        jax.monitoring.unregister_event_duration_listener(on_trace)
    assert code == 0
    assert not {"_rest", "_linearised"} & set(traced), traced
    text = capsys.readouterr().out
    assert "wheel loads at rest" in text and "lower sway" in text
    data = json.loads(report.read_text())
    assert {"total_mass_kg", "static_wheel_loads_N", "modes"} <= set(data)
    assert data["total_mass_kg"] == pytest.approx(32000 + 2 * 2615 + 4 * 1813, rel=1e-12)
    loads = data["static_wheel_loads_N"]
    assert len(loads) == 8  # 4 wheelsets, leading first, left then right
    weight = data["total_mass_kg"] * GRAVITY
    assert abs(sum(loads) / weight - 1.0) < LOADS
    np.testing.assert_allclose(loads, weight / 8, rtol=LOADS)
    for mode in data["modes"]:
        assert {"frequency_hz", "damping_ratio", "body", "motion"} <= set(mode)
    bounce = [m for m in data["modes"] if (m["body"], m["motion"]) == ("carbody", "bounce")]
    assert len(bounce) == 1 and 0.5 < bounce[0]["frequency_hz"] < 2.0
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
