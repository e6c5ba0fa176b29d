"""The outputs of a run recomputed from its saved states: the wheelsets' place on the
track, the contact details of every wheel and patch, the accelerations and the
constraint violation (:class:`~jaxrail.simulation.SimulationResult`)."""

import jax
import jax.numpy as jnp

from ..multibody import FixedLoads, accelerations, constraints
from ..track import to_track_coordinates, track_frame
from ..track.rails import track_irregularity, wheel_height
from ..vehicles.loads import contact_loads
from ..vehicles.vehicle import wheelset_states
from .result import SimulationResult, WheelOutputs


def wheelset_track_coordinates(vehicle, params, track, q, qdot, deflection=None):
    """Per wheelset: lateral [m], vertical [m] offsets and yaw [rad] relative to the
    design track, the height [m] of each wheel's profile origin (W, 2) over its rail's
    (:func:`jaxrail.track.rails.wheel_height`: the rail where the contact finds it, with
    its irregularity and, on a flexible track, its ``deflection`` (W, 2, 2) [m]), and
    the irregularity channels at the wheelset (W, 4) [m]."""
    position, rotation, _, _ = wheelset_states(vehicle, q, qdot)
    sides = jnp.array([1.0, -1.0])

    def one(r, a, w):
        s, lateral, vertical = to_track_coordinates(track, r)
        frame = track_frame(track, s)
        axle = frame.T @ a[:, 1]
        yaw = -jnp.arctan2(axle[0], axle[1])
        irregularity = track_irregularity(track, s)
        wheel_heights = jax.vmap(
            lambda side, d: wheel_height(track, r, a, side, d, s),
            in_axes=(0, None if w is None else 0))(sides, w)
        return lateral, vertical, yaw, wheel_heights, irregularity
    return jax.vmap(one, in_axes=(0, 0, None if deflection is None else 0))(
        position, rotation, deflection)


def state_outputs(vehicle, params, track, q, qdot, rails, model, t=0.0, drive=None,
                  elements=None):
    """``(WheelOutputs, qddot)`` at one state: the wheel outputs (leading shape (W, 2,
    P)) and the accelerations (7 n,) of eq. (19) with the same loads, from one contact
    evaluation; ``rails``: the flexible track's ``(w, wdot)`` (W, 2, 2), or None;
    ``drive``: the run's speed drive (its force at time ``t`` [s]), or None;
    ``elements``: the force elements' internal states (:class:`~jaxrail.multibody.State`)."""
    forces_on_bodies, torques, patches, forces = contact_loads(vehicle, params, track, q,
                                                               qdot, model, rails)
    if drive is not None:
        forces_on_bodies = drive.add_to(t, qdot, forces_on_bodies)
    qddot = accelerations(vehicle.system, params.system, 0.0, q, qdot,
                          FixedLoads(forces_on_bodies, torques), elements)[0]
    position, _, _, _ = wheelset_states(vehicle, q, qdot)
    frames = jax.vmap(lambda r: track_frame(track, to_track_coordinates(track, r)[0]))(position)
    side = jnp.array([1.0, -1.0])[None, :]
    total = jnp.sum(forces.force, axis=2)  # (W, 2, 3)
    lateral = jnp.einsum("wsi,wi->ws", total, frames[:, :, 1]) * side
    vertical = jnp.einsum("wsi,wi->ws", total, frames[:, :, 2])
    wheels = WheelOutputs(patches.active, patches.surface, patches.y_wheel, patches.y_rail,
                          patches.penetration, patches.contact_angle, forces.normal_force,
                          forces.creep_force_x, forces.creep_force_y, forces.creepage_x,
                          forces.creepage_y, forces.spin, forces.semi_axis_a,
                          forces.semi_axis_b, lateral, vertical)
    return wheels, qddot


def wheel_outputs(vehicle, params, track, q, qdot, rails, model):
    """WheelOutputs at one state (:func:`state_outputs` without the accelerations)."""
    return state_outputs(vehicle, params, track, q, qdot, rails, model)[0]


def simulation_result(vehicle, params, track, model, start, ts, saved, result, derailed,
                      steps, accepted_steps, rejected_steps, evaluations, drive=None):
    """SimulationResult from the :class:`~jaxrail.multibody.State` ``saved`` at the
    output times (leading axis T; non-finite rows: not reached) and the ``start``,
    without host timings. ``drive``: the run's speed drive, or None."""
    q0, qdot0, rails0 = start.q, start.qdot, start.track
    q, qdot, rails = saved.q, saved.qdot, saved.track
    _, rest_vertical, _, _, _ = wheelset_track_coordinates(vehicle, params, track, q0, qdot0)
    valid = jnp.all(jnp.isfinite(q), axis=1) & jnp.all(jnp.isfinite(qdot), axis=1)
    # Outputs after an early stop are recomputed at the initial state and masked.
    safe = lambda x, x0: jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 1)), x, x0)  # noqa: E731
    q_safe, qdot_safe = safe(q, q0), safe(qdot, qdot0)
    rails_safe = None if rails is None else jax.tree.map(safe, rails, rails0)
    elements_safe = jax.tree.map(safe, saved.elements, start.elements)
    lateral, vertical, yaw, _, irregularity = jax.vmap(
        lambda a, b: wheelset_track_coordinates(vehicle, params, track, a, b))(q_safe, qdot_safe)
    wheels, qddot = jax.lax.map(
        lambda y: state_outputs(vehicle, params, track, *y[1:4], model, y[0], drive, y[4]),
        (ts, q_safe, qdot_safe, rails_safe, elements_safe))
    deflection = (jnp.zeros(lateral.shape + (2, 2), dtype=q.dtype) if rails is None
                  else rails_safe[0])
    n_norm = vehicle.system.n_bodies
    violation = jax.vmap(lambda a, b: jnp.max(jnp.abs(
        constraints(vehicle.system, params.system, a, b)[0][n_norm:]), initial=0.0))(
        q_safe, qdot_safe)
    nan = lambda x: jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 1)), x, jnp.nan)  # noqa: E731
    wheels = jax.tree.map(lambda x: nan(x) if jnp.issubdtype(x.dtype, jnp.floating) else x,
                          wheels)
    return SimulationResult(
        t=ts, q=q, qdot=qdot, qddot=nan(qddot), valid=valid, wheelset_lateral=nan(lateral),
        wheelset_vertical=nan(vertical - rest_vertical), wheelset_yaw=nan(yaw),
        irregularity=nan(irregularity), rail_deflection=nan(deflection), wheels=wheels,
        constraint_violation=nan(violation),
        result=result, derailed=jnp.asarray(derailed), steps=steps, accepted_steps=accepted_steps,
        rejected_steps=rejected_steps, rhs_evaluations=evaluations[0],
        jacobian_evaluations=evaluations[1], wall_time_s=jnp.asarray(jnp.nan),
        compile_time_s=jnp.asarray(jnp.nan))
