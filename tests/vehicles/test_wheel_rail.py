"""Wheel-rail loads on a wheelset: Hertz statics, creep direction, lift-off, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact import Hertz, SearchConfig, hertz, wheelset_pose
from jaxrail.contact.kalker import kalker_coefficients
from jaxrail.profiles import s1002
from jaxrail.profiles.analytic import conical_wheel
from jaxrail.track import straight_track
from jaxrail.vehicles import ContactParameters, wheelset_contact_loads
from jaxrail.vehicles.wheel_rail import MIN_CURVATURE_RATIO

WHEEL, TRACK = s1002(), straight_track(20.0)  # UIC60 1:40 at 1435 mm
SPEED = 10.0


@jax.jit
def loads(params, height, yaw, lateral_velocity):
    position, rotation = wheelset_pose(TRACK, 10.0, 0.0, height, 0.0, yaw)
    velocity = jnp.array([SPEED, lateral_velocity, 0.0])
    spin = SPEED / 0.46 * rotation[:, 1]  # rolling about the axle at the nominal radius
    return wheelset_contact_loads(WHEEL, TRACK, params, position, rotation, velocity, spin,
                                  SearchConfig(), 10.0)


def test_static_normal_force_is_hertz():
    """With the pure Hertz law each normal force is K delta^1.5 with K from the
    curvatures, and the resultant is the sum of the patch forces along their normals."""
    params = ContactParameters(normal_law=Hertz())
    force, moment, patches, forces = loads(params, 0.4599, 0.0, 0.0)
    on = np.asarray(patches.active)
    assert on[:, 0].all()
    n = forces.normal_force[on]
    delta = patches.penetration[on]
    np.testing.assert_allclose(n, forces.stiffness[on] * delta**1.5, rtol=1e-12)
    # Independent: the Hertz approach for that load equals the penetration.
    a_sum = 0.5 * patches.curvature_wheel_x[on]
    b_sum = np.maximum(0.5 * patches.curvature_contact_y[on], MIN_CURVATURE_RATIO * a_sum)
    approach = hertz(n, a_sum, b_sum, 8.2e10, 0.28).approach
    np.testing.assert_allclose(approach, delta, rtol=1e-9)
    vertical = np.sum(np.asarray(forces.normal_force)[on] * np.asarray(patches.normal)[on][:, 2])
    # The spin creep force lies in the tilted tangent plane: a small vertical share.
    assert float(force[2]) == pytest.approx(vertical, rel=1e-3)
    assert abs(float(force[1])) < 1e-6 * float(force[2])  # symmetric: no net lateral force
    np.testing.assert_allclose(forces.normal_force[0], forces.normal_force[1], rtol=1e-10)


def test_lateral_creep_force_opposes_lateral_slip_with_kalker_slope():
    """A cylindrical wheel (no spin: it touches the rail crown) sliding sideways slowly:
    each wheel's lateral creep force opposes the slip and equals Kalker's linear law
    -G a b c22 eta."""
    cylinder = conical_wheel(0.0)
    # About 5 um into the crown: a patch narrower than WIDE_FROM, at the deepest point.
    position, rotation = wheelset_pose(TRACK, 10.0, 0.0, 0.46 + 8.9e-5, 0.0, 0.0)
    slip = 1e-5 * SPEED
    run = jax.jit(wheelset_contact_loads)
    params = ContactParameters(normal_law=Hertz())
    args = (cylinder, TRACK, params, position, rotation, jnp.array([SPEED, slip, 0.0]))
    patch = run(*args, SPEED / 0.46 * rotation[:, 1])[2]
    depth = float(jnp.linalg.norm(patch.wheel_point[0, 0] - patch.rail_point[0, 0]))
    # Roll freely: the interface (half the overlap at the contact point below the wheel
    # surface) has no slip.
    _, _, patches, forces = run(*args, SPEED / (0.46 - 0.5 * depth) * rotation[:, 1])
    assert np.asarray(patches.active[:, 0]).all()
    np.testing.assert_allclose(forces.creepage_x[:, 0], 0.0, atol=1e-9)
    np.testing.assert_allclose(forces.spin[:, 0], 0.0, atol=1e-6)
    eta = np.asarray(forces.creepage_y[:, 0])
    assert np.all(eta > 0.0)
    a, b = np.asarray(forces.semi_axis_a[:, 0]), np.asarray(forces.semi_axis_b[:, 0])
    _, c22, _ = kalker_coefficients(a / b, 0.28)
    expected = -8.2e10 * a * b * np.asarray(c22) * eta
    np.testing.assert_allclose(forces.creep_force_y[:, 0], expected, rtol=1e-3)


def _lateral_plus_vertical(scale, mu, height, yaw):
    params = ContactParameters(friction=mu, stiffness_scale=scale)
    force = loads(params, height, yaw, 0.0)[0]
    return force[1] + force[2]


force_gradient = jax.jit(jax.grad(_lateral_plus_vertical, argnums=(0, 1)))


def test_lift_off_gives_zero_loads_and_finite_gradients():
    force, moment, patches, _ = loads(ContactParameters(), 0.463, 0.0, 0.0)
    assert not bool(jnp.any(patches.active))
    assert float(jnp.max(jnp.abs(force))) == 0.0 and float(jnp.max(jnp.abs(moment))) == 0.0
    gradient = force_gradient(1.0, 0.3, 0.463, 0.0)
    assert np.all(np.isfinite(gradient)) and np.all(np.asarray(gradient) == 0.0)


def test_gradients_wrt_stiffness_and_friction_match_finite_differences():
    """d(lateral + vertical force)/d(stiffness scale, friction) at a yawed, rolling
    wheelset, against central differences."""
    grad = force_gradient(1.0, 0.3, 0.4599, 2e-3)
    for k, h in enumerate((1e-6, 1e-6)):
        plus, minus = [1.0, 0.3], [1.0, 0.3]
        plus[k] += h
        minus[k] -= h
        fd = (_lateral_plus_vertical(*plus, 0.4599, 2e-3)
              - _lateral_plus_vertical(*minus, 0.4599, 2e-3)) / (2 * h)
        assert float(grad[k]) == pytest.approx(float(fd), rel=1e-5, abs=1e-6)
        assert float(grad[k]) != 0.0
