"""The steady curving state (jaxrail.stability.curving) against closed forms and against
the time integration: the suspended wheelset (its frame turning about the curve's
centre) with coned wheels (1:40) on UIC60 1:40, in left curves without cant.

- A wheelset free of its springs rolls on the pure-rolling line,
  y = -r0 l0 / (lambda R) (no creep coefficient enters).
- With its springs, in a wide curve (small creepages), it takes Wickens' linear steady
  curving state: (k_y + k_g) y - 2 f22 psi = -m V^2/R - 2 f23/R and
  2 f11 lambda l0/r0 y + (k_psi + 2 f23) psi = -2 f11 l0^2/R, with the coefficients the
  engine reports at the rolling contact's spin and Polach's combined coefficient: his
  law scales both creep forces by C = sqrt((c11 xi)^2 + (c22 eta)^2) / |(xi, eta)|, so
  f11 and f22 are taken along the steady creepages' direction (fixed point).
- A simulation started from the state stays in it (global coordinates, no turning
  frame).
- The wear numbers' gradient by implicit differentiation of the state
  (jaxrail.stability.curving_wear) against central differences of states solved anew.
- Each solve starts from the state solved at the nearest speed, through states 5 m/s
  apart (a stand-in problem, nothing compiled)."""

import types

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.multibody import velocities_from_twists
from jaxrail.profiles.analytic import conical_wheel
from jaxrail.simulation import SolverOptions, solve
from jaxrail.stability import LinearStability
from jaxrail.stability.curving import SteadyCurving
from jaxrail.stability.curving_wear import CurvingWear
from jaxrail.stability.wheelset import polach_slopes_along, wheelset_coefficients
from jaxrail.track import Track, straight_track
from jaxrail.track.layout import Arc, Straight
from jaxrail.vehicles import get_values, set_values, trailer_values
from jaxrail.vehicles.suspended_wheelset import LONGITUDINAL_STIFFNESS, suspended_wheelset

WHEEL = conical_wheel(0.025, nominal_radius=0.46)  # on the standard UIC60 1:40
RADIUS = 3000.0  # [m]
SPEED = 30.0  # [m/s]


def _curve(radius):
    vehicle, params = suspended_wheelset(WHEEL, curve_radius=radius)
    return vehicle, params, Track.from_segments([Arc(300.0, radius, "left")])


@pytest.fixture(scope="module")
def curving():
    vehicle, params, track = _curve(RADIUS)
    return vehicle, params, track, SteadyCurving(vehicle, params, track)


@pytest.fixture(scope="module")
def coefficients():
    vehicle, params = suspended_wheelset(WHEEL)
    c = jax.jit(lambda p, v: wheelset_coefficients(vehicle, p, straight_track(200.0), v))
    return {k: float(v) for k, v in c(params, SPEED).items()}


def test_a_wheelset_free_of_its_springs_rolls_on_the_pure_rolling_line(curving, coefficients):
    vehicle, params, track, steady = curving
    free = set_values(vehicle, params, ["primary_longitudinal_stiffness",
                                        "primary_lateral_stiffness"], jnp.zeros(2))
    state = steady(SPEED, free)
    c = coefficients
    pure = -c["rolling_radius_m"] * c["half_contact_distance_m"] / (c["conicity"] * RADIUS)
    assert abs(state.wheelset_lateral_m[0] / pure - 1.0) < 0.005
    assert state.residual < 1e-6


def _wickens_curving(c, radius, speed):
    """(y, psi) of Wickens' steady curving (module docstring)."""
    v = trailer_values()
    mass = v["wheelset.mass"] + v["axlebox.mass"]
    ky, kpsi = (2 * v["primary.lateral_stiffness"],
                2 * LONGITUDINAL_STIFFNESS * v["axlebox.half_span"] ** 2)
    f23 = c["f23_spin_n_m"]
    lam, l0, r0, kg = (c["conicity"], c["half_contact_distance_m"], c["rolling_radius_m"],
                       c["gravitational_stiffness_n_m"])
    a11, a22 = c["f11_spin_n"], c["f22_spin_n"]
    for _ in range(40):
        stiffness = np.array([[ky + kg, -2 * a22], [2 * a11 * lam * l0 / r0, kpsi + 2 * f23]])
        load = np.array([-mass * speed**2 / radius - 2 * f23 / radius,
                         -2 * a11 * l0**2 / radius])
        y, psi = np.linalg.solve(stiffness, load)
        a11, a22 = (float(f) for f in polach_slopes_along(c, l0 / radius + lam * y / r0, psi))
    return y, psi


def test_the_suspended_wheelset_takes_wickens_steady_curving_state(curving, coefficients):
    radius = 1.0e5  # [m]: creep forces under 5 % of their limit
    vehicle, params, track = _curve(radius)
    state = curving[3](SPEED, params, track)
    y, psi = _wickens_curving(coefficients, radius, SPEED)
    assert y < 0.0 and psi < 0.0  # outwards, nose out (the springs hold it off radial)
    assert abs(state.wheelset_lateral_m[0] / y - 1.0) < 0.02
    assert abs(state.wheelset_yaw_rad[0] / psi - 1.0) < 0.02


