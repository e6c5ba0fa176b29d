"""Quasi-static geometry against an independent NumPy brute-force search, mirror
symmetry, two-point contact, and the EN 15302 conicity integral."""

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from brute_force import BruteForce
from jaxrail.geometry import equivalent_conicity, wheelset_geometry
from jaxrail.profiles import s1002, simplified_s1002
from jaxrail.profiles.uic60 import uic60
from jaxrail.profiles.measures import rail_offset
from jaxrail.track import Rails

SHIFTS = np.round(np.arange(-10.0, 10.001, 0.5), 6) * 1e-3


def geometry(wheel, rail, shifts):
    """The jitted entry point, called as the CLI calls it (41 shifts, float64 gauge and
    yaw rate), so that the tests and the CLI tests share one compilation per wheel."""
    return wheelset_geometry(wheel, Rails.at_gauge(rail, jnp.asarray(1.435, dtype=jnp.float64)),
                             shifts, jnp.asarray(0.0, dtype=jnp.float64))



@pytest.fixture(scope="module")
def real():
    return geometry(s1002(), uic60(), jnp.asarray(SHIFTS))


@pytest.fixture(scope="module")
def brute():
    rail = uic60()
    return BruteForce(s1002(), rail, rail_offset(rail))


def _jump_shifts(brute, shifts):
    """Shifts where the brute-force contact point jumps, located by bisection."""
    jumps = []
    previous = brute.solve(shifts[0])
    for a, b in zip(shifts[:-1], shifts[1:]):
        current = brute.solve(b)
        if max(abs(current[1] - previous[1]), abs(current[2] - previous[2])) > 1.5e-3:
            lo, hi, left = a, b, previous
            while hi - lo > 1e-5:
                mid = 0.5 * (lo + hi)
                probe = brute.solve(mid)
                if max(abs(probe[1] - left[1]), abs(probe[2] - left[2])) > 1.5e-3:
                    hi = mid
                else:
                    lo, left = mid, probe
            jumps.append(0.5 * (lo + hi))
        previous = current
    return np.array(jumps)


def test_against_brute_force(real, brute):
    """Contact positions on the wheel and dr agree with dense sampling to 0.05 mm,
    except within 0.2 mm of shifts where the contact jumps."""
    jumps = _jump_shifts(brute, SHIFTS)
    assert len(jumps) >= 2  # tread -> throat and throat -> flange jumps, on both sides
    y_wheel = np.asarray(real.main_patch("y_wheel"))
    compared = 0
    for k, shift in enumerate(SHIFTS):
        if np.min(np.abs(jumps - shift)) < 0.2e-3:
            continue
        roll, y_left, y_right, delta_r, _, _ = brute.solve(shift)
        assert abs(y_wheel[k, 0] - y_left) < 0.05e-3, shift
        assert abs(y_wheel[k, 1] - y_right) < 0.05e-3, shift
        assert abs(float(real.delta_r[k]) - delta_r) < 0.05e-3, shift
        assert abs(float(real.roll[k]) - roll) < 2e-5, shift
        compared += 1
    assert compared >= 35
    assert float(jnp.max(real.residual)) < 1e-10


def test_mirror_symmetry(real):
    """A shift of +y gives the left/right mirror of -y."""
    flipped = slice(None, None, -1)
    y = np.asarray(real.main_patch("y_wheel"))
    radius = np.asarray(real.main_patch("rolling_radius"))
    angle = np.asarray(real.main_patch("contact_angle"))
    np.testing.assert_allclose(y[flipped, ::-1], y, atol=1e-9)
    np.testing.assert_allclose(radius[flipped, ::-1], radius, atol=1e-10)
    np.testing.assert_allclose(angle[flipped, ::-1], angle, atol=1e-7)
    np.testing.assert_allclose(real.delta_r[flipped], -real.delta_r, atol=1e-10)
    np.testing.assert_allclose(real.roll[flipped], -real.roll, atol=1e-10)


def test_flange_contact_angle_and_track_position(real):
    """Beyond the flangeway clearance the left wheel runs on its flange at a steep
    contact angle; the contact point sits on the rail's gauge corner."""
    k = int(np.argmin(np.abs(SHIFTS - 8e-3)))
    angle = float(real.main_patch("contact_angle")[k, 0])
    assert 0.8 < angle < 1.25  # between the flange face and the 70 deg flank
    y_track = float(real.main_patch("y_track")[k, 0])
    assert 0.715 < y_track < 0.725  # the gauge corner, 717.5 mm is the gauge point


def _at_jump(wheel, on_first_side, lo, hi, rounds=4):
    """Geometry at the shift where the left wheel's main contact jumps: grids of 41
    shifts (the one compiled shape), each refined around the switch of
    ``on_first_side(result) -> bool array`` (True before the jump)."""
    for _ in range(rounds):
        shifts = jnp.linspace(lo, hi, SHIFTS.size)
        result = geometry(wheel, uic60(), shifts)
        first = np.asarray(on_first_side(result))
        assert first[0] and not first[-1]
        k = int(np.argmin(first))  # first shift past the jump
        lo, hi = float(shifts[k - 1]), float(shifts[k])
    return result, k


def test_two_point_contact_real_profile():
    """At the shift where the contact jumps from the tread to the throat, both points
    touch: two patches on one wheel."""
    result, k = _at_jump(s1002(), lambda r: r.main_patch("y_wheel")[:, 0] > -0.02, 4.5e-3, 5.0e-3)
    on = np.asarray(result.patches.active[k - 1, 0])
    assert on.sum() == 2
    y = np.sort(np.asarray(result.patches.y_wheel[k - 1, 0])[on])
    assert y[0] < -0.025 and y[1] > -0.018  # one in the throat, one on the tread


