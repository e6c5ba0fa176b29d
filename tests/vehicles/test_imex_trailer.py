"""The stiff wheel-rail loads IMEX treats implicitly, and IMEX on the 11-body trailer.

1. ``wheelset_load_jacobian`` (the force laws differentiated in their six scalar
   inputs, chained with the kinematics by hand) equals forward-mode AD of the whole
   frozen-patch load in the wheelset's 14 coordinates and velocities (a free wheelset
   at rest 4 mm off centre).
2. A load Jacobian kept across steps (``StiffJacobian.turned``) equals the Jacobian
   evaluated at the wheelset turned about its axle.
3. The trailer on the straight from the paper's 2 mm misalignment: IMEX (steps of
   about 1 ms, a new Jacobian every 8 accepted steps) against Tsit5 (about 0.35 ms)
   for 0.4 s, lateral displacements within 0.05 mm and wheel loads within 2 %.
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
from jaxrail.scenarios import load_scenario, parse_scenario
from jaxrail.simulation import SolverOptions, simulate
from jaxrail.vehicles.initial import initial_state
from jaxrail.vehicles.loads import (OnlineContact, VehicleLoads, contact_loads,
                                    wheelset_load_jacobian)
from jaxrail.vehicles.wheel_rail import patch_loads

DURATION = 0.4


@pytest.fixture(scope="module")
def straight():
    scenario = load_scenario("straight")
    vehicle, params, track = scenario.build()
    return scenario, vehicle, params, track


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


@pytest.mark.usefixtures("integrations_at_level_1")
def test_imex_follows_tsit5_on_the_trailer(straight):
    scenario, vehicle, params, track = straight
    results = {}
    for integrator in ("tsit5", "imex"):
        options = SolverOptions(rtol=scenario.rtol, atol=scenario.atol, n_outputs=401,
                                integrator=integrator)
        results[integrator] = simulate(vehicle, params, track, DURATION, scenario.speed,
                                       scenario.misalignment, options=options)
    reference, imex = results["tsit5"], results["imex"]
    assert imex.status == "successful" == reference.status
    lateral = np.abs(np.asarray(imex.wheelset_lateral) - np.asarray(reference.wheelset_lateral))
    assert np.max(lateral) < 5e-5
    loads = [np.nansum(np.asarray(r.wheels.normal_force), axis=-1) for r in (reference, imex)]
    assert np.max(np.abs(loads[1] - loads[0])) < 0.02 * np.max(loads[0])
    assert int(imex.accepted_steps) < 0.5 * int(reference.accepted_steps)
    # the evaluations each run reports (counted: tests/multibody/test_evaluations.py):
    # a Jacobian every 8 accepted steps, again at each rejected attempt of such a step
    assert int(imex.rhs_evaluations) == 8 * int(imex.steps)
    assert (int(imex.accepted_steps) / 8 <= int(imex.jacobian_evaluations)
            <= int(imex.accepted_steps) / 8 + 1 + int(imex.rejected_steps))
    assert int(reference.rhs_evaluations) == 6 * int(reference.steps) + 1