def test_a_simulation_started_in_the_steady_curving_state_stays_in_it(curving):
    vehicle, params, track, steady = curving
    state = steady(SPEED)
    s = state.steady
    qdot = velocities_from_twists(s.q, s.velocity, s.angular_velocity)
    # the traceable core under jit: this process's earlier programs may hold host
    # callbacks that the exported programs of simulate() cannot carry; duration and speed
    # traced, as SteadyCurving's settling run calls it: one program for both
    result = eqx.filter_jit(solve)(vehicle, params, track, jnp.float64(1.0), jnp.float64(SPEED),
                                   initial=(s.q, qdot), options=SolverOptions(integrator="imex"),
                                   contact_model=steady.model)
    assert result.status == "successful"
    lateral = np.asarray(result.wheelset_lateral)[:, 0]
    yaw = np.asarray(result.wheelset_yaw)[:, 0]
    assert state.wheelset_lateral_m[0] < -1e-3  # 1.9 mm out: a real curving offset
    assert np.max(np.abs(lateral - state.wheelset_lateral_m[0])) < 1e-6
    assert np.max(np.abs(yaw - state.wheelset_yaw_rad[0])) < 1e-6


def test_the_wear_numbers_gradient_against_central_differences(curving):
    vehicle, params, track, steady = curving
    names = ("primary_longitudinal_stiffness", "primary_lateral_stiffness")
    wear = CurvingWear(steady, names)
    point = wear(SPEED)
    assert point.wear_number_n.shape == (1, 2)
    assert np.all(np.isfinite(point.wear_number_n)) and np.max(point.wear_number_n) > 0.0
    values = np.asarray(get_values(vehicle, params, names))
    for k, name in enumerate(names):
        h = 1e-4 * values[k]
        sides = [wear(SPEED, set_values(vehicle, params, [name], [values[k] + s * h]),
                      start=point.state).wear_number_n for s in (1.0, -1.0)]
        central = (sides[0] - sides[1]) / (2.0 * h)
        assert np.all(np.isfinite(point.gradient[name])) and np.max(np.abs(central)) > 0.0
        np.testing.assert_allclose(point.gradient[name], central, rtol=0,
                                   atol=1e-4 * np.max(np.abs(central)), err_msg=name)
    with pytest.raises(ValueError, match="no_such_parameter"):
        CurvingWear(steady, ("no_such_parameter",))


def test_bad_inputs_are_named(curving):
    vehicle, params, track, steady = curving
    with pytest.raises(ValueError, match="one arc"):
        SteadyCurving(vehicle, params, straight_track(100.0))
    straight_vehicle, straight_params = suspended_wheelset(WHEEL)
    with pytest.raises(ValueError, match="prismatic joint.*curve_radius"):
        SteadyCurving(straight_vehicle, straight_params, track)
    with pytest.raises(ValueError, match="speed must be > 0"):
        steady(0.0)
    with pytest.raises(ValueError, match="straight track or on one circular arc"):
        LinearStability(vehicle, params, Track.from_segments(
            [Straight(50.0), Arc(50.0, 300.0)], allow_curvature_jumps=True))
    in_curve = LinearStability(vehicle, params, track)
    with pytest.raises(ValueError, match="gradient is implemented on straight track"):
        in_curve.critical_speed_gradient(None, ["primary_lateral_stiffness"])
    with pytest.raises(ValueError, match="curve_radius must be > 0"):
        suspended_wheelset(WHEEL, curve_radius=-1.0)


def test_each_solve_starts_from_the_state_solved_at_the_nearest_speed():
    """The continuation's choice of start, on a stand-in problem whose state is its
    speed (no vehicle is compiled): after 60, 70, ..., 140 m/s, the root solve's 90.64
    m/s starts from 90 m/s (not from the last, 140), and 100 m/s asked with only 60 solved
    goes through 65, ..., 95 m/s, each started from the one before."""
    steady = SteadyCurving.__new__(SteadyCurving)
    steady.vehicle = types.SimpleNamespace(system=types.SimpleNamespace(n_bodies=1),
                                           wheelsets=())
    steady.params, steady.track = object(), Track.from_segments([Arc(300.0, 3000.0)])
    steady._solved = None
    starts = []
    steady._setup = lambda params, track, speed: (float(speed), None, None, np.zeros(7))

    def newton(u, params, track, setup_values):
        starts.append((setup_values[0], float(u[0])))
        return np.r_[setup_values[0], np.zeros(6)], np.zeros(6), 1

    steady._newton = newton
    steady._report = lambda u, track, setup_values: (None, np.zeros(0), np.zeros(0))
    for speed in range(60, 141, 10):
        steady(speed)
    del starts[:]
    steady(90.64)
    assert starts == [(90.64, 90.0)]
    steady._solved = None
    steady(60.0)
    del starts[:]
    steady(100.0)
    assert starts == [(v, v - 5.0) for v in (65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0)]
