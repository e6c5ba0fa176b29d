"""A suspended single wheelset: the textbook model of hunting stability (Wickens).

One wheelset tied by a primary suspension (the trailer's, softer longitudinally:
:data:`LONGITUDINAL_STIFFNESS`; longitudinal and lateral springs, the vertical damper,
and the small pitch spring and damper that hold the axlebox body about the axle) at
+-``axlebox.half_span`` either side of the track centreline to a frame that moves along
the track. The frame slides along the global x axis on a
prismatic joint to the ground (the straight track's direction): it neither rolls,
yaws nor moves sideways or vertically, so the wheelset's lateral and yaw motion meets
the yaw stiffness ``2 k_x b^2`` and the lateral stiffness ``2 k_y`` of a frame that
goes straight on, Wickens' model. The frame's mass is the sprung mass per axle of the
trailer (``carbody / 4 + bogie / 2``); the primary springs have no vertical stiffness
and press the wheelset down with the frame's weight as a constant preload (Wickens'
constant axle load), so the wheel loads are the trailer's at any frame height. Nothing
drives or brakes the frame unless a speed drive holds it
(:class:`~jaxrail.vehicles.drive.SpeedDrive`, as the nonlinear stability methods do).

Body order: frame, axlebox_1, wheelset_1 (the axlebox body joined to the wheelset by a
revolute joint about the axle, as in the trailer). The prismatic joint fixes the frame's
path to straight track along global x. Built with ``curve_radius`` R the frame turns
instead about the vertical through the centre of a curve of radius R that starts at
the origin heading along +x (``Track.from_segments([Arc(length, R, direction)])``): a
revolute joint to the ground there, so the frame runs round the circle of radius R at
its height, radial to it, and the wheelset curves against Wickens' frame (no cant: the
frame does not roll with the track).

The built-in vehicle file ``suspended-wheelset`` (``data/suspended-wheelset.toml``, what
scenarios build, through :func:`suspended_wheelset_file`) is the same vehicle, number for
number, the curve a build option (:func:`curved_guide`; tests/vehicles/test_vehicle_file.py).
"""

import dataclasses

import numpy as np

from .._constants import GRAVITY
from ..contact.search import SearchConfig
from ..multibody import Prismatic, Revolute, RigidBody, build_system
from ..profiles import s1002
from .from_file import read_toml, vehicle_file_path, vehicle_from_data
from .trailer import primary_bushings, trailer_values, unsprung_bodies
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import ContactParameters

FRAME_GYRATION_RADIUS = 1.0  # [m] of the frame (its rotations are held by the joint) [A]
LONGITUDINAL_STIFFNESS = 1.0e6
"""[N/m] per side [A]: the primary longitudinal stiffness of the suspended wheelset, a
soft yaw stiffness (2 k_x b^2 = 2 MN m/rad at b = 1 m) that puts its linear critical
speed near 100 m/s on S1002 / UIC60 1:40; the trailer's 31.4 MN/m puts it far above
any service speed."""


def frame_mass(values: dict) -> float:
    """Sprung mass per axle [kg]: carbody / 4 + bogie / 2 (the trailer's)."""
    return 0.25 * values["carbody.mass"] + 0.5 * values["bogie.mass"]


def curve_centre(curve_radius, direction="left") -> float:
    """y [m] of the centre of a curve of radius ``curve_radius`` [m] that starts at the
    origin heading along +x and turns ``direction`` ('left' or 'right')."""
    if not (np.isfinite(curve_radius) and curve_radius > 0.0):
        raise ValueError(f"curve_radius must be > 0 m, got {curve_radius}")
    if direction not in ("left", "right"):
        raise ValueError(f"direction must be 'left' or 'right', got {direction!r}")
    return (1.0 if direction == "left" else -1.0) * float(curve_radius)


