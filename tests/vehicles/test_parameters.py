"""Named parameters read and write the right numbers of the parameter pytrees."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.normal import Hertz
from jaxrail.profiles.analytic import conical_wheel
from jaxrail.multibody import join_coordinates
from jaxrail.multibody.forces import element_deformation
from jaxrail.track import straight_track
from jaxrail.vehicles import bogie, trailer, trailer_values, vehicle_accelerations
from jaxrail.vehicles.parameters import (PARAMETERS, get_values, set_values,
                                         set_values_and_track)
from jaxrail.vehicles.suspended_wheelset import suspended_wheelset
from jaxrail.vehicles.initial import wheelset_load
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
        get_values(vehicle, eqx.tree_at(lambda p: p.contact, params, hertz), ("restitution",))


def test_every_parameter_has_a_unit():
    assert all(p.unit and p.description for p in PARAMETERS.values())


def test_gauge_and_wheelbase_move_the_rails_the_axles_and_their_seats():
    vehicle, params = trailer()
    track = straight_track(30.0)
    names = ("track_gauge", "wheelbase")
    assert np.allclose(get_values(vehicle, params, names, track),
                       [1.435, 2.0 * VALUES["bogie.semi_wheelbase"]])
    changed, moved = set_values_and_track(vehicle, params, track, names,
                                          jnp.array([1.445, 2.9]))
    # the gauge by brute force: where the rail head is 14 mm below its top, on a 1 um grid
    rail = moved.rails.profile
    y = np.arange(*rail.domain, 1e-6)
    z = np.asarray(jax.vmap(rail.height)(jnp.asarray(y)))
    top = np.argmax(z)
    inside = y[:top][z[:top] >= z[top] - 0.014][0]
    assert abs(2.0 * (float(moved.rails.offset) + inside) - 1.445) < 4e-6
    # the axles 2.9 m apart in each bogie, the carbody and frames where they were
    x = np.asarray(changed.layout[:, 0])
    assert np.allclose(x[np.asarray(vehicle.wheelsets)], [10.95, 8.05, -8.05, -10.95])
    assert np.allclose(x[np.asarray(vehicle.axleboxes)], x[np.asarray(vehicle.wheelsets)])
    assert np.array_equal(x[:3], np.asarray(params.layout[:3, 0]))
    # at the new layout every primary bushing is undeformed: its seat moved with the axle
    n = vehicle.system.n_bodies
    rest = join_coordinates(changed.layout, np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)))
    rest = np.asarray(rest).reshape(n, 7)
    bushing = changed.system.forces["bushing"]
    group = next(g for g in vehicle.system.force_groups if g.kind == "bushing")
    for k in range(len(group.names)):
        element = jax.tree.map(lambda a: a[k], bushing)
        deformation = element_deformation("bushing", rest[group.body_i[k]],
                                          rest[group.body_j[k]], element)
        assert np.max(np.abs(np.asarray(deformation))) < 1e-12, group.names[k]


def test_gauge_and_wheelbase_gradients_under_jit_and_vmap():
    """The bogie's accelerations at a displaced state are differentiable in the gauge and
    the wheelbase (central differences), and vmap over them equals single calls. Two
    programs: the jitted value and gradient (also the single calls), and one jitted vmap
    over the central differences' points and the batch."""
    vehicle, params = bogie()
    track = straight_track(30.0)
    names = ("track_gauge", "wheelbase")
    n = vehicle.system.n_bodies
    layout = np.array(params.layout)
    layout[:, 0] += 10.0
    layout[np.asarray(vehicle.wheelsets), 1] += 4e-3  # wheel flanges near the right rails
    layout[np.asarray(vehicle.wheelsets), 2] = float(params.nominal_radius) - 5e-5
    q = jnp.asarray(join_coordinates(layout, np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))))
    qdot = jnp.zeros_like(q)

    def lateral(x):
        """Squared horizontal accelerations: the gauge moves the contact patches, the
        wheelbase the primary suspension's seats (longitudinal deflection)."""
        trial, moved = set_values_and_track(vehicle, params, track, names, x)
        qddot = vehicle_accelerations(vehicle, trial, moved, 0.0, q, qdot)
        return jnp.sum(qddot.reshape(n, 7)[:, :2] ** 2)

    x = jnp.array([1.437, 2.5])
    value_and_grad = jax.jit(jax.value_and_grad(lateral))
    f, grad = value_and_grad(x)
    assert np.isfinite(f) and np.all(np.isfinite(grad)) and np.all(grad != 0.0)
    h = np.array([1e-6, 1e-6])
    steps = np.diag(h)
    batch = jnp.array([[1.437, 2.5], [1.433, 2.7]])
    # rows: x + h0, x - h0, x + h1, x - h1, then the batch
    points = jnp.concatenate([jnp.stack([x + steps[0], x - steps[0], x + steps[1],
                                         x - steps[1]]), batch])
    evaluated = jax.jit(jax.vmap(lateral))(points)
    for i in range(2):
        central = (evaluated[2 * i] - evaluated[2 * i + 1]) / (2.0 * h[i])
        assert abs(float(grad[i]) / float(central) - 1.0) < 1e-4, (i, grad[i], central)
    # single calls: the value of the jitted value-and-gradient at each batch row
    assert np.allclose(evaluated[4:], [value_and_grad(b)[0] for b in batch], rtol=1e-12)


