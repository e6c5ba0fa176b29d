"""The non-spinning axle frame of a wheelset that carries its axleboxes
(jaxrail.multibody.axle_frame): the frame is the axle's yaw and roll whatever the
spin, its derivative matches central differences under jit and vmap, and a bushing on
a spinning axle pulls it back by its own stiffness in each direction, conservatively
(the generalized forces are minus the gradient of the stored energy)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody import quaternion as qt
from jaxrail.multibody.axle_frame import axle_direction, axle_rotation

X, Y, Z = np.eye(3)
K = (3.0e7, 4.0e6, 1.0e6, 2.0e5, 5.0e4, 3.0e5)  # [N/m] x3, [N m/rad] x3


def _euler(yaw, roll, spin):
    """Euler parameters of yaw about z, then roll about the new x, then spin about y."""
    return qt.multiply(qt.multiply(qt.from_axis_angle(Z, yaw), qt.from_axis_angle(X, roll)),
                       qt.from_axis_angle(Y, spin))


@pytest.mark.parametrize("yaw", [0.3, 2.0, -2.9])
@pytest.mark.parametrize("roll", [0.05, -0.11])
def test_the_axle_frame_is_the_yaw_and_roll_whatever_the_spin(yaw, roll):
    expected = np.asarray(_euler(yaw, roll, 0.0))
    for spin in (0.0, 1.3, 4.0, 7.5):
        p = _euler(yaw, roll, spin)
        for scale in (1.0, 1.7):  # any norm of p
            got = np.asarray(axle_rotation(scale * p))
            sign = np.sign(got @ expected)  # p and -p are one orientation
            np.testing.assert_allclose(sign * got, expected, atol=1e-14)
        a = qt.rotation_matrix(axle_rotation(p))
        np.testing.assert_allclose(a[:, 1], axle_direction(p), atol=1e-14)  # y: the axle
        assert abs(float(a[2, 0])) < 1e-14  # x: level


def test_the_axle_frame_under_jit_vmap_and_its_derivative():
    rng = np.random.default_rng(3)
    ps = jnp.stack([_euler(*angles) for angles in rng.uniform(-0.4, 3.0, (5, 3))])
    batched = jax.jit(jax.vmap(axle_rotation))(ps)
    for p, b in zip(ps, batched):
        np.testing.assert_allclose(b, axle_rotation(p), atol=1e-15)
        jacobian = jax.jit(jax.jacfwd(axle_rotation))(p)
        h = 1e-6
        central = np.stack([(axle_rotation(p + h * e) - axle_rotation(p - h * e)) / (2 * h)
                            for e in np.eye(4)], axis=1)
        np.testing.assert_allclose(jacobian, central, atol=1e-8)
        np.testing.assert_allclose(jacobian @ p, 0.0, atol=1e-14)  # blind to |p|
        reverse = jax.grad(lambda x: axle_rotation(x) @ jnp.arange(1.0, 5.0))(p)
        np.testing.assert_allclose(reverse, jacobian.T @ np.arange(1.0, 5.0), atol=1e-13)


def _axle_on_bushings(axle=True):
    """A wheelset held to the ground by bushings at its journals (+-1 m on the axle),
    its elements on the axle frame (``axle``) or on the spinning body."""
    bodies = [mb.RigidBody("wheelset", 1800.0, (1300.0, 110.0, 1300.0))]
    forces = [mb.Bushing("ground", "wheelset", (0.0, y, 0.5), (0.0, y, 0.0), stiffness=K,
                         damping=(1e4,) * 3 + (1e2,) * 3) for y in (1.0, -1.0)]
    return mb.build_system(bodies, forces=forces, axle_bodies=("wheelset",) if axle else ())


def _state(dx, yaw, roll, spin, z=0.5):
    return jnp.concatenate([jnp.array([dx, 0.0, z]), _euler(yaw, roll, spin)])


def test_a_bushing_on_a_spinning_axle_pulls_it_back_by_its_stiffness():
    system, params = _axle_on_bushings()
    dx, zero = 2e-3, jnp.zeros(7)
    for spin in (0.0, 0.9, 3.4):
        q = _state(dx, 0.0, 0.0, spin)
        g = mb.generalized_forces(system, params, 0.0, q, zero)
        np.testing.assert_allclose(g[:3], [-2 * K[0] * dx, 0.0, 0.0], atol=1e-6)
        turn = jax.jvp(lambda b: _state(dx, 0.0, 0.0, b), (spin,), (1.0,))[1]
        assert abs(float(g @ turn)) < 1e-6  # no torque about the axle
    # on the spinning body, the bushings wind up with the wheel's turn about the axle
    system, params = _axle_on_bushings(axle=False)
    g = mb.generalized_forces(system, params, 0.0, _state(dx, 0.0, 0.0, 0.9), zero)
    turn = jax.jvp(lambda b: _state(dx, 0.0, 0.0, b), (0.9,), (1.0,))[1]
    np.testing.assert_allclose(-g @ turn, K[4] * np.sin(1.8), rtol=1e-9)  # 2 k sin cos


def test_the_axle_frame_forces_are_minus_the_gradient_of_the_stored_energy():
    system, params = _axle_on_bushings()
    q = _state(1.5e-3, 0.02, -0.01, 2.2, z=0.503)
    g = mb.generalized_forces(system, params, 0.0, q, jnp.zeros(7))
    energy = jax.grad(lambda x: mb.potential_energy(system, params, x))(q)
    p = q[3:]
    tangent = energy[3:] - p * (energy[3:] @ p) / (p @ p)
    np.testing.assert_allclose(g[:3], -energy[:3], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(g[3:], -tangent, rtol=1e-10, atol=1e-8)
    # the damping: the power the bushings take equals minus the generalized force's
    qdot = jnp.concatenate([jnp.array([0.01, -0.02, 0.005]),
                            jax.jvp(lambda b: _euler(0.02, -0.01, b), (2.2,), (30.0,))[1]])
    damping = (mb.generalized_forces(system, params, 0.0, q, qdot)
               - mb.generalized_forces(system, params, 0.0, q, jnp.zeros(7)))
    np.testing.assert_allclose(-damping @ qdot, mb.dissipated_power(system, params, q, qdot),
                               rtol=1e-10)
