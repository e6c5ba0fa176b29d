"""Named parameters read and write the right numbers of the parameter pytrees."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.normal import Hertz
from jaxrail.identify import PARAMETERS, get_values, set_values
from jaxrail.vehicles import bogie, trailer, trailer_values
from jaxrail.vehicles.wheel_rail import ContactParameters

VALUES = trailer_values()


def test_values_are_the_vehicle_data():
    vehicle, params = trailer()
    names = ("contact_stiffness", "friction", "restitution", "primary_lateral_stiffness",
             "primary_vertical_damping", "secondary_lateral_damping",
             "secondary_vertical_stiffness")
    expected = [1.0, 0.4, 0.8, VALUES["primary.lateral_stiffness"],
                VALUES["primary.vertical_damping"], VALUES["secondary.lateral_damping"],
                VALUES["secondary.vertical_stiffness"]]
    assert np.allclose(get_values(vehicle, params, names), expected)


def test_set_changes_only_its_family_and_column():
    vehicle, params = trailer()
    changed = set_values(vehicle, params, ("primary_lateral_stiffness",), jnp.array([1.0e6]))
    before = params.system.forces["bushing"].stiffness
    after = changed.system.forces["bushing"].stiffness
    names = next(g.names for g in vehicle.system.force_groups if g.kind == "bushing")
    primary = np.array([n.startswith("primary_") for n in names])
    assert np.all(after[primary, 1] == 1.0e6)
    assert np.array_equal(np.delete(np.asarray(after), 1, axis=1),
                          np.delete(np.asarray(before), 1, axis=1))
    assert np.array_equal(after[~primary], before[~primary])


def test_gradient_flows_to_the_set_value():
    vehicle, params = bogie()
    names = ("friction", "primary_vertical_damping")

    def f(v):
        p = set_values(vehicle, params, names, v)
        return p.contact.friction**2 + jnp.sum(p.system.forces["bushing"].damping[:, 2])

    grad = jax.grad(f)(jnp.array([0.3, 5000.0]))
    assert np.allclose(grad, [0.6, 4.0])  # the bogie has four primary bushings


def test_missing_parameters_are_named():
    vehicle, params = bogie()
    with pytest.raises(ValueError, match="no secondary suspension"):
        get_values(vehicle, params, ("secondary_lateral_stiffness",))
    with pytest.raises(ValueError, match="unknown parameter 'stiffness'.*contact_stiffness"):
        get_values(vehicle, params, ("stiffness",))
    hertz = ContactParameters(normal_law=Hertz())
    with pytest.raises(ValueError, match="Hertz has no restitution"):
        get_values(vehicle, type(params)(params.system, hertz), ("restitution",))


def test_every_parameter_has_a_unit():
    assert all(p.unit and p.description for p in PARAMETERS.values())
