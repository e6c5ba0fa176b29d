"""A single free wheelset on the track: one rigid body of :mod:`jaxrail.multibody`
under gravity and the wheel-rail loads of :func:`wheelset_contact_loads`.

For tests and studies (Klingel's kinematic hunting, contact dynamics). Mass data: the
Manchester benchmark wheelset, 1813 kg [V-src]; inertias Ixx = Izz = 1120, Iyy = 112
kg m^2 [R, recalled] (shared/reference/vehicle.md).
"""

import diffrax
import jax
import jax.numpy as jnp

from ..contact.pose import wheelset_pose
from ..contact.search import SearchConfig, search_wheelset
from ..multibody import (RigidBody, angular_velocity, body_pose, build_system,
                         join_coordinates, quaternion, simulate_system, velocities_from_twists)
from ..profiles import rail_offset
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import ContactParameters, wheelset_contact_loads

WHEELSET_MASS = 1813.0  # [kg] Manchester benchmark [V-src]
WHEELSET_INERTIA = (1120.0, 112.0, 1120.0)  # [kg m^2] (roll, spin, yaw) [R]


def touching_height(wheel, rail, track, rail_offset, s, config=SearchConfig()):
    """Centre height [m] above the track plane at which a centred wheelset at arc length
    ``s`` first touches the rails (bisection, 60 steps), and the contact patches there."""
    search = jax.jit(lambda h: search_wheelset(wheel, rail, track, rail_offset,
                                               *wheelset_pose(track, s, 0.0, h), config))
    lo, hi = 0.5 * float(wheel.nominal_radius), 1.5 * float(wheel.nominal_radius)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(jnp.max(search(mid).penetration)) > 0.0 else (lo, mid)
    return hi, search(hi - 1e-7)


def simulate_single_wheelset(wheel, rail, track, rail_offset, speed, lateral, t1, ts,
                             contact=ContactParameters(), s0=10.0, config=SearchConfig(),
                             rtol=1e-6, atol=1e-9, max_steps=400_000):
    """Roll a free wheelset along the track from arc length ``s0`` [m].

    It starts at the touching height, shifted by ``lateral`` [m] (positive left), moving
    at ``speed`` [m/s] and spinning at ``speed / rolling radius`` of the centred contact.
    Integrated by Tsit5 with a PID controller (``rtol``, ``atol``) from 0 to ``t1`` [s],
    saved at ``ts``. Returns ``(solution, (height, patches))``: diffrax's Solution with
    ``ys = (q, qdot)`` (Euler-parameter coordinates of one body) and the centred
    touching height and patches.
    """
    height, patches = touching_height(wheel, rail, track, rail_offset, s0, config)
    vehicle, vehicle_params = single_wheelset(wheel, rail, contact, config)
    system, params = vehicle.system, vehicle_params.system

    def external(t, q, qdot):
        position, rotation = body_pose(q, 0)
        omega = angular_velocity(q, qdot, 0)[0]
        force, moment, _, _ = wheelset_contact_loads(wheel, rail, track, rail_offset, contact,
                                                     position, rotation, qdot[:3], omega, config)
        return force[None, :], moment[None, :]

    position, rotation = wheelset_pose(track, s0, lateral, height)
    q0 = join_coordinates(position[None, :], quaternion.from_rotation_matrix(rotation)[None, :])
    radius = patches.rolling_radius[0, 0]
    qdot0 = velocities_from_twists(q0, speed * rotation[:, 0][None, :],
                                   (speed / radius) * rotation[:, 1][None, :])
    run = jax.jit(lambda q0, qdot0: simulate_system(
        system, params, q0, qdot0, t1, dt0=1e-4, saveat=diffrax.SaveAt(ts=ts), rtol=rtol,
        atol=atol, external=external, max_steps=max_steps))
    return run(q0, qdot0), (height, patches)


def single_wheelset(wheel, rail, contact=ContactParameters(), config=SearchConfig()):
    """A free wheelset as a :class:`Vehicle` (one body, no suspension) for
    :func:`jaxrail.simulate.simulate`: ``(Vehicle, VehicleParams)``."""
    system, params = build_system([RigidBody("wheelset", WHEELSET_MASS, WHEELSET_INERTIA)], [],
                                  [], gravity=(0.0, 0.0, -9.81))
    vehicle = Vehicle("single wheelset", system, (0,), [(0.0, 0.0, float(wheel.nominal_radius))],
                      wheel, rail, float(rail_offset(rail)), config)
    return vehicle, VehicleParams(params, contact)
