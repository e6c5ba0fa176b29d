"""A bogie carrying half the carbody: one bogie frame, 2 axlebox bodies, 2 wheelsets.

Half of the trailer (:mod:`jaxrail.vehicles.trailer`) for studies that need real wheel
loads, a primary suspension and stable curving at a fraction of the trailer's cost
(identification, Monte Carlo). The frame is the trailer's bogie frame with half the
carbody's mass added at its centre of mass (the carbody's roll and yaw about the bogie
are left out); the primary suspension, axlebox bodies and wheelsets are the trailer's.
Nothing holds the frame in yaw but its wheelsets.

Body order: frame, axlebox_1, axlebox_2, wheelset_1 (leading), wheelset_2.

The built-in vehicle file ``bogie`` (``data/bogie.toml``, what scenarios build) is the
same vehicle, number for number (tests/vehicles/test_vehicle_file.py).
"""

import numpy as np

from .._constants import GRAVITY
from ..contact.search import SearchConfig
from ..multibody import RigidBody, build_system
from ..profiles import s1002
from .trailer import primary_bushings, trailer_values, unsprung_bodies
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import ContactParameters

CARBODY_GYRATION_RADIUS = 1.0  # [m] of the added half carbody about the frame's axes [A]


def bogie_frame_mass(values: dict) -> float:
    """Mass [kg] of the loaded frame: bogie + carbody / 2."""
    return values["bogie.mass"] + 0.5 * values["carbody.mass"]


def bogie(wheel=None, values=None, config=SearchConfig(),
          contact=None) -> tuple[Vehicle, VehicleParams]:
    """The loaded bogie as ``(Vehicle, VehicleParams)``; arguments as
    :func:`jaxrail.vehicles.trailer`. Force elements ``primary_k_left``/``_right``
    (k = 1 leading, 2)."""
    v = trailer_values() if values is None else values
    r0 = v["wheelset.nominal_radius"]
    wheel = s1002(nominal_radius=r0) if wheel is None else wheel
    b = v["bogie.semi_wheelbase"]
    added = 0.5 * v["carbody.mass"] * CARBODY_GYRATION_RADIUS**2
    inertia = tuple(v[f"bogie.{n}"] + added for n in ("roll_inertia", "pitch_inertia",
                                                      "yaw_inertia"))
    mass = bogie_frame_mass(v)
    bodies = [RigidBody("frame", mass, inertia)]
    layout = [(0.0, 0.0, v["bogie.height"])]
    unsprung, unsprung_layout, joints = unsprung_bodies(v, (b, -b))
    forces = [e for k, x in ((1, b), (2, -b))
              for e in primary_bushings(v, k, "frame", x, mass * GRAVITY / 4.0)]
    system, system_params = build_system(bodies + unsprung, joints, forces,
                                         gravity=(0.0, 0.0, -GRAVITY))
    vehicle = Vehicle("bogie", system, (3, 4), config, axleboxes=(1, 2))
    return vehicle, VehicleParams(system_params,
                                  ContactParameters() if contact is None else contact,
                                  wheel, np.array(layout + unsprung_layout))
