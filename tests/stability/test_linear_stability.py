"""Linear stability of the suspended wheelset against closed forms: Wickens' model built
here from the coefficients the engine reports, and Klingel's kinematic frequency as the
speed goes to zero; with Maxwell yaw dampers, their own relaxation roots and the hunting
mode left where it was when they barely act. Coned wheels (1:40) on UIC60 1:40: one contact patch per wheel, so
the conicity is the rolling radius difference's slope (on S1002 two close patches share
the load, docs/stability.md). The critical speed's gradient is checked against central
differences of the critical speed by benchmarks/critical_speed_gradient.py: its
forward-over-forward programs take about 2.5 min to compile, beyond the suite's budget."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.profiles.analytic import conical_wheel
from jaxrail.stability import LinearStability
from jaxrail.stability.wheelset import polach_slopes_along, wheelset_coefficients
from jaxrail.multibody import (MaxwellDamper, Prismatic, RigidBody, build_system,
                               velocities_from_twists)
from jaxrail.vehicles.loads import contact_loads
from jaxrail.track import Track, straight_track
from jaxrail.track.layout import Arc, Straight
from jaxrail.vehicles import Vehicle, VehicleParams, set_values, trailer_values
from jaxrail.vehicles.suspended_wheelset import (FRAME_GYRATION_RADIUS, LONGITUDINAL_STIFFNESS,
                                                 frame_mass, suspended_wheelset)
from jaxrail.vehicles.trailer import GRAVITY, primary_bushings, unsprung_bodies

CONE = 0.025  # [rad] of the coned wheels
RANGE = (200.0, 300.0)  # [m/s]: the critical speed is near 238 m/s


@pytest.fixture(scope="module")
def wheelset():
    vehicle, params = suspended_wheelset(conical_wheel(CONE, nominal_radius=0.46))
    track = straight_track(200.0)
    stability = LinearStability(vehicle, params, track)
    coefficients = jax.jit(lambda p, v: wheelset_coefficients(vehicle, p, track, v))
    return vehicle, params, stability, coefficients


@pytest.fixture(scope="module")
def critical(wheelset):
    stability = wheelset[2]
    return stability.critical_speed(*RANGE, points=stability.sweep(RANGE))


def _wickens(mass, yaw_inertia, spin_inertia, lateral_stiffness, yaw_stiffness, c):
    """Least stable eigenvalue (Im > 0) of Wickens' 2-dof wheelset at speed V, as a
    function of V: lateral y and yaw psi, creep f11, f22, f23, conicity, gravitational
    stiffness (Garg and Dukkipati's form) and the gyroscopic yaw moment of the spinning
    axle rolling at lambda y / l0, I_y (V / r0) (lambda / l0) y'. The creep slopes are
    Polach's along the steady creepage of the centred rolling wheelset: longitudinal
    (its spin V / r0 leaves xi0 of order 1e-8, and eta0 = 0), so C = c11 for both."""
    f11, f22 = (float(f) for f in polach_slopes_along(c, 1.0, 0.0))
    f23 = c["f23_spin_n_m"]
    lam, l0, r0, kg = (c["conicity"], c["half_contact_distance_m"], c["rolling_radius_m"],
                       c["gravitational_stiffness_n_m"])

    def eigenvalue(speed):
        m = np.diag([mass, yaw_inertia])
        damping = np.array([[2 * f22, 2 * f23], [-2 * f23, 2 * f11 * l0**2]]) / speed
        damping[1, 0] += spin_inertia * speed * lam / (r0 * l0)
        stiffness = np.array([[lateral_stiffness + kg, -2 * f22],
                              [2 * f11 * lam * l0 / r0, yaw_stiffness + 2 * f23]])
        a = np.block([[np.zeros((2, 2)), np.eye(2)],
                      [-np.linalg.solve(m, stiffness), -np.linalg.solve(m, damping)]])
        values = np.linalg.eigvals(a)
        values = values[values.imag > 0.0]
        return values[np.argmax(values.real)]

    return eigenvalue


def test_critical_speed_matches_wickens_model(wheelset, critical):
    vehicle, params, stability, coefficients = wheelset
    # the premise of the reference's creep slopes: the steady creepage is longitudinal
    track = stability.track
    steady = stability.steady_and_matrices(critical.speed)[0]
    forces = contact_loads(vehicle, params, track, steady.q, velocities_from_twists(
        steady.q, steady.velocity, steady.angular_velocity))[3]
    assert np.all(np.asarray(forces.creepage_x[0, :, 0]) != 0.0)
    assert np.all(np.asarray(forces.creepage_y[0, :, 0]) == 0.0)
    c = {k: float(v) for k, v in coefficients(params, critical.speed).items()}
    v = trailer_values()
    eigenvalue = _wickens(v["wheelset.mass"] + v["axlebox.mass"],
                          v["wheelset.yaw_inertia"] + v["axlebox.yaw_inertia"],
                          v["wheelset.spin_inertia"],
                          2 * v["primary.lateral_stiffness"],
                          2 * LONGITUDINAL_STIFFNESS * v["axlebox.half_span"] ** 2, c)
    low, high = 10.0, 1000.0
    assert eigenvalue(low).real < 0.0 < eigenvalue(high).real
    for _ in range(80):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if eigenvalue(mid).real < 0.0 else (low, mid)
    assert abs(critical.speed / high - 1.0) < 0.02
    assert abs(critical.eigenvalue.real) < 1e-6 * abs(critical.eigenvalue)
    assert critical.hunting_share > 0.9


def test_free_wheelset_hunts_at_klingels_frequency_as_speed_goes_to_zero(wheelset):
    vehicle, params, stability, coefficients = wheelset
    free = set_values(vehicle, params, ["primary_longitudinal_stiffness",
                                        "primary_lateral_stiffness"], jnp.zeros(2))
    speed = 2.0  # [m/s]: V / L = 0.12 Hz
    c = {k: float(v) for k, v in coefficients(free, speed).items()}
    wavelength = 2 * np.pi * np.sqrt(c["rolling_radius_m"] * c["half_contact_distance_m"]
                                     / c["conicity"])
    point = stability.hunting(speed, free)
    assert abs(point.frequency_hz / (speed / wavelength) - 1.0) < 0.01
    assert abs(point.damping_ratio) < 0.05


def test_bad_inputs_are_named(wheelset, critical):
    vehicle, params, stability, _ = wheelset
    with pytest.raises(ValueError, match="does not bracket.*damping ratio"):
        stability.critical_speed(20.0, 40.0, points=[stability.hunting(20.0),
                                                     stability.hunting(40.0)])
    with pytest.raises(ValueError, match="unknown parameter 'spring'"):
        stability.critical_speed_gradient(critical, ["spring"])
    with pytest.raises(ValueError, match="0 < low < high"):
        stability.critical_speed(50.0, 40.0)
    curved = Track.from_segments([Straight(50.0), Arc(50.0, 300.0)],
                                 allow_curvature_jumps=True)
    with pytest.raises(ValueError, match="straight track or on one circular arc"):
        LinearStability(vehicle, params, curved)


def _with_yaw_dampers(series_stiffness, damping):
    """The fixture's suspended wheelset with a longitudinal Maxwell damper each side,
    frame to axlebox body, 1.3 m from the centreline (a yaw damper's place), unloaded
    at rest."""
    plain, plain_params = suspended_wheelset(conical_wheel(CONE, nominal_radius=0.46))
    v = {**trailer_values(), "primary.longitudinal_stiffness": LONGITUDINAL_STIFFNESS}
    mass, height = frame_mass(v), v["bogie.height"]
    unsprung, _, joints = unsprung_bodies(v, (0.0,))
    guide = Prismatic("ground", "frame", (0.0, 0.0, height), (0.0, 0.0, 0.0),
                      axis_i=(1.0, 0.0, 0.0), axis_j=(1.0, 0.0, 0.0), name="guide")
    springs = [dataclasses.replace(b, stiffness=b.stiffness[:2] + (0.0,) + b.stiffness[3:])
               for b in primary_bushings(v, 1, "frame", 0.0, mass * GRAVITY / 2.0)]
    below = v["wheelset.nominal_radius"] - height
    dampers = [MaxwellDamper("frame", "axlebox_1", (-1.0, y, below), (0.0, y, 0.0),
                             series_stiffness=series_stiffness, free_length=1.0,
                             damping=damping, name=f"yaw_damper_{side}")
               for side, y in (("left", 1.3), ("right", -1.3))]
    system, system_params = build_system(
        [RigidBody("frame", mass, (mass * FRAME_GYRATION_RADIUS**2,) * 3)] + unsprung,
        joints + [guide], springs + dampers, gravity=(0.0, 0.0, -GRAVITY))
    assert system.body_names == plain.system.body_names
    vehicle = Vehicle("suspended wheelset with yaw dampers", system, plain.wheelsets,
                      plain.config, axleboxes=plain.axleboxes)
    return vehicle, VehicleParams(system_params, plain_params.contact, plain_params.wheel,
                                  plain_params.layout)


HUNTING_SPEED = 200.0  # [m/s], below the critical speed


def test_maxwell_dampers_add_their_relaxation_and_leave_hunting_when_they_barely_act(
        wheelset):
    # k_s / c = 1e6 1/s: each damper relaxes at -k_s / c (the bodies, m s^2 ~ 1e15 N/m
    # against k_s = 1e5 N/m, do not move at that rate) and, relaxed at once, acts as a
    # damper of 0.1 N s/m: a yaw damping of 2 c 1.3^2 = 0.34 N m s on the wheelset's
    # 1320 kg m^2, which moves the hunting eigenvalue by about 1e-4 1/s (at 10 N s/m it
    # moved by 7.7e-3 of 52). Rows wired wrongly would leave k_s a yaw spring of
    # 2 k_s 1.3^2 = 0.34 MN m/rad, a sixth of the primary's, or make the relaxation grow.
    vehicle, params, stability, _ = wheelset
    series_stiffness, damping = 1.0e5, 0.1
    damped, damped_params = _with_yaw_dampers(series_stiffness, damping)
    with_dampers = LinearStability(damped, damped_params, stability.track)
    a, c = with_dampers.matrices(HUNTING_SPEED)
    n = vehicle.system.n_bodies
    assert a.shape == (12 * n + 2, 12 * n + 2) and c.shape[1] == 12 * n + 2
    assert stability.matrices(HUNTING_SPEED)[0].shape == (12 * n, 12 * n)
    modes = with_dampers.modes(HUNTING_SPEED)
    relaxation = np.sort(modes.eigenvalues.real)[:2]
    np.testing.assert_allclose(relaxation, -series_stiffness / damping, rtol=1e-6)
    plain = stability.hunting(HUNTING_SPEED)
    hunting = with_dampers.hunting(HUNTING_SPEED)
    assert abs(hunting.eigenvalue - plain.eigenvalue) < 1e-5 * abs(plain.eigenvalue)
    assert len(modes.eigenvalues) == len(stability.modes(HUNTING_SPEED).eigenvalues) + 2