def curved_guide(data: dict, curve_radius, direction="left") -> dict:
    """A copy of the parsed vehicle file ``data`` (``suspended-wheelset.toml``) whose
    joint ``guide``, the frame's prismatic joint to the ground, is instead a revolute
    joint to the ground about the vertical through the centre of a curve of radius
    ``curve_radius`` [m] turning ``direction`` (module docstring), at the guide's
    height. The joint kind is the file's structure, so the curve is a build option
    applied to the data before :func:`~jaxrail.vehicles.vehicle_from_data`."""
    centre = curve_centre(curve_radius, direction)
    joints = data.get("joint", [])
    guides = [k for k, joint in enumerate(joints) if joint.get("name") == "guide"]
    if len(guides) != 1:
        raise ValueError("a curve radius needs the vehicle file's one top-level [[joint]] "
                         "named 'guide' (the frame's joint to the ground)")
    guide = joints[guides[0]]
    height = guide["at"][2]
    turned = {"name": "guide", "kind": "revolute", "body_i": guide["body_i"],
              "body_j": guide["body_j"], "axis": [0, 0, 1],
              "at": [0, {"value": centre, "unit": "m", "tag": "A",
                         "source": f"the centre of a {direction} curve of radius "
                                   f"{float(curve_radius):g} m (the curve_radius build "
                                   f"option)"}, height]}
    return {**data, "joint": [turned if k == guides[0] else joint
                              for k, joint in enumerate(joints)]}


def suspended_wheelset_file(curve_radius=None, direction="left", **options
                            ) -> tuple[Vehicle, VehicleParams]:
    """The built-in vehicle file ``suspended-wheelset`` as ``(Vehicle, VehicleParams)``,
    with :func:`curved_guide` where ``curve_radius`` [m] is given; ``options`` as
    :func:`~jaxrail.vehicles.vehicle_from_file`. It builds what
    :func:`suspended_wheelset` builds (tests/vehicles/test_vehicle_file.py)."""
    path = vehicle_file_path("suspended-wheelset")
    data = read_toml(path)
    if curve_radius is not None:
        data = curved_guide(data, curve_radius, direction)
    return vehicle_from_data(data, where=str(path), folder=path.parent, **options)


def suspended_wheelset(wheel=None, values=None, config=SearchConfig(),
                       contact=None, curve_radius=None,
                       direction="left") -> tuple[Vehicle, VehicleParams]:
    """The suspended wheelset as ``(Vehicle, VehicleParams)``; arguments as
    :func:`jaxrail.vehicles.trailer` (default values: the trailer's, with the primary
    longitudinal stiffness :data:`LONGITUDINAL_STIFFNESS`). Force elements
    ``primary_1_left``/``_right``; the joint ``guide`` holds the frame on the line
    y = 0, z = frame height, or with ``curve_radius`` [m] on the circle of that radius
    turning ``direction`` ('left' or 'right') from the origin (module docstring)."""
    if values is None:
        values = {**trailer_values(), "primary.longitudinal_stiffness": LONGITUDINAL_STIFFNESS}
    v = values
    r0 = v["wheelset.nominal_radius"]
    wheel = s1002(nominal_radius=r0) if wheel is None else wheel
    mass = frame_mass(v)
    height = v["bogie.height"]
    bodies = [RigidBody("frame", mass, (mass * FRAME_GYRATION_RADIUS**2,) * 3)]
    unsprung, unsprung_layout, joints = unsprung_bodies(v, (0.0,))
    if curve_radius is None:
        guide = Prismatic("ground", "frame", (0.0, 0.0, height), (0.0, 0.0, 0.0),
                          axis_i=(1.0, 0.0, 0.0), axis_j=(1.0, 0.0, 0.0), name="guide")
    else:
        centre = curve_centre(curve_radius, direction)
        guide = Revolute("ground", "frame", (0.0, centre, height), (0.0, centre, 0.0),
                         name="guide")
    # no vertical stiffness: the springs press the wheelset down with a constant force,
    # the frame's weight (Wickens' constant axle load), whatever the frame's height
    forces = [dataclasses.replace(b, stiffness=b.stiffness[:2] + (0.0,) + b.stiffness[3:])
              for b in primary_bushings(v, 1, "frame", 0.0, mass * GRAVITY / 2.0)]
    system, system_params = build_system(bodies + unsprung, joints + [guide], forces,
                                         gravity=(0.0, 0.0, -GRAVITY))
    vehicle = Vehicle("suspended wheelset", system, (2,), config, axleboxes=(1,))
    layout = np.array([(0.0, 0.0, height)] + unsprung_layout)
    return vehicle, VehicleParams(system_params,
                                  ContactParameters() if contact is None else contact,
                                  wheel, layout)
