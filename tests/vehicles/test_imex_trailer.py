"""The stiff wheel-rail loads IMEX treats implicitly, and IMEX on the 11-body trailer.

1. ``wheelset_load_jacobian`` (the force laws differentiated in their six scalar
   inputs, chained with the kinematics by hand) equals forward-mode AD of the whole
   frozen-patch load in the wheelset's 14 coordinates and velocities (a free wheelset
   at rest 4 mm off centre).
2. The trailer on the straight from the paper's 2 mm misalignment: IMEX (steps of
   about 1 ms) against Tsit5 (about 0.35 ms) for 0.4 s, lateral displacements within
   0.05 mm and wheel loads within 2 %.
"""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.multibody import quaternion as qt
from jaxrail.multibody.forces import body_torque
from jaxrail.scenarios import load_scenario, parse_scenario
from jaxrail.simulation import SolverOptions, simulate
from jaxrail.vehicles.initial import initial_state
from jaxrail.vehicles.loads import OnlineContact, contact_loads, wheelset_load_jacobian
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


def test_wheelset_load_jacobian_equals_brute_force_ad():
    """At a free wheelset's rest pose 4 mm off centre (the per-wheelset loads are the
    trailer's; its lighter equilibrium compiles in a fraction of the time)."""
    scenario = parse_scenario((Path(__file__).parents[1] / "data" / "wheelset-straight.toml")
                              .read_text())
    vehicle, params, track = scenario.build()
    q, qdot = eqx.filter_jit(initial_state)(vehicle, params, track, scenario.speed, 0.004,
                                            None, OnlineContact())  # compiled: twice as fast as eager
    _, torques, patches, _ = jax.jit(lambda a, b: contact_loads(
        vehicle, params, track, a, b))(q, qdot)
    k = vehicle.wheelsets[0]
    one = jax.tree.map(lambda x: x[0], patches)
    q_body, qdot_body = q.reshape(-1, 7)[k], qdot.reshape(-1, 7)[k]
    fast = jax.jit(wheelset_load_jacobian)(params.contact, one, q_body, qdot_body, torques[k])
    slow = jax.jit(brute_force_jacobian)(params.contact, one, q_body, qdot_body)
    assert np.all(np.isfinite(fast))
    np.testing.assert_allclose(fast, slow, rtol=1e-8, atol=1e-6 * float(jnp.max(jnp.abs(slow))))


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
    # the evaluations each run reports (counted: tests/multibody/test_evaluations.py)
    assert int(imex.rhs_evaluations) == 8 * int(imex.steps) == 8 * int(imex.jacobian_evaluations)
    assert int(reference.rhs_evaluations) == 6 * int(reference.steps) + 1
