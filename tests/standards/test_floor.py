"""The accelerometer reading at a body point, against closed forms of rigid motions."""

import numpy as np
import pytest

from jaxrail.standards.floor import floor_accelerations


def _turning(rate, heading_accel, t):
    """States of a body yawing about its centre (fixed at the origin) with yaw
    psi = rate t + heading_accel t^2 / 2: q, qdot, qddot (T, 7)."""
    psi = rate * t + 0.5 * heading_accel * t**2
    dpsi = rate + heading_accel * t
    c, s = np.cos(psi / 2), np.sin(psi / 2)
    z = np.zeros_like(t)
    q = np.stack([z, z, z, c, z, z, s], axis=1)
    qdot = np.stack([z, z, z, -0.5 * dpsi * s, z, z, 0.5 * dpsi * c], axis=1)
    qddot = np.stack([z, z, z, -0.25 * dpsi**2 * c - 0.5 * heading_accel * s, z, z,
                      -0.25 * dpsi**2 * s + 0.5 * heading_accel * c], axis=1)
    return q, qdot, qddot


def test_a_yawing_body_reads_centripetal_and_tangential_acceleration_and_gravity():
    t = np.linspace(0.0, 2.0, 21)
    rate, heading_accel, arm = 0.7, 0.3, 4.0
    q, qdot, qddot = _turning(rate, heading_accel, t)
    reading = floor_accelerations(q, qdot, qddot, 0, (arm, 0.0, -1.0))
    dpsi = rate + heading_accel * t
    np.testing.assert_allclose(reading[:, 0], -dpsi**2 * arm, rtol=1e-12)  # to the centre
    np.testing.assert_allclose(reading[:, 1], heading_accel * arm, rtol=1e-12)
    np.testing.assert_allclose(reading[:, 2], 9.81, rtol=1e-12)  # gravity read as +g


def test_a_rolled_body_at_rest_reads_gravity_along_its_tilted_axes():
    roll = 0.05  # [rad] about x: the body's y axis tilts up by roll
    q = np.array([[0.0, 0.0, 1.0, np.cos(roll / 2), np.sin(roll / 2), 0.0, 0.0]])
    reading = floor_accelerations(q, np.zeros((1, 7)), np.zeros((1, 7)), 0, (1.0, 0.5, 0.0))
    np.testing.assert_allclose(reading[0], [0.0, 9.81 * np.sin(roll), 9.81 * np.cos(roll)],
                               atol=1e-12)


@pytest.mark.parametrize("shape", [(3, 14), (3, 2, 7)])
def test_body_axis_layouts_agree(shape):
    rng = np.random.default_rng(1)
    q = rng.normal(size=(3, 14))
    q.reshape(3, 2, 7)[:, :, 3:] /= np.linalg.norm(q.reshape(3, 2, 7)[:, :, 3:], axis=2,
                                                   keepdims=True)
    qdot, qddot = rng.normal(size=(3, 14)), rng.normal(size=(3, 14))
    a = floor_accelerations(q.reshape(shape), qdot.reshape(shape), qddot.reshape(shape), 1,
                            (0.3, 0.2, 0.1))
    b = floor_accelerations(q, qdot, qddot, 1, (0.3, 0.2, 0.1))
    np.testing.assert_array_equal(a, b)
