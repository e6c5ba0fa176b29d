"""Vehicles from vehicle files: ``vehicle_from_file("trailer")`` or a path, and
``vehicle_from_data`` for the same content as plain data (docs/vehicle-files.md).

The file is read and checked whole (:mod:`~jaxrail.vehicles.vehicle_file`,
:mod:`~jaxrail.vehicles.load_path`) before the system is built: every error is a
``ValueError`` that names the file, the table and the key, and nothing is compiled.
The built-in vehicle files are ``jaxrail/vehicles/data/<name>.toml`` with a
``[vehicle]`` table (:func:`vehicle_names`).
"""

import re
import tomllib
from pathlib import Path

import numpy as np

from .._constants import GRAVITY
from ..contact.search import SearchConfig
from ..multibody import RigidBody, build_system
from ..multibody import forces as fc
from ..track import RAIL_KEYS
from . import element_kinds as ek
from .axleboxes import carry_axleboxes
from .load_path import check_supported, static_loads
from .quantities import check_dimension, file_error, read_number
from .vehicle import Vehicle, VehicleParams
from .vehicle_file import data_folder, read_vehicle_model
from .wheel_rail import ContactParameters
from .wheels import wheel_profile

VEHICLE_KEYS = ("name", "description", "gravity")
FORMULATIONS = ("auto", "joints")


def vehicle_names() -> list[str]:
    """Names of the built-in vehicle files (``data/*.toml`` with a ``[vehicle]`` table)."""
    names = []
    for path in sorted(data_folder().glob("*.toml")):
        with open(path, "rb") as stream:
            if "vehicle" in tomllib.load(stream):
                names.append(path.stem)
    return names


def vehicle_file_path(path_or_name) -> Path:
    """The path of a vehicle file: an existing file, or a built-in name."""
    path = Path(path_or_name)
    if path.is_file():
        return path
    if str(path_or_name) in vehicle_names():
        return data_folder() / f"{path_or_name}.toml"
    raise ValueError(f"no vehicle file {str(path_or_name)!r}: give a path or a built-in "
                     f"name ({', '.join(vehicle_names())})")


def read_toml(path: Path) -> dict:
    """The parsed TOML of ``path``; ValueError naming it if it does not parse."""
    try:
        with open(path, "rb") as stream:
            return tomllib.load(stream)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: {error}") from None


def vehicle_from_file(path_or_name, **options) -> tuple[Vehicle, VehicleParams]:
    """``(Vehicle, VehicleParams)`` of a vehicle file (a path, or a built-in name such
    as ``"trailer"``); ``options`` as :func:`vehicle_from_data`. Profile files named in
    it are relative to its folder."""
    path = vehicle_file_path(path_or_name)
    return vehicle_from_data(read_toml(path), where=str(path), folder=path.parent, **options)


def vehicle_from_data(data: dict, where: str = "<data>", folder=None, *, wheel=None,
                      config: SearchConfig = SearchConfig(), contact=None,
                      parameters=None, formulation: str = "auto"
                      ) -> tuple[Vehicle, VehicleParams]:
    """``(Vehicle, VehicleParams)`` from a vehicle file's content as plain data. The rail
    profile and the gauge are the track's (:class:`jaxrail.track.Rails`, a scenario's
    ``[track]``), not the vehicle's: a file that names them is refused.

    Arguments:
        data: the parsed TOML (nested dicts and lists).
        where: the name errors give for it; folder: where its profile files are.
        wheel: the wheel profile replacing the file's; config: contact search settings;
            contact: :class:`ContactParameters` (default ones).
        parameters: ``{"group.name": value}`` in SI units, replacing the file's named
            parameters (everything that depends on them follows).
        formulation: ``"auto"``: each wheelset carries its axlebox body where the
            topology allows it (:func:`~jaxrail.vehicles.axleboxes.carry_axleboxes`:
            no axle joints), else the file's joints; ``"joints"``: the file's bodies and
            joints as written (eq. 19), the reference the other is checked against.
    """
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
    model = read_vehicle_model(data, where, parameters)
    settings = _vehicle_table(model)
    _check_axleboxes(model)
    check_supported(model)
    axle_bodies = ()
    if formulation == "auto":
        folded = carry_axleboxes(model)
        model, axle_bodies = folded.model, folded.axle_bodies
    wheel_spec = _wheels(model)
    if wheel is None:
        profile, radius, b2b, table = wheel_spec
        try:
            wheel = wheel_profile(profile, radius, b2b, folder)
        except ValueError as error:
            raise file_error(where, table, "profile", str(error)) from None
    loads = static_loads(model, settings["gravity"])
    position = {b.name: b.position for b in model.bodies} | {"ground": (0.0, 0.0, 0.0)}
    joints = [_description(model, link, position) for link in model.joints]
    forces = [_description(model, link, position, loads) for link in model.elements]
    bodies = [RigidBody(b.name, b.mass, b.inertia) for b in model.bodies]
    system, system_params = build_system(bodies, joints, forces,
                                         gravity=(0.0, 0.0, -settings["gravity"]),
                                         axle_bodies=axle_bodies)
    names = system.body_names
    leading = sorted(model.wheelsets, key=lambda w: -position[w.body][0])
    axleboxes = tuple(names.index(w.axlebox) for w in leading if w.axlebox is not None)
    vehicle = Vehicle(settings["name"], system, tuple(names.index(w.body) for w in leading),
                      config, axleboxes=axleboxes)
    layout = np.array([b.position for b in model.bodies])
    return vehicle, VehicleParams(system_params,
                                  ContactParameters() if contact is None else contact,
                                  wheel, layout)


