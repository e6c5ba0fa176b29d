"""The paper's 11-body trailer: 4 wheelsets, 4 axlebox bodies, 2 bogie frames, 1 carbody.

Topology (section 4 of the paper):

- each axlebox body is joined to its wheelset by a revolute joint about the axle: it
  follows the wheelset's translation, roll and yaw, and does not spin;
- the primary suspension joins each axlebox body to its bogie frame: one six-component
  bushing per side (longitudinal, lateral, vertical stiffness; vertical damping; a
  small pitch stiffness and damping holds the axlebox body's rotation about the axle);
- the secondary suspension joins each bogie frame to the carbody: one bushing per side
  (longitudinal, lateral, vertical stiffness; vertical and lateral damping).

Numbers: ``jaxrail/vehicles/data/manchester_trailer.toml``, the Manchester benchmark
vehicle 1 with every value's source and a tag (V-src checked, R recalled, A assumed).
The bushings carry the static loads as preloads at zero deflection, so the nominal
layout is the static equilibrium whatever the stiffnesses; the implied static
deflection of a bushing is its preload over its stiffness.

Body order: carbody, bogie_1 (leading), bogie_2, axlebox_1..4, wheelset_1..4;
wheelset 1 leads.
"""

import importlib.resources
import tomllib
from pathlib import Path

import numpy as np

from .._constants import GRAVITY as GRAVITY  # [m/s^2], as trailer.GRAVITY too
from ..contact.search import SearchConfig
from ..multibody import Bushing, Revolute, RigidBody, build_system
from ..profiles import s1002
from .vehicle import Vehicle, VehicleParams
from .wheel_rail import ContactParameters

DEFAULT_DATA = "manchester_trailer.toml"
TAGS = ("V-src", "R", "A")


def read_vehicle_data(path=None) -> dict:
    """The entries of a vehicle parameter file: ``{"group.name": {"value", "unit",
    "source", "tag"}}``. Default: the built-in Manchester trailer file."""
    if path is None:
        text = importlib.resources.files(__package__).joinpath("data", DEFAULT_DATA).read_text()
        where = DEFAULT_DATA
    else:
        text, where = Path(path).read_text(), str(path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"vehicle data file {where}: {error}") from error
    entries = {}
    for group, items in raw.items():
        for name, entry in items.items():
            key = f"{group}.{name}"
            if not isinstance(entry, dict) or set(entry) != {"value", "unit", "source", "tag"}:
                raise ValueError(f"{where}: {key} must have exactly value, unit, source, tag")
            if entry["tag"] not in TAGS:
                raise ValueError(f"{where}: {key} has tag {entry['tag']!r}, not one of {TAGS}")
            entries[key] = entry
    return entries


def trailer_values(path=None, **overrides) -> dict[str, float]:
    """``{"group.name": value}`` of a trailer data file, with ``overrides`` given as
    ``carbody__mass=30000.0`` (double underscore for the dot)."""
    values = {k: float(e["value"]) for k, e in read_vehicle_data(path).items()}
    for key, value in overrides.items():
        dotted = key.replace("__", ".")
        if dotted not in values:
            raise ValueError(f"unknown trailer value {dotted!r}; known: {sorted(values)}")
        values[dotted] = float(value)
    missing = set(_REQUIRED) - set(values)
    if missing:
        raise ValueError(f"trailer data lacks {sorted(missing)}")
    return values


_REQUIRED = [f"{g}.{n}" for g, names in {
    "carbody": ["mass", "roll_inertia", "pitch_inertia", "yaw_inertia", "height",
                "bogie_half_distance"],
    "bogie": ["mass", "roll_inertia", "pitch_inertia", "yaw_inertia", "height",
              "semi_wheelbase"],
    "wheelset": ["mass", "roll_inertia", "spin_inertia", "yaw_inertia", "nominal_radius"],
    "axlebox": ["mass", "roll_inertia", "pitch_inertia", "yaw_inertia", "half_span"],
    "primary": ["longitudinal_stiffness", "lateral_stiffness", "vertical_stiffness",
                "vertical_damping", "pitch_stiffness", "pitch_damping"],
    "secondary": ["longitudinal_stiffness", "lateral_stiffness", "vertical_stiffness",
                  "vertical_damping", "lateral_damping", "half_span", "height"],
}.items() for n in names]


def static_loads(values: dict) -> dict[str, float]:
    """Static vertical loads [N] of the symmetric trailer at rest on level track:
    per secondary element, per primary element, per wheel, and the total weight."""
    carbody, bogie = values["carbody.mass"], values["bogie.mass"]
    unsprung = values["wheelset.mass"] + values["axlebox.mass"]
    total = carbody + 2 * bogie + 4 * unsprung
    return {
        "secondary": carbody * GRAVITY / 4.0,
        "primary": (carbody + 2 * bogie) * GRAVITY / 8.0,
        "wheel": total * GRAVITY / 8.0,
        "total": total * GRAVITY,
    }


def _inertia(values, group, names=("roll_inertia", "pitch_inertia", "yaw_inertia")):
    return tuple(values[f"{group}.{n}"] for n in names)


