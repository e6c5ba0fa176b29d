"""A compound pendulum on a revolute joint to the ground: the small-angle period, and
jit + vmap + grad through one diffrax simulation (the pivot distance as parameter).

The pivot is the body point (0, 0, d) above the centre of mass, on the global y axis
through the origin; gravity is -z; theta is the rotation about y. One compiled
function, vmap(value_and_grad(...)) over a batch of pivot distances, serves all
checks (reverse-mode AD through diffrax is expensive to compile).
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody import quaternion as qt

G, MASS, J_YY = 9.81, 1.5, 0.03
THETA0 = 0.01  # [rad], released from rest
FD_STEP = 1e-4
LENGTHS = (0.1, 0.25, 0.5, 0.8)  # [m]; the FD pair is centred on LENGTHS[2]
T_END, N_SAVE = 5.0, 1001

PENDULUM, PARAMS = mb.build_system(
    [mb.RigidBody("link", MASS, (0.02, J_YY, 0.01))],
    joints=[mb.Revolute("link", "ground", (0.0, 0.0, 0.5), (0.0, 0.0, 0.0),
                        axis_i=(0.0, 1.0, 0.0), axis_j=(0.0, 1.0, 0.0))],
    gravity=(0.0, 0.0, -G),
    baumgarte=(20.0, 20.0),
)


def final_angle(pivot_distance, ts):
    """(theta(ts[-1]), theta(ts)) [rad]."""
    params = eqx.tree_at(lambda p: p.joints["revolute"].point_i, PARAMS,
                         jnp.zeros((1, 3)).at[0, 2].set(pivot_distance))
    p0 = qt.from_axis_angle(jnp.array([0.0, 1.0, 0.0]), jnp.asarray(THETA0))
    r0 = -qt.rotation_matrix(p0) @ params.joints["revolute"].point_i[0]
    sol = mb.simulate_system(mb.SystemLoads(PENDULUM, params), jnp.concatenate([r0, p0]),
                             jnp.zeros(7), ts[-1], dt0=1e-3, saveat=diffrax.SaveAt(ts=ts),
                             rtol=1e-11, atol=1e-11)
    q = sol.ys.q
    theta = 2.0 * jnp.arctan2(q[:, 5], q[:, 3])
    return theta[-1], theta


batch_angle_and_gradient = jax.jit(
    jax.vmap(jax.value_and_grad(final_angle, has_aux=True), in_axes=(0, None))
)


@pytest.fixture(scope="module")
def batch():
    d = np.array(LENGTHS + (LENGTHS[2] - FD_STEP, LENGTHS[2] + FD_STEP))
    ts = jnp.linspace(0.0, T_END, N_SAVE)
    (final, theta), grad = batch_angle_and_gradient(jnp.asarray(d), ts)
    return d, np.asarray(ts), np.asarray(final), np.asarray(theta), np.asarray(grad)


def small_angle_period(d):
    return 2.0 * np.pi * np.sqrt((J_YY + MASS * d**2) / (MASS * G * d))


def measured_period(t, theta):
    """Mean period from the downward zero crossings, linearly interpolated."""
    i = np.nonzero((theta[:-1] > 0.0) & (theta[1:] <= 0.0))[0]
    crossings = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    assert len(crossings) >= 3
    return (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def test_pendulum_matches_the_small_angle_period(batch):
    d, ts, _, theta, _ = batch
    for k in range(len(LENGTHS)):
        expected = small_angle_period(d[k]) * (1.0 + THETA0**2 / 16.0)  # amplitude
        period = measured_period(ts, theta[k])
        assert abs(period / expected - 1.0) < 1e-6, (d[k], period, expected)
        assert abs(np.max(theta[k]) - THETA0) < 1e-9  # amplitude kept: no energy drift
    # The check can tell the lengths apart.
    assert abs(small_angle_period(0.1) / small_angle_period(0.25) - 1.0) > 1e-3


def test_grad_of_final_angle_wrt_pivot_distance_matches_finite_differences(batch):
    _, _, final, _, grad = batch
    assert np.all(np.isfinite(grad))
    fd = (final[-1] - final[-2]) / (2.0 * FD_STEP)
    assert abs(grad[2]) > 1e-2  # a real sensitivity, not a trivially zero one
    np.testing.assert_allclose(grad[2], fd, rtol=1e-5)
    # The batch really differs: each length ends at another angle.
    assert np.min(np.abs(np.diff(final[: len(LENGTHS)]))) > 1e-4