def _vehicle_table(model) -> dict:
    table = model.vehicle
    for key in table:
        if key in RAIL_KEYS:
            raise file_error(model.where, "vehicle", key, "the rail profile and the gauge "
                             "belong to the track now: give them in the scenario's [track] "
                             f"({', '.join(RAIL_KEYS)}), or in Python to "
                             "Track.with_rails(Rails.at_gauge(profile, gauge))")
        if key not in VEHICLE_KEYS:
            raise file_error(model.where, "vehicle", key, f"unknown key; known: "
                             f"{', '.join(VEHICLE_KEYS)}")
    name = table.get("name")
    if not isinstance(name, str) or not name.strip():
        raise file_error(model.where, "vehicle", "name", "missing: the vehicle's name")
    settings = {"name": name, "gravity": GRAVITY}
    if "gravity" in table:
        try:
            q = read_number(table["gravity"], model.parameters)
            check_dimension(q, "m/s^2")
            if isinstance(q, list) or not q.value > 0.0:
                raise ValueError("must be one positive number")
        except ValueError as error:
            raise file_error(model.where, "vehicle", "gravity", str(error)) from None
        settings["gravity"] = q.value
    return settings


def _wheels(model):
    """(profile, nominal radius, back-to-back, table) shared by every wheelset: the
    vehicle has one wheel profile (:attr:`VehicleParams.wheel`)."""
    first = None
    for w in model.wheelsets:
        profile = w.profile
        if isinstance(profile, list) and len(profile) == 2 and profile[0] == profile[1]:
            profile = profile[0]
        if not isinstance(profile, str):
            raise file_error(model.where, w.table, "profile", f"one profile name or file "
                             f"for both wheels (or [left, right], the same), got {w.profile!r}")
        spec = (profile.strip().lower(), w.nominal_radius, w.back_to_back)
        if first is None:
            first, name = spec, profile
        elif spec != first:
            raise file_error(model.where, w.table, "profile", f"(profile, nominal radius, "
                             f"back-to-back) {spec} differs from the first wheelset's "
                             f"{first}: a vehicle has one wheel profile today")
    return name, first[1], first[2], model.wheelsets[0].table


def _check_axleboxes(model):
    with_box = [w for w in model.wheelsets if w.axlebox is not None]
    if with_box and len(with_box) != len(model.wheelsets):
        w = next(w for w in model.wheelsets if w.axlebox is None)
        raise file_error(model.where, w.table, "axlebox", "missing: either every wheelset "
                         "names its axlebox body or none does")
    for w in with_box:
        if not any({j.body_i, j.body_j} == {w.body, w.axlebox} for j in model.joints):
            raise file_error(model.where, w.table, "axlebox", f"no joint joins "
                             f"{w.axlebox!r} to {w.body!r} (the axlebox rides on its "
                             f"wheelset through a revolute joint about the axle)")


def _minus(a, b):
    return tuple(x - y for x, y in zip(a, b))


def _description(model, link, position, loads=None):
    """The build-time description of a joint or element, its points in its bodies'
    frames (the bodies are unrotated at rest: point = vehicle-frame point - centre),
    checked by its kind alone so that errors name its table."""
    values = link.values
    if loads is not None and link.static:
        load, upper_is_j = loads[link.name]
        try:
            values = ek.static_preload(link.cls, values, load, upper_is_j)
        except ValueError as error:
            raise file_error(model.where, link.table, "preload", str(error)) from None
    spec = ek.build(link.cls, values, body_i=link.body_i, body_j=link.body_j,
                    point_i=_minus(link.at_i, position[link.body_i]),
                    point_j=_minus(link.at_j, position[link.body_j]), name=link.name)
    try:
        if loads is None:
            getattr(spec, "frames", lambda: None)()
        else:
            fc.FORCE_KINDS[link.kind].params([spec], f"force {link.kind}")
    except (ValueError, TypeError) as error:
        raise file_error(model.where, link.table, _culprit(link, str(error)), str(error)) from None
    return spec


def _culprit(link, message: str) -> str:
    """The keys a kind's own error is about: the fields it names, else the element's
    tables (fields given as lists of numbers, not directions), else its parameters."""
    named = [f for f in ek.fields(link.cls) if re.search(rf"\b{f}\b", message)]
    tables = [f for f, v in link.values.items() if isinstance(v, list) and len(v) > 1
              and not ek.is_direction(f)]
    return ", ".join(named or tables) or "kind parameters"