def unsprung_bodies(values: dict, axle_x) -> tuple[list, list, list]:
    """Axlebox bodies ``axlebox_k`` and wheelsets ``wheelset_k`` (k = 1, 2, ... in the
    order of ``axle_x`` [m], vehicle frame), their layout rows and the revolute joints
    ``axle_k`` that join each axlebox body to its wheelset about the axle."""
    v, r0 = values, values["wheelset.nominal_radius"]
    bodies = [RigidBody(f"axlebox_{k}", v["axlebox.mass"], _inertia(v, "axlebox"))
              for k in range(1, len(axle_x) + 1)]
    bodies += [RigidBody(f"wheelset_{k}", v["wheelset.mass"],
                         _inertia(v, "wheelset", ("roll_inertia", "spin_inertia",
                                                  "yaw_inertia")))
               for k in range(1, len(axle_x) + 1)]
    layout = [(x, 0.0, r0) for x in axle_x] * 2
    joints = [Revolute(f"axlebox_{k}", f"wheelset_{k}", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                       axis_i=(0.0, 1.0, 0.0), axis_j=(0.0, 1.0, 0.0), name=f"axle_{k}")
              for k in range(1, len(axle_x) + 1)]
    return bodies, layout, joints


def primary_bushings(values: dict, k: int, frame: str, x: float, preload: float) -> list:
    """The two primary bushings ``primary_k_left``/``_right`` between ``axlebox_k`` and
    the bogie frame body ``frame``; the axle is ``x`` [m] ahead of the frame's centre of
    mass, which is at the height ``bogie.height``. Each carries the vertical ``preload`` [N] at zero
    deflection (compressed: pushes the frame up)."""
    v, p = values, "primary."
    stiffness = (v[p + "longitudinal_stiffness"], v[p + "lateral_stiffness"],
                 v[p + "vertical_stiffness"], 0.0, v[p + "pitch_stiffness"], 0.0)
    damping = (0.0, 0.0, v[p + "vertical_damping"], 0.0, v[p + "pitch_damping"], 0.0)
    half, dz = v["axlebox.half_span"], v["wheelset.nominal_radius"] - v["bogie.height"]
    return [Bushing(f"axlebox_{k}", frame, (0.0, y, 0.0), (x, y, dz), stiffness=stiffness,
                    damping=damping, preload=(0.0, 0.0, -preload, 0.0, 0.0, 0.0),
                    name=f"primary_{k}_{side}")
            for side, y in (("left", half), ("right", -half))]


def trailer(wheel=None, values=None, config=SearchConfig(),
            contact=None) -> tuple[Vehicle, VehicleParams]:
    """The 11-body trailer as ``(Vehicle, VehicleParams)`` (its rails are the track's).

    Arguments:
        wheel: profile (default S1002 with the data's nominal radius).
        values: :func:`trailer_values` (default the built-in Manchester file).
        config: contact search settings; contact: :class:`ContactParameters` (default
            ones).
    """
    v = trailer_values() if values is None else values
    r0 = v["wheelset.nominal_radius"]
    wheel = s1002(nominal_radius=r0) if wheel is None else wheel
    loads = static_loads(v)
    a, b = v["carbody.bogie_half_distance"], v["bogie.semi_wheelbase"]
    bogie_x = (a, -a)
    axle_x = (a + b, a - b, -a + b, -a - b)

    bodies = [RigidBody("carbody", v["carbody.mass"], _inertia(v, "carbody"))]
    layout = [(0.0, 0.0, v["carbody.height"])]
    for k, x in enumerate(bogie_x, 1):
        bodies.append(RigidBody(f"bogie_{k}", v["bogie.mass"], _inertia(v, "bogie")))
        layout.append((x, 0.0, v["bogie.height"]))
    unsprung, unsprung_layout, joints = unsprung_bodies(v, axle_x)
    bodies += unsprung
    layout += unsprung_layout

    s = "secondary."
    secondary_k = (v[s + "longitudinal_stiffness"], v[s + "lateral_stiffness"],
                   v[s + "vertical_stiffness"], 0.0, 0.0, 0.0)
    secondary_c = (0.0, v[s + "lateral_damping"], v[s + "vertical_damping"], 0.0, 0.0, 0.0)
    secondary_f0 = (0.0, 0.0, -loads["secondary"], 0.0, 0.0, 0.0)

    forces = []
    for k, x in enumerate(axle_x, 1):
        bogie = 1 if k <= 2 else 2
        forces += primary_bushings(v, k, f"bogie_{bogie}", x - bogie_x[bogie - 1],
                                   loads["primary"])
    half, seat = v["secondary.half_span"], v["secondary.height"]
    for k, x in enumerate(bogie_x, 1):
        for side, y in (("left", half), ("right", -half)):
            forces.append(Bushing(
                f"bogie_{k}", "carbody", (0.0, y, seat - v["bogie.height"]),
                (x, y, seat - v["carbody.height"]),
                stiffness=secondary_k, damping=secondary_c, preload=secondary_f0,
                name=f"secondary_{k}_{side}"))

    system, system_params = build_system(bodies, joints, forces, gravity=(0.0, 0.0, -GRAVITY))
    vehicle = Vehicle("trailer", system, tuple(range(7, 11)), config, axleboxes=tuple(range(3, 7)))
    return vehicle, VehicleParams(system_params,
                                  ContactParameters() if contact is None else contact,
                                  wheel, np.array(layout))
