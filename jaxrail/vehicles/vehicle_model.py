"""A vehicle file expanded (:mod:`~jaxrail.vehicles.vehicle_file`): its bodies, wheelsets,
joints and force elements as flat lists, every number in SI units and every point in
the vehicle frame (x forward, y left, z up, origin on the track centreline at the
vehicle's reference point, z = 0 at the rail tops). ``table`` fields name the
declaration each came from, for errors."""

import dataclasses

from .quantities import Parameters


@dataclasses.dataclass(frozen=True)
class Body:
    """A body: mass [kg], inertia (3,) principal or (3, 3) [kg m^2], centre of mass
    (3,) [m] in the vehicle frame; ``table`` names its declaration."""

    name: str
    mass: float
    inertia: list
    position: tuple
    table: str


@dataclasses.dataclass(frozen=True)
class Wheelset:
    """A wheelset body's wheels: profile name or path (as written), nominal radius [m],
    back-to-back distance [m] (None if not given), its axlebox body's name or None."""

    body: str
    profile: object
    nominal_radius: float
    back_to_back: float | None
    axlebox: str | None
    table: str


@dataclasses.dataclass(frozen=True)
class Link:
    """A joint or force element: kind, its description class, the bodies' names
    ("ground" for the fixed frame), its two points (3,) [m] in the vehicle frame, the
    other fields' values (SI), and whether its preload is to carry the static load."""

    kind: str
    cls: type
    name: str
    body_i: str
    body_j: str
    at_i: tuple
    at_j: tuple
    values: dict
    static: bool
    table: str


@dataclasses.dataclass(frozen=True)
class VehicleModel:
    """A vehicle file, expanded. ``vehicle``: its ``[vehicle]`` table (raw);
    ``parameters``: :class:`~jaxrail.vehicles.quantities.Parameters`."""

    where: str
    vehicle: dict
    parameters: Parameters
    bodies: tuple[Body, ...]
    wheelsets: tuple[Wheelset, ...]
    joints: tuple[Link, ...]
    elements: tuple[Link, ...]