def test_simplified_profile_two_patches():
    """The simplified profile's tread and flange are searched independently: centred only
    the tread touches; where the rail's gauge corner sits in the V between them, both
    touch (the paper's Fig. 4a)."""
    wheel = simplified_s1002()
    patches = geometry(wheel, uic60(), jnp.asarray(SHIFTS)).patches
    active, surface = np.asarray(patches.active[20, 0]), np.asarray(patches.surface[20, 0])
    assert active.sum() == 1 and surface[active].tolist() == [0]  # centred: tread only
    result, k = _at_jump(wheel, lambda r: r.main_patch("surface")[:, 0] == 0, 0.0, 9e-3)
    active = np.asarray(result.patches.active[k - 1, 0])
    surface = np.asarray(result.patches.surface[k - 1, 0])
    angles = np.asarray(result.patches.contact_angle[k - 1, 0])
    assert sorted(set(surface[active].tolist())) == [0, 1]
    assert np.all(angles[active & (surface == 0)] < 0.4)  # tread (near the V)
    assert np.all(angles[active & (surface == 1)] > 1.0)  # steep flange


def test_conicity_of_a_cone_is_its_slope():
    shifts = np.linspace(-0.01, 0.01, 41)
    for slope in (0.05, 0.2):
        values = equivalent_conicity(shifts, 2.0 * slope * shifts, [1e-3, 3e-3, 6e-3])
        np.testing.assert_allclose(values, slope, rtol=1e-10)


def test_conicity_matches_integrated_klingel_wavelength():
    """Nonlinear, asymmetric dr: the integral method equals the wavelength of the
    integrated kinematic equation (scipy)."""
    e, r0 = 0.75, 0.46
    y = np.linspace(-0.01, 0.01, 4001)
    dr = 0.2 * y + 2.0e4 * y**3 + 3.0 * y**2
    for amplitude in (3e-3, 6e-3):
        rhs = lambda x, s: [s[1], -np.interp(s[0], y, dr) / (2 * e * r0)]  # noqa: E731
        turning = lambda x, s: s[1]  # noqa: E731
        turning.direction = 1.0
        turning.terminal = True
        solution = solve_ivp(rhs, [0, 200], [amplitude, 0.0], events=turning, rtol=1e-12, atol=1e-15)
        wavelength = 2.0 * solution.t_events[0][0]
        expected = e * r0 * (2 * np.pi / wavelength) ** 2
        value = float(equivalent_conicity(y, dr, [amplitude])[0])
        assert value == pytest.approx(expected, rel=1e-6)


def test_s1002_uic60_conicity_range(real):
    """S1002 / UIC60 1:40 / 1435: the usual equivalent conicity at 3 mm is about 0.15-0.2."""
    values = equivalent_conicity(SHIFTS, real.delta_r, [3e-3])
    assert 0.12 < float(values[0]) < 0.25


@pytest.fixture(scope="module")
def steep():
    """S1002 on UIC60 1:20 over the same shifts."""
    return geometry(s1002(), uic60("1:20"), jnp.asarray(SHIFTS))


def test_rows_say_whether_the_contact_solve_converged(real, steep):
    """Every row of S1002 on UIC60 1:40 and 1:20 converges: the deepest patch on each
    wheel is at the virtual penetration. On 1:20 at +6.5 mm the left flange, just come
    into contact, was 0.085 mm deep (the solve refined its deepest point from depths in
    which a strip beyond the rail domain counted as -1e3 m deep, see quasistatic.py)."""
    from jaxrail.geometry.report import geometry_rows

    assert all(row["converged"] for row in geometry_rows(real))
    assert all(row["converged"] for row in geometry_rows(steep))
    deepest = np.asarray(steep.patches.penetration).max(axis=2)
    np.testing.assert_allclose(deepest, 1e-6, atol=1e-12)


def test_steep_rail_against_brute_force(steep):
    """S1002 on UIC60 1:20: dr within 0.02 mm of the rigid brute force at every shift,
    the rows next to the tread -> flange jump (between 6 and 6.5 mm) included.

    The brute force samples at 2 um here: on the flange (slope 2.75) its contact point
    snaps to a sample, which at 5 um moves dr by up to 0.007 mm. What is left at +-6.5 mm
    (0.019 mm) is the 1 um virtual penetration: dr rises there by 0.028 mm per um of
    shift, and it falls to 0.001 mm at a virtual penetration of 0.01 um."""
    rail = uic60("1:20")
    brute = BruteForce(s1002(), rail, rail_offset(rail), step=2e-6)
    y_wheel = np.asarray(steep.main_patch("y_wheel"))
    for k, shift in enumerate(SHIFTS):
        roll, y_left, y_right, delta_r, _, _ = brute.solve(shift)
        assert abs(float(steep.delta_r[k]) - delta_r) < 0.02e-3, shift
        assert abs(y_wheel[k, 0] - y_left) < 0.01e-3, shift
        assert abs(y_wheel[k, 1] - y_right) < 0.01e-3, shift
        assert abs(float(steep.roll[k]) - roll) < 2e-5, shift
    k = int(np.argmin(np.abs(SHIFTS - 6.5e-3)))
    assert float(steep.main_patch("contact_angle")[k, 0]) > 1.1  # on the flange
