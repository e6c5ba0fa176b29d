"""Named parameters made from a vehicle's force elements (``<family>.<field>``)."""

from types import SimpleNamespace

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.vehicles import trailer
from jaxrail.vehicles.element_parameters import element_parameters, family
from jaxrail.vehicles.parameters import get_values, parameter, set_values, vehicle_parameters


@pytest.mark.parametrize("name, expected", [
    ("yaw_damper_1_left", "yaw_damper"), ("primary_3_right", "primary"),
    ("traction_rod_2", "traction_rod"), ("anti_roll_bar", "anti_roll_bar"),
    ("secondary_1_left", "secondary"), ("_1", "_1"),
])
def test_family_drops_repetition_and_mirroring(name, expected):
    assert family(name) == expected


def test_the_trailers_bushing_families_are_parameters_like_the_named_ones():
    """``primary_vertical_stiffness`` (the older names of jaxrail.vehicles.parameters,
    aliases of the bushings' element parameters) reads and writes what
    ``primary.vertical_stiffness`` does: the same numbers, both names listed."""
    vehicle, params = trailer()
    known = vehicle_parameters(vehicle, params)
    assert {"primary.vertical_stiffness", "secondary.lateral_damping",
            "primary.pitch_stiffness"} <= set(known)
    assert known["primary.pitch_stiffness"].unit == "N m/rad"
    assert {"primary_vertical_stiffness", "secondary_lateral_damping"} <= set(known)
    pairs = [("primary.vertical_stiffness", "primary_vertical_stiffness"),
             ("secondary.lateral_damping", "secondary_lateral_damping")]
    for new, old in pairs:
        np.testing.assert_array_equal(get_values(vehicle, params, [new]),
                                      get_values(vehicle, params, [old]))
        a = set_values(vehicle, params, [new], jnp.array([1.234e5]))
        b = set_values(vehicle, params, [old], jnp.array([1.234e5]))
        for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)):
            np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def _damped_vehicle(**damper):
    bodies = [mb.RigidBody("carbody", 1000.0, (1.0, 1.0, 1.0)),
              mb.RigidBody("bogie_1", 100.0, (1.0, 1.0, 1.0))]
    forces = [mb.MaxwellDamper("bogie_1", "carbody", (0, y, 0), (1.0, y, 0), 6e6, 1.0,
                               name=f"yaw_damper_1_{side}", **damper)
              for side, y in (("left", 1.2), ("right", -1.2))]
    system, params = mb.build_system(bodies, forces=forces)
    return SimpleNamespace(system=system, name="test"), _Params(params)


class _Params(eqx.Module):
    """The part of VehicleParams the element parameters read and write."""

    system: mb.SystemParams


def test_a_linear_yaw_dampers_damping_and_series_stiffness():
    vehicle, params = _damped_vehicle(damping=4e5)
    known = element_parameters(vehicle, params)
    assert {"yaw_damper.damping", "yaw_damper.series_stiffness",
            "yaw_damper.free_length"} <= set(known)
    damping = parameter("yaw_damper.damping", vehicle, params)
    assert float(damping.get(vehicle, params)) == pytest.approx(4e5, rel=1e-14)
    changed = damping.set(vehicle, params, 2.5e5)
    e = changed.system.forces["maxwell_damper"]
    np.testing.assert_allclose(e.forces / e.velocities, 2.5e5, rtol=1e-14)
    assert float(damping.get(vehicle, changed)) == pytest.approx(2.5e5, rel=1e-14)
    with pytest.raises(ValueError, match="unknown parameter 'yaw_damper.mass'"):
        parameter("yaw_damper.mass", vehicle, params)


def test_a_blow_off_dampers_damping_is_its_slope_at_rest_and_scales_the_table():
    """400 kN s/m below 8 kN, 40 kN s/m beyond: the damping is 400 kN s/m, and writing
    200 kN s/m halves the force at every velocity of the table."""
    v = [-0.1, -0.02, 0.0, 0.02, 0.1]
    f = [-11.2e3, -8e3, 0.0, 8e3, 11.2e3]
    vehicle, params = _damped_vehicle(velocities=v, forces=f)
    damping = parameter("yaw_damper.damping", vehicle, params)
    assert float(damping.get(vehicle, params)) == pytest.approx(4e5, rel=1e-12)
    changed = damping.set(vehicle, params, 2e5)
    e = changed.system.forces["maxwell_damper"]
    np.testing.assert_allclose(e.velocities[0], 2.0 * np.asarray(v), rtol=1e-14)
    # the gradient of the set value through the table is finite and exact: d/dc of the
    # velocity at the table's 8 kN point is -v c0 / c^2
    grad = jax.grad(lambda c: damping.set(vehicle, params, c).system.forces[
        "maxwell_damper"].velocities[0, 3])(jnp.float64(2e5))
    assert float(grad) == pytest.approx(-0.02 * 4e5 / 2e5**2, rel=1e-12)
