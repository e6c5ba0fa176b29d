"""One strip against the rail: the depth's derivatives need none of the rail foot's, and
derivatives of derivatives follow the foot."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail import enable_float64

enable_float64()

from jaxrail.contact.strip import strip_point, wheel_frame  # noqa: E402
from jaxrail.profiles import s1002, uic60  # noqa: E402

WHEEL = s1002()
RAIL = uic60("1:40")
RAIL_AXES = jnp.eye(3)  # t, n, b: straight rail along x, left rail (side +1)
STRIPS = jnp.array([-0.04, -0.03, -0.01, 0.0, 0.012, 0.03])  # flange root to field tread


def _strips(pose, foot_derivatives=True, rail=RAIL):
    """The strips of a wheel whose profile origin is at (0, y, z) [m] and whose axle is
    yawed by ``psi`` [rad] and rolled by ``phi`` [rad] (a StripPoint of arrays)."""
    y, z, psi, phi = pose
    axle = jnp.array([-jnp.sin(psi) * jnp.cos(phi), jnp.cos(psi) * jnp.cos(phi), jnp.sin(phi)])
    frame = wheel_frame(axle, RAIL_AXES[:, 0])
    origin = jnp.array([0.0, y, z])
    return jax.vmap(lambda s: strip_point(WHEEL.surfaces[0], WHEEL.nominal_radius, rail, s,
                                          origin, frame, jnp.zeros(3), RAIL_AXES, 1.0,
                                          foot_derivatives))(STRIPS)


def _depths(pose, foot_derivatives):
    return _strips(pose, foot_derivatives).depth


def _converged(pose):
    """Strips whose rail foot converged inside the rail domain (the others are far
    from contact: their depth has no meaning, see ``rail_foot``)."""
    return np.asarray(_strips(pose).rail_inside) > 0.5


POSE = jnp.array([2e-3, 0.46 - 2e-4, 0.02, 0.01])


def test_depth_jacobian_without_foot_derivatives_is_exact():
    with_foot = jax.jit(jax.jacfwd(lambda p: _depths(p, True)))(POSE)
    without = jax.jit(jax.jacfwd(lambda p: _depths(p, False)))(POSE)
    reverse = jax.jit(jax.jacrev(lambda p: _depths(p, False)))(POSE)
    assert np.all(np.isfinite(without))
    converged = _converged(POSE)
    assert converged.sum() >= 4
    np.testing.assert_allclose(without[converged], with_foot[converged], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(reverse, without, rtol=1e-12, atol=1e-15)
    # Central differences (independent of any derivative rule).
    steps = np.array([1e-7, 1e-7, 1e-6, 1e-6])
    for j, h in enumerate(steps):
        e = jnp.zeros(4).at[j].set(h)
        fd = (_depths(POSE + e, False) - _depths(POSE - e, False)) / (2 * h)
        np.testing.assert_allclose(without[converged, j], fd[converged], rtol=1e-6, atol=1e-9)


def test_rail_foot_without_derivatives_is_constant_to_autodiff():
    def feet(pose, foot_derivatives):
        return _strips(pose, foot_derivatives).y_rail

    assert np.all(jax.jacfwd(lambda p: feet(p, False))(POSE) == 0.0)
    assert np.any(jax.jacfwd(lambda p: feet(p, True))(POSE) != 0.0)


@pytest.mark.parametrize("field, foot_derivatives", [("depth", False), ("depth", True),
                                                     ("y_rail", True)])
def test_second_derivatives_follow_the_foot(field, foot_derivatives):
    """Derivatives of derivatives (the critical speed's gradient differentiates the
    linearised equations of motion): the Hessian of the depth (its foot frozen or not)
    and of the rail foot in the wheel's pose and the rail's inclination, against central
    differences of their Jacobians. A plain Newton step from the stopped foot, exact to
    first order only, fails it: the frozen foot's depth Hessian lacks the foot's motion
    and the foot's own Hessian is off by up to 8 times."""
    def value(x):
        rail = eqx.tree_at(lambda r: r.inclination, RAIL, x[4])
        return getattr(_strips(x[:4], foot_derivatives, rail), field)

    x0 = jnp.concatenate([POSE, jnp.array([RAIL.inclination])])
    jacobian = jax.jit(jax.jacfwd(value))
    hessian = np.asarray(jax.jit(jax.jacfwd(jax.jacfwd(value)))(x0))  # (strips, 5, 5)
    converged = _converged(POSE)
    assert np.all(np.isfinite(hessian[converged]))
    for j, h in enumerate([1e-6, 1e-6, 1e-5, 1e-5, 1e-5]):
        e = jnp.zeros(5).at[j].set(h)
        central = (np.asarray(jacobian(x0 + e)) - np.asarray(jacobian(x0 - e))) / (2 * h)
        scale = np.abs(central[converged]).max()
        np.testing.assert_allclose(hessian[converged][:, :, j], central[converged],
                                   rtol=1e-5, atol=1e-6 * scale)
