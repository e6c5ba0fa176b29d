"""A single free wheelset on the track: one rigid body of :mod:`jaxrail.multibody`
under gravity and the wheel-rail loads, simulated by :func:`jaxrail.simulation.simulate`
(a free wheelset rolled from its touching height:
:func:`jaxrail.simulation.simulate_single_wheelset`).

For tests and studies (Klingel's kinematic hunting, contact dynamics). Mass data: the
Manchester benchmark wheelset, 1813 kg [V-src]; inertias Ixx = Izz = 1120, Iyy = 112
kg m^2 [R, recalled] (shared/reference/vehicle.md).

The built-in vehicle file ``single-wheelset`` (``data/single-wheelset.toml``, what
scenarios build) is :func:`single_wheelset` with S1002 wheels, number for number
(tests/vehicles/test_vehicle_file.py).
"""

import jax
import jax.numpy as jnp

from .._constants import GRAVITY
from ..contact.pose import wheelset_pose
from ..contact.search import SearchConfig, search_wheelset
from ..multibody import RigidBody, build_system
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import ContactParameters

WHEELSET_MASS = 1813.0  # [kg] Manchester benchmark [V-src]
WHEELSET_INERTIA = (1120.0, 112.0, 1120.0)  # [kg m^2] (roll, spin, yaw) [R]


def touching_height(wheel, track, s, config=SearchConfig()):
    """Centre height [m] above the track plane at which a centred wheelset at arc length
    ``s`` first touches the track's rails (bisection, 60 steps), and the contact patches
    there."""
    search = jax.jit(lambda h: search_wheelset(wheel, track, *wheelset_pose(track, s, 0.0, h),
                                               config))
    lo, hi = 0.5 * float(wheel.nominal_radius), 1.5 * float(wheel.nominal_radius)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(jnp.max(search(mid).penetration)) > 0.0 else (lo, mid)
    return hi, search(hi - 1e-7)


def single_wheelset(wheel, contact=None, config=SearchConfig()):
    """A free wheelset as a :class:`Vehicle` (one body, no suspension) for
    :func:`jaxrail.simulation.simulate`: ``(Vehicle, VehicleParams)``."""
    contact = ContactParameters() if contact is None else contact
    system, params = build_system([RigidBody("wheelset", WHEELSET_MASS, WHEELSET_INERTIA)], [],
                                  [], gravity=(0.0, 0.0, -GRAVITY))
    layout = jnp.stack([0.0, 0.0, wheel.nominal_radius])[None, :]
    return (Vehicle("single wheelset", system, (0,), config),
            VehicleParams(params, contact, wheel, layout))