def test_wheelset_mass_sets_each_wheelset_and_its_load():
    vehicle, params = trailer()
    wheelsets = np.asarray(vehicle.wheelsets)
    assert np.isclose(get_values(vehicle, params, ("wheelset_mass",))[0],
                      VALUES["wheelset.mass"])
    heavier = set_values(vehicle, params, ("wheelset_mass",),
                         jnp.array([VALUES["wheelset.mass"] + 100.0]))
    mass, before = np.asarray(heavier.system.bodies.mass), np.asarray(params.system.bodies.mass)
    assert np.allclose(mass[wheelsets], VALUES["wheelset.mass"] + 100.0)
    assert np.array_equal(np.delete(mass, wheelsets), np.delete(before, wheelsets))
    # each wheelset carries its own 100 kg more: 981 N of wheel load, the sprung load kept
    gain = wheelset_load(vehicle, heavier) - wheelset_load(vehicle, params)
    assert np.isclose(gain, 100.0 * -float(params.system.gravity[2]))


def test_the_cone_angle_of_a_coned_wheel_is_named_and_a_measured_profile_has_none():
    vehicle, params = suspended_wheelset(conical_wheel(0.025))
    steeper = set_values(vehicle, params, ("wheel_cone_angle",), jnp.array([0.03]))
    assert np.isclose(get_values(vehicle, steeper, ("wheel_cone_angle",))[0], 0.03)
    # the profile itself changes: its height 10 mm off centre is -tan(angle) y
    assert np.isclose(float(steeper.wheel.surfaces[0].height(0.01)), -np.tan(0.03) * 0.01)
    s1002_vehicle, s1002_params = suspended_wheelset()
    with pytest.raises(ValueError, match="'S1002' has no cone angle"):
        get_values(s1002_vehicle, s1002_params, ("wheel_cone_angle",))


def test_a_contact_table_refuses_the_geometry_parameters_before_building():
    from jaxrail.montecarlo import run_samples
    from jaxrail.scenarios import load_scenario

    with pytest.raises(ValueError, match=r"\['track_gauge'\]: the contact table is built"):
        run_samples(load_scenario("straight"), {"track_gauge": np.array([1.43, 1.44])},
                    contact="table")


def test_the_gauge_is_the_tracks_and_set_values_says_where_to_set_it():
    vehicle, params = bogie()
    with pytest.raises(ValueError, match="track_gauge is the track's: give get_values the "
                       "track"):
        get_values(vehicle, params, ("track_gauge",))
    with pytest.raises(ValueError, match=r"track_gauge is the track's: set it with "
                       r"set_values_and_track\(vehicle, params, track, names, values\)"):
        set_values(vehicle, params, ("friction", "track_gauge"), jnp.array([0.3, 1.44]))
