"""The stiff wheel-rail loads IMEX treats implicitly.

1. ``wheelset_load_jacobian`` (the force laws differentiated in their six scalar
   inputs, chained with the kinematics by hand) equals forward-mode AD of the whole
   frozen-patch load in the wheelset's 14 coordinates and velocities (a free wheelset
   at rest 4 mm off centre).
2. A load Jacobian kept across steps (``StiffJacobian.turned``) equals the Jacobian
   evaluated at the wheelset turned about its axle.

IMEX against Tsit5 on the 11-body trailer is in tests/vehicles/test_trailer.py, where it
runs on the programs of that module's ``jaxrail simulate`` run.
"""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.multibody import State
from jaxrail.multibody import quaternion as qt
from jaxrail.multibody.forces import body_torque
from jaxrail.multibody.imex import stiff_jacobian
from jaxrail.scenarios import parse_scenario
from jaxrail.vehicles.initial import initial_state
from jaxrail.vehicles.loads import (OnlineContact, VehicleLoads, contact_loads,
                                    wheelset_load_jacobian)
from jaxrail.vehicles.wheel_rail import patch_loads


def brute_force_jacobian(contact, patches, q_body, qdot_body):
    """The same derivative by jacfwd through patch_loads, penetration moved along
    each normal by the wheel point's displacement."""
    r, p = q_body[:3], q_body[3:]

    def load(dq, dqdot):
        moved_p = p + dq[3:]
        omega = 2.0 * qt.e_matrix(moved_p) @ (qdot_body[3:] + dqdot[3:])
        turn = 2.0 * qt.e_matrix(p) @ dq[3:]
        shift = dq[:3] + jnp.cross(turn, patches.wheel_point - r)
        moved = eqx.tree_at(lambda x: x.penetration, patches,
                            patches.penetration - jnp.sum(shift * patches.normal, axis=-1))
        force, moment, _ = patch_loads(contact, moved, r, qdot_body[:3] + dqdot[:3], omega)
        return jnp.concatenate([force, body_torque(moved_p, moment)[3:]])

    zero = jnp.zeros(7)
    return jnp.concatenate(jax.jacfwd(load, argnums=(0, 1))(zero, zero), axis=1)


@pytest.fixture(scope="module")
def wheelset():
    """A free wheelset's rest pose 4 mm off centre, rolling (the per-wheelset loads are
    the trailer's; its lighter equilibrium compiles in a fraction of the time)."""
    scenario = parse_scenario((Path(__file__).parents[1] / "data" / "wheelset-straight.toml")
                              .read_text())
    vehicle, params, track = scenario.build()
    # compiled: twice as fast as eager
    state = eqx.filter_jit(initial_state)(vehicle, params, track, scenario.speed, 0.004,
                                          None, OnlineContact())
    return vehicle, params, track, state.q, state.qdot


def test_wheelset_load_jacobian_equals_brute_force_ad(wheelset):
    vehicle, params, track, q, qdot = wheelset
    _, torques, patches, _ = jax.jit(lambda a, b: contact_loads(
        vehicle, params, track, a, b))(q, qdot)
    k = vehicle.wheelsets[0]
    one = jax.tree.map(lambda x: x[0], patches)
    q_body, qdot_body = q.reshape(-1, 7)[k], qdot.reshape(-1, 7)[k]
    fast = jax.jit(wheelset_load_jacobian)(params.contact, one, q_body, qdot_body, torques[k])
    slow = jax.jit(brute_force_jacobian)(params.contact, one, q_body, qdot_body)
    assert np.all(np.isfinite(fast))
    np.testing.assert_allclose(fast, slow, rtol=1e-8, atol=1e-6 * float(jnp.max(jnp.abs(slow))))


def test_a_kept_jacobian_turns_with_the_wheelset(wheelset):
    """IMEX keeps J between refreshes and carries it by each wheelset's turn about its
    axle: J.turned(t) must equal J evaluated at the wheelset turned by t (Euler
    parameters and their rates multiplied by t), the loads of a body of revolution
    being the same. 0.7 rad changes J itself by about a third."""
    vehicle, params, track, q, qdot = wheelset
    loads = VehicleLoads(vehicle, params, track, OnlineContact())
    jacobian = jax.jit(lambda a, b: stiff_jacobian(0.0, State.of(a, b), loads)[1])
    k = vehicle.wheelsets[0]
    turn = qt.from_axis_angle(jnp.array([0.0, 1.0, 0.0]), 0.7)
    positions, velocities = q.reshape(-1, 7), qdot.reshape(-1, 7)
    turned_q = positions.at[k, 3:].set(qt.multiply(positions[k, 3:], turn)).ravel()
    turned_qdot = velocities.at[k, 3:].set(qt.multiply(velocities[k, 3:], turn)).ravel()
    here, there = jacobian(q, qdot), jacobian(turned_q, turned_qdot)
    carried = jax.jit(lambda j, t: j.turned(t))(here, turn[None])
    for name in ("a_q", "a_v"):
        before, after, kept = (np.asarray(getattr(j, name)) for j in (here, there, carried))
        scale = np.max(np.abs(after))
        assert np.max(np.abs(after - before)) > 0.2 * scale  # the turn matters
        np.testing.assert_allclose(kept, after, rtol=0, atol=1e-5 * scale)
