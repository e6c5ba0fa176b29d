"""The linearisation's rows of force elements with internal states, against closed
forms, on systems without contact (milliseconds to compile): the co-moving rates
(:func:`jaxrail.stability.linear.comoving_rates`) that :func:`linear_system` and the
standing modes both linearise."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.multibody import (MaxwellDamper, Prismatic, RigidBody, SpringDamper,
                               accelerations, build_system, join_coordinates)
from jaxrail.stability.linear import (SteadyMotion, comoving_rates, element_state_count,
                                      joint_rows, state_basis)

ROOTS = 1e-6  # relative, each root of the closed form
MASS, STIFFNESS = 500.0, 2.0e5  # [kg], [N/m]
HEIGHT = 1.0  # [m]: the mass above its ground point, the springs' free length


def _mass_on_springs(series_stiffness, damping):
    """One mass sliding vertically (a prismatic joint to the ground) on a spring k and a
    Maxwell element (k_s, c) to the ground, both unloaded at rest; its eigenvalues on
    the joint's tangent space, internal state included."""
    bodies = [RigidBody("mass", MASS, (10.0, 10.0, 10.0))]
    joints = [Prismatic("ground", "mass", (0.0, 0.0, HEIGHT), (0.0, 0.0, 0.0),
                        axis_i=(0.0, 0.0, 1.0), axis_j=(0.0, 0.0, 1.0))]
    forces = [SpringDamper("ground", "mass", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                           stiffness=STIFFNESS, free_length=HEIGHT),
              MaxwellDamper("ground", "mass", (0.1, 0.0, 0.0), (0.1, 0.0, 0.0),
                            series_stiffness=series_stiffness, free_length=HEIGHT,
                            damping=damping)]
    system, params = build_system(bodies, joints, forces)
    q = join_coordinates(jnp.array([[0.0, 0.0, HEIGHT]]), jnp.array([[1.0, 0.0, 0.0, 0.0]]))
    zero = jnp.zeros((1, 3))
    steady = SteadyMotion(q, zero, zero, jnp.zeros(3), jnp.zeros(3))
    z0 = jnp.zeros(12 + element_state_count(system))

    def accelerate(q, qdot, elements):
        return accelerations(system, params, 0.0, q, qdot, None, elements)[0]

    a = jax.jacfwd(comoving_rates)(z0, system, params, steady, accelerate)
    c = jax.jacfwd(joint_rows, argnums=2)(system, params, z0, steady)
    basis = state_basis(c, 1)
    return a, c, basis, np.linalg.eigvals(basis.T @ np.asarray(a) @ basis)


@pytest.mark.parametrize("series_stiffness, damping", [(8.0e5, 3.0e3), (2.0e6, 4.0e4),
                                                       (5.0e4, 1.0e2)])
def test_a_mass_on_a_spring_and_a_maxwell_element_has_the_cubics_roots(series_stiffness,
                                                                         damping):
    # m x'' = -k x - k_s (x - z), c z' = k_s (x - z):
    # m c s^3 + m k_s s^2 + c (k + k_s) s + k k_s = 0
    a, c, basis, values = _mass_on_springs(series_stiffness, damping)
    assert a.shape == (13, 13) and c.shape == (10, 13) and basis.shape == (13, 3)
    assert np.all(np.asarray(c)[:, 12] == 0.0)  # no joint ties the internal state
    np.testing.assert_array_equal(basis[12], [0.0, 0.0, 1.0])
    expected = np.roots([MASS * damping, MASS * series_stiffness,
                         damping * (STIFFNESS + series_stiffness),
                         STIFFNESS * series_stiffness])
    for root in expected:
        nearest = values[np.argmin(np.abs(values - root))]
        assert abs(nearest - root) < ROOTS * abs(root), (root, nearest)


def test_a_stiff_body_leaves_the_maxwell_elements_relaxation_root_at_minus_ks_over_c():
    # k_s / c = 1e4 1/s, far above the mass's sqrt(k / m) = 20 rad/s: the mass hardly
    # moves at that rate, and the root is -k_s / c within (k + k_s) / (m (k_s / c)^2)
    series_stiffness, damping = 1.0e5, 10.0
    values = _mass_on_springs(series_stiffness, damping)[3]
    relaxation = values[np.argmin(values.real)]
    assert relaxation.imag == 0.0
    assert abs(relaxation / (-series_stiffness / damping) - 1.0) < 1e-4
