"""Initial conditions: a vehicle at rest on its wheels, rolling at a given speed.

Static equilibrium: the suspension bushings carry the static loads as preloads at the
nominal layout (:mod:`jaxrail.vehicles.trailer`), so the sprung bodies are in
equilibrium where the layout puts them; each wheelset is lowered into the rails until
its vertical wheel-rail force equals its share of the vehicle's weight (the vehicle
is assumed symmetric: weight / number of wheelsets each). The sprung bodies follow the
wheelsets' mean height. A lateral misalignment shifts the whole vehicle sideways.
"""

import jax
import jax.numpy as jnp
import numpy as np

from ..contact.pose import wheelset_pose
from ..multibody import consistent_initial_conditions, join_coordinates
from ..multibody import quaternion as qt
from ..multibody import velocities_from_twists
from ..track import track_frame
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import wheelset_contact_loads

BISECTION_STEPS = 60


def _vertical_wheel_force(vehicle, params, track, s, lateral, height, speed):
    """Upward wheel-rail force [N] (track normal) on a wheelset at ``s`` [m], shifted
    ``lateral`` [m], its centre ``height`` [m] above the track plane, moving at
    ``speed`` [m/s] and spinning at speed / nominal radius (the spin creepage of the
    conical contact gives lateral creep forces with a vertical component)."""
    position, rotation = wheelset_pose(track, s, lateral, height)
    velocity = speed * rotation[:, 0]
    spin = (speed / vehicle.nominal_radius) * rotation[:, 1]
    force, _, patches, forces = wheelset_contact_loads(
        vehicle.wheel, vehicle.rail, track, vehicle.rail_offset, params.contact, position,
        rotation, velocity, spin, vehicle.config)
    return force @ track_frame(track, s)[:, 2], (patches, forces)


def wheelset_rest_height(vehicle: Vehicle, params: VehicleParams, track, s, lateral, load,
                         speed=0.0):
    """Centre height [m] above the track plane at which a wheelset at arc length ``s``
    [m], shifted ``lateral`` [m] and rolling at ``speed`` [m/s], carries ``load`` [N]
    on the rails, and its mean rolling radius [m] there (weighted by normal force).

    Bisection (60 steps, no gradient) followed by one Newton step, which carries the
    derivative with respect to the parameters (implicit function theorem).
    """
    r0 = vehicle.nominal_radius

    frozen = jax.lax.stop_gradient((params, s, lateral, load, speed))
    frozen_force = lambda h: _vertical_wheel_force(  # noqa: E731
        vehicle, frozen[0], track, frozen[1], frozen[2], h, frozen[4])[0]

    def bisect(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        heavy = frozen_force(mid) > frozen[3]  # too deep: raise the wheelset
        return jnp.where(heavy, mid, lo), jnp.where(heavy, hi, mid)

    lo, hi = jax.lax.fori_loop(0, BISECTION_STEPS, bisect,
                               (jnp.asarray(0.5 * r0), jnp.asarray(1.5 * r0)))
    h = jax.lax.stop_gradient(0.5 * (lo + hi))
    # Newton step with a finite-difference slope: no derivative of the search is
    # compiled here, and the step still carries dh/dparams = -(dF/dparams) / slope.
    step = 1e-7
    value, (patches, forces) = jax.vmap(
        lambda h: _vertical_wheel_force(vehicle, params, track, s, lateral, h, speed))(
        jnp.stack([h, h + step]))
    slope = jax.lax.stop_gradient((value[1] - value[0]) / step)
    h = h - (value[0] - load) / slope
    # Rolling radius to the middle of the overlap, where the creepages are taken.
    weight = jnp.where(patches.active[0], forces.normal_force[0], 0.0)
    radius = patches.rolling_radius[0] - 0.5 * patches.penetration[0]
    radius = jnp.sum(weight * radius) / jnp.sum(weight)
    return h, radius


def initial_state(vehicle: Vehicle, params: VehicleParams, track, speed, misalignment=0.0,
                  s0=None):
    """``(q0, qdot0)`` of the vehicle at rest on the track, rolling at ``speed`` [m/s].

    Arguments:
        s0: arc length [m] of the vehicle's reference point (default: the rearmost
            wheelset 5 m after the start of the track).
        misalignment: lateral shift [m] of the whole vehicle, positive left.

    All bodies move along the track at ``speed``; the wheelsets spin at ``speed /
    rolling radius``. The state is projected onto the joint constraints.
    """
    layout = np.asarray(vehicle.layout)
    if s0 is None:
        s0 = 5.0 - float(np.min(layout[:, 0]))
    speed = jnp.asarray(speed, dtype=jnp.float64)
    misalignment = jnp.asarray(misalignment, dtype=jnp.float64)
    wheelsets = np.asarray(vehicle.wheelsets)
    mass = params.system.bodies.mass
    load = -jnp.sum(mass) * params.system.gravity[2] / len(wheelsets)
    heights, radii = jax.vmap(lambda s: wheelset_rest_height(
        vehicle, params, track, s, misalignment, load, speed))(s0 + layout[wheelsets, 0])
    lift = jnp.mean(heights) - vehicle.nominal_radius

    def place(x, y, z, is_wheelset, height):
        s = s0 + x
        vertical = jnp.where(is_wheelset, height, z + lift)
        position, rotation = wheelset_pose(track, s, y + misalignment, vertical)
        return position, qt.from_rotation_matrix(rotation), speed * track_frame(track, s)[:, 0]

    is_wheelset = np.isin(np.arange(len(layout)), wheelsets)
    height = jnp.zeros(len(layout)).at[wheelsets].set(heights)
    position, p, velocity = jax.vmap(place)(layout[:, 0], layout[:, 1], layout[:, 2],
                                            is_wheelset, height)
    q = join_coordinates(position, p)
    spin = jnp.zeros(len(layout)).at[wheelsets].set(speed / radii)
    axle = jax.vmap(qt.rotation_matrix)(p)[:, :, 1]
    qdot = velocities_from_twists(q, velocity, spin[:, None] * axle)
    return consistent_initial_conditions(vehicle.system, params.system, q, qdot)
