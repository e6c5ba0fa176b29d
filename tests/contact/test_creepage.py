"""Creepages from rigid-body kinematics: rolling, slip, yaw, conicity, standstill, AD."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.creepage import creepages
from jaxrail.contact.polach import polach

V, R = 30.0, 0.46  # forward speed [m/s], rolling radius [m]
EX, EY, EZ = np.eye(3)
FLAT_FRAME = np.eye(3)  # columns t = x, l = y, n = z


def _axle_rotation(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _creep_vec(v, w, c, p, frame, v_rail, w_rail, speed):
    return jnp.stack(creepages(v, w, c, p, frame, v_rail, w_rail, rolling_speed=speed))


def _creep_default_speed(v, w, c, p, frame):
    return jnp.stack(creepages(v, w, c, p, frame))


creep = jax.jit(_creep_vec)
creep_default = jax.jit(_creep_default_speed)
creep_batch = jax.jit(jax.vmap(_creep_default_speed))
polach_jit = jax.jit(polach)


def wheel_state(yaw=0.0, slip=0.0, lateral_speed=0.0):
    """Velocity, angular velocity, centre, contact point of a wheel rolling forward."""
    axle = _axle_rotation(yaw) @ EY
    omega = (1.0 - slip) * V / R * axle  # top of the wheel moves forward
    centre = np.array([0.0, 0.75, R])
    point = centre - R * EZ
    velocity = V * EX + lateral_speed * EY
    return velocity, omega, centre, point


def test_pure_rolling_gives_zero_creepage():
    v, w, c, p = wheel_state()
    xi, eta, phi = np.array(creep_default(v, w, c, p, FLAT_FRAME))
    assert abs(xi) < 1e-15 and abs(eta) < 1e-15 and abs(phi) < 1e-15
    # the same wheel rolling with the wrong sense of rotation slips at 2V
    xi, _, _ = np.array(creep(v, -w, c, p, FLAT_FRAME, np.zeros(3), np.zeros(3), V))
    assert xi == pytest.approx(2.0, rel=1e-14)


def test_known_longitudinal_and_lateral_slip():
    # omega = (1 - k) V / r: the contact point moves forward at k V over the rail
    k, vy = 0.004, 0.09
    v, w, c, p = wheel_state(slip=k, lateral_speed=vy)
    xi, eta, phi = np.array(creep(v, w, c, p, FLAT_FRAME, np.zeros(3), np.zeros(3), V))
    assert xi == pytest.approx(k, rel=1e-12)
    assert eta == pytest.approx(vy / V, rel=1e-12)
    assert phi == 0.0
    # default rolling speed: sqrt(V^2 + v_reg^2), relative effect v_reg^2 / (2 V^2)
    xi_d, _, _ = np.array(creep_default(v, w, c, p, FLAT_FRAME))
    assert xi_d == pytest.approx(k * V / math.sqrt(V**2 + 0.01**2), rel=1e-12)
    assert abs(xi_d / k - 1) < 1e-7


def test_moving_rail_is_subtracted():
    # On a roller rig the wheel centre is fixed and the rail moves backwards at V.
    v, w, c, p = wheel_state()
    xi, eta, phi = np.array(creep(v - V * EX, w, c, p, FLAT_FRAME, -V * EX, np.zeros(3), V))
    assert abs(xi) < 1e-15 and abs(eta) < 1e-15 and abs(phi) < 1e-15
    # a rail rotating about the normal adds to the spin with the opposite sign
    *_, phi = np.array(creep(v, w, c, p, FLAT_FRAME, np.zeros(3), 0.3 * EZ, V))
    assert phi == pytest.approx(-0.3 / V, rel=1e-14)


@pytest.mark.parametrize("yaw", [-0.02, 0.005, 0.03])
def test_yawed_wheelset(yaw):
    # Nose turned left by yaw (about +z), moving along +x: xi = 1 - cos, eta = -sin.
    v, w, c, p = wheel_state(yaw=yaw)
    xi, eta, phi = np.array(creep(v, w, c, p, FLAT_FRAME, np.zeros(3), np.zeros(3), V))
    assert xi == pytest.approx(1.0 - math.cos(yaw), rel=1e-9, abs=1e-15)
    assert eta == pytest.approx(-math.sin(yaw), rel=1e-12)
    assert abs(phi) < 1e-15
    # ... and the Polach force on the wheel pushes back (steers the nose to the right)
    fx, fy = polach_jit(8e4, 0.4, 6e-3, 4e-3, xi, eta, phi)
    assert float(fy) * yaw > 0


@pytest.mark.parametrize("gamma", [0.025, 0.4, 1.1])
def test_spin_of_a_coned_wheel(gamma):
    v, w, c, p = wheel_state()
    # left wheel: normal leans towards the track centre, n = (0, -sin g, cos g)
    n_left = np.array([0.0, -math.sin(gamma), math.cos(gamma)])
    frame_left = np.column_stack([EX, np.cross(n_left, EX), n_left])
    *_, phi_left = np.array(creep(v, w, c, p, frame_left, np.zeros(3), np.zeros(3), V))
    assert phi_left == pytest.approx(-math.sin(gamma) / R, rel=1e-13)
    # right wheel (mirror): n = (0, +sin g, cos g) and phi = +sin(gamma)/r
    n_right = np.array([0.0, math.sin(gamma), math.cos(gamma)])
    frame_right = np.column_stack([EX, np.cross(n_right, EX), n_right])
    c_r = c * [1, -1, 1]
    p_r = p * [1, -1, 1]
    *_, phi_right = np.array(creep(v, w, c_r, p_r, frame_right, np.zeros(3), np.zeros(3), V))
    assert phi_right == pytest.approx(math.sin(gamma) / R, rel=1e-13)
    # the frame is right-handed: t x l = n
    np.testing.assert_allclose(np.cross(frame_left[:, 0], frame_left[:, 1]), n_left, atol=1e-15)


def test_standstill_is_finite():
    # stopped wheel with a small slip: creepage = slip / v_reg, finite gradients
    v = np.zeros(3)
    w = 0.002 / R * EY  # contact point slips backwards at 2 mm/s
    c = np.array([0.0, 0.75, R])
    p = c - R * EZ
    xi, eta, phi = np.array(creep_default(v, w, c, p, FLAT_FRAME))
    assert xi == pytest.approx(-0.002 / 0.01, rel=1e-12)
    jac = jax.jit(jax.jacrev(_creep_default_speed, argnums=(0, 1, 2, 3, 4)))(v, w, c, p, FLAT_FRAME)
    assert all(np.all(np.isfinite(np.array(j))) for j in jac)
    # all-zero state
    xi, eta, phi = np.array(creep_default(v, 0 * w, c, p, FLAT_FRAME))
    assert xi == eta == phi == 0.0


def test_grad_matches_central_differences():
    rng = np.random.default_rng(3)
    v, w, c, p = wheel_state(yaw=0.01, slip=0.002, lateral_speed=0.05)
    w = w + 0.3 * rng.normal(size=3)
    p = p + 0.01 * rng.normal(size=3)
    gamma = 0.3
    n = np.array([0.0, -math.sin(gamma), math.cos(gamma)])
    frame = np.column_stack([EX, np.cross(n, EX), n])
    args = [v, w, c, p, frame]
    jac = jax.jit(jax.jacrev(_creep_default_speed, argnums=(0, 1, 2, 3, 4)))(*args)
    for i, a in enumerate(args):
        fd = np.zeros((3,) + a.shape)
        for idx in np.ndindex(a.shape):
            h = 1e-6 * max(1.0, abs(a[idx]))
            plus = [x.copy() for x in args]
            minus = [x.copy() for x in args]
            plus[i][idx] += h
            minus[i][idx] -= h
            fd[(slice(None),) + idx] = (
                np.array(creep_default(*plus)) - np.array(creep_default(*minus))
            ) / (2 * h)
        np.testing.assert_allclose(np.array(jac[i]), fd, rtol=1e-6, atol=1e-8)


def test_vmap_over_contacts():
    states = [wheel_state(yaw=y, slip=s) for y, s in [(0.0, 0.0), (0.01, 0.0), (0.0, 0.003), (-0.02, 0.001)]]
    v, w, c, p = (np.stack(x) for x in zip(*states))
    frames = np.broadcast_to(FLAT_FRAME, (4, 3, 3))
    batched = np.array(creep_batch(v, w, c, p, frames))
    for i in range(4):
        single = np.array(creep_default(v[i], w[i], c[i], p[i], FLAT_FRAME))
        np.testing.assert_allclose(batched[i], single, rtol=1e-14)


def test_bad_shapes_raise():
    v, w, c, p = wheel_state()
    with pytest.raises(ValueError, match="wheel_velocity"):
        creepages(v[:2], w, c, p, FLAT_FRAME)
    with pytest.raises(ValueError, match="contact_frame"):
        creepages(v, w, c, p, FLAT_FRAME[:, :2])
    with pytest.raises(ValueError, match="rail_velocity"):
        creepages(v, w, c, p, FLAT_FRAME, rail_velocity=np.zeros(4))
    with pytest.raises(ValueError, match="speed_regularisation"):
        creepages(v, w, c, p, FLAT_FRAME, speed_regularisation=0.0)
