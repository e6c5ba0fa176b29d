"""A vehicle file read into flat lists: templates repeated, mirrored parts doubled,
every number in SI and every point in the vehicle frame (docs/vehicle-files.md).

``read_vehicle_model(data, where)`` takes the parsed TOML and returns a
:class:`VehicleModel`: bodies (wheelsets among them), joints and force elements, in
the order the system will have them:

- bodies: the vehicle's own first, then those of the templates it uses, then those of
  the templates these use (carbody, bogie frames, axle parts), each declaration's
  copies together in the order of the instances;
- joints and force elements: the other way round, innermost templates first (from the
  wheelsets up the load path: primary before secondary).

A copy made by a template instance has the suffix ``_1``, ``_2``, ... (numbered over
all instances of that declaration), and a mirrored part ``_left`` (as written, y >= 0)
and ``_right`` (y -> -y) after it. A body name in a template means that instance's
copy, else the enclosing instance's, else the vehicle's, else a full name.
"""

import dataclasses
from pathlib import Path

import numpy as np

from . import element_kinds as ek
from .quantities import Parameters, check_dimension, file_error, plain, read_number
from .vehicle_model import Body, Link, VehicleModel, Wheelset

TOP_KEYS = ("vehicle", "parameters", "template", "body", "wheelset", "joint", "element",
            "use")
PART_KEYS = ("body", "wheelset", "joint", "element", "use")
BODY_KEYS = {"name", "mass", "inertia", "at", "mirror"}
WHEELSET_KEYS = {"name", "mass", "inertia", "at", "profile", "nominal_radius",
                 "back_to_back", "axlebox"}
LINK_KEYS = {"name", "kind", "body_i", "body_j", "at", "at_i", "at_j", "mirror"}
SIDES = {0: "", 1: "_left", -1: "_right"}


@dataclasses.dataclass
class _Scope:
    template: str | None
    origin_x: float
    depth: int
    parent: "_Scope | None"
    declared: dict = dataclasses.field(default_factory=dict)  # local -> (base, mirrored)


class _Reader:
    def __init__(self, data, where, overrides):
        self.where = where
        if not isinstance(data, dict):
            raise ValueError(f"{where}: a vehicle file is a table, got {type(data).__name__}")
        for key in data:
            if key not in TOP_KEYS:
                raise file_error(where, "top level", key, f"unknown table; known: "
                                 f"{', '.join(TOP_KEYS)}")
        self.data = data
        self.parameters = Parameters(data.get("parameters", {}), where, overrides)
        self.templates = data.get("template", {})
        if not isinstance(self.templates, dict):
            raise file_error(where, "template", "", "write [template.NAME] tables")
        self.items, self.order, self.copies = [], {}, {}

    def error(self, table, key, problem):
        return file_error(self.where, table, key, problem)

    def number(self, entry, table, key, unit=None, plain_numbers=False):
        try:
            q = read_number(entry, self.parameters, plain_numbers)
            _check_table(q)
            check_dimension(q, unit)
        except ValueError as error:
            if str(error).startswith(self.where):
                raise
            raise self.error(table, key, str(error)) from None
        return q

    def vector(self, entry, table, key, n=3, unit="m", plain_numbers=False):
        q = self.number(entry, table, key, unit, plain_numbers)
        if not isinstance(q, list) or len(q) != n or any(isinstance(x, list) for x in q):
            raise self.error(table, key, f"must have {n} entries")
        return plain(q)

    # ---- expansion ------------------------------------------------------------------

    def visit(self, container, prefix, scope, chain=()):
        if not isinstance(container, dict):
            raise self.error(prefix.rstrip("."), "", "a template is a table of parts")
        for key in container if prefix else ():
            if key not in PART_KEYS:
                raise self.error(prefix.rstrip("."), key, f"unknown part; a template has "
                                 f"{', '.join(PART_KEYS)}")
        for what in PART_KEYS:
            entries = container.get(what, [])
            if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
                raise self.error(prefix.rstrip(".") or "top level", what,
                                 f"write [[{prefix}{what}]] tables")
            for k, entry in enumerate(entries):
                table = f"{prefix}{what}[{k}]" + (f" {entry['name']!r}" if "name" in entry
                                                   else "")
                if what == "use":
                    self.use(entry, table, scope, chain)
                else:
                    self.declare(what, entry, table, scope, (prefix, what, k))

    def declare(self, what, entry, table, scope, decl):
        name = entry.get("name")
        if not isinstance(name, str) or not name.isidentifier():
            raise self.error(table, "name", f"must be an identifier, got {name!r}")
        self.order.setdefault(decl, len(self.order))
        copy = self.copies.get(decl, 0) + 1
        self.copies[decl] = copy
        base = name if scope.template is None else f"{name}_{copy}"
        mirror = entry.get("mirror", False)
        if not isinstance(mirror, bool):
            raise self.error(table, "mirror", f"must be true or false, got {mirror!r}")
        if what in ("body", "wheelset"):
            if name in scope.declared:
                raise self.error(table, "name", f"{name!r} is declared twice here")
            scope.declared[name] = (base, mirror)
        depth = scope.depth if what in ("body", "wheelset") else -scope.depth
        self.items.append((what, entry, table, scope, base, (depth, self.order[decl], copy)))

    def use(self, entry, table, scope, chain):
        for key in entry:
            if key not in ("template", "x"):
                raise self.error(table, key, "a [[use]] has only template and x")
        name = entry.get("template")
        if not isinstance(name, str) or name not in self.templates:
            raise self.error(table, "template", f"unknown template {name!r}; templates: "
                             f"{', '.join(self.templates) or 'none'}")
        if name in chain:
            raise self.error(table, "template", f"template {name!r} uses itself")
        if "x" not in entry:
            raise self.error(table, "x", "missing: the x position of each instance [m]")
        xs = plain(self.number(entry["x"], table, "x", "m"))
        xs = xs if isinstance(xs, list) else [xs]
        if not xs or any(isinstance(x, list) for x in xs):
            raise self.error(table, "x", f"must be one position or a list of them, got {xs}")
        for x in xs:
            child = _Scope(name, scope.origin_x + x, scope.depth + 1, scope)
            self.visit(self.templates[name], f"template.{name}.", child, chain + (name,))

    # ---- evaluation -------------------------------------------------------------------

    def resolve(self, ref, scope, side, table, key):
        if not isinstance(ref, str):
            raise self.error(table, key, f"must name a body, got {ref!r}")
        stem, suffix = ref, ""
        for s in ("_left", "_right"):
            if ref.endswith(s):
                stem, suffix = ref[: -len(s)], s
        s = scope
        while s is not None:
            for local, extra in ((ref, None), (stem, suffix)):
                if local in s.declared and (extra is None or s.declared[local][1]):
                    base, mirrored = s.declared[local]
                    if extra:
                        return base + extra
                    if mirrored and side == 0:
                        raise self.error(table, key, f"body {ref!r} is mirrored: name "
                                         f"{ref}_left or {ref}_right")
                    return base + (SIDES[side] if mirrored else "")
            s = s.parent
        if ref == "ground" or ref in self.body_names:
            return ref
        raise self.error(table, key, f"unknown body {ref!r}; bodies: "
                         f"{', '.join(sorted(self.body_names))}")

    def point(self, entry, table, key, scope, side):
        x, y, z = self.vector(entry, table, key)
        if side == -1:
            y = -y
        return (scope.origin_x + x, y, z)

    def body(self, entry, table, scope, base, side, wheelset):
        allowed = WHEELSET_KEYS if wheelset else BODY_KEYS
        for key in entry:
            if key not in allowed:
                raise self.error(table, key, f"unknown key; known: {', '.join(sorted(allowed))}")
        for key in ("mass", "inertia") + (("nominal_radius",) if wheelset else ("at",)):
            if key not in entry:
                raise self.error(table, key, "missing")
        mass = self.number(entry["mass"], table, "mass", "kg")
        if isinstance(mass, list) or not mass.value > 0.0:
            raise self.error(table, "mass", f"must be one positive mass, got {plain(mass)}")
        inertia = plain(self.number(entry["inertia"], table, "inertia", "kg m^2"))
        inertia = _check_inertia(inertia, lambda p: self.error(table, "inertia", p))
        if side == -1 and inertia.shape == (3, 3):
            inertia = ek.REFLECT @ inertia @ ek.REFLECT
        radius = None
        if wheelset:
            radius = self.number(entry["nominal_radius"], table, "nominal_radius", "m")
            if isinstance(radius, list) or not radius.value > 0.0:
                raise self.error(table, "nominal_radius", "must be one positive length")
            radius = radius.value
        position = (self.point(entry["at"], table, "at", scope, side) if "at" in entry
                    else (scope.origin_x, 0.0, radius))
        if side == 1 and position[1] < 0.0:
            raise self.error(table, "at", "a mirrored part is written for the left side "
                             "(y >= 0)")
        name = base + SIDES[side]
        body = Body(name, mass.value, inertia.tolist(), position, table)
        if not wheelset:
            return body, None
        if "profile" not in entry:
            raise self.error(table, "profile", "missing: the wheels' profile (a built-in "
                             "name such as 'S1002' or a profile file)")
        b2b = entry.get("back_to_back")
        if b2b is not None:
            b2b = self.number(b2b, table, "back_to_back", "m")
            if isinstance(b2b, list) or not b2b.value > 0.0:
                raise self.error(table, "back_to_back", "must be one positive length")
            b2b = b2b.value
        axlebox = entry.get("axlebox")
        if axlebox is not None:
            axlebox = self.resolve(axlebox, scope, side, table, "axlebox")
        return body, Wheelset(name, entry["profile"], radius, b2b, axlebox, table)

    def link(self, what, entry, table, scope, base, side):
        family = "joint" if what == "joint" else "element"
        try:
            cls = ek.description(entry.get("kind"), family)
        except ValueError as error:
            raise self.error(table, "kind", str(error)) from None
        fields = ek.fields(cls)
        shorthand = {"axis"} if family == "joint" and {"axis_i", "axis_j"} <= set(fields) else set()
        static = entry.get("preload") == "static"
        for key in entry:
            if key not in LINK_KEYS | set(fields) | shorthand | ({"preload"} if static else set()):
                raise self.error(table, key, f"unknown key for kind {cls.kind!r}; its fields: "
                                 f"{', '.join(fields)}")
        bodies = [self.resolve(entry.get(k), scope, side, table, k) for k in ("body_i", "body_j")]
        if bodies[0] == bodies[1]:
            raise self.error(table, "body_j", f"joins body {bodies[0]!r} to itself")
        if "at" in entry:
            at_i = at_j = self.point(entry["at"], table, "at", scope, side)
        elif "at_i" in entry and "at_j" in entry:
            at_i = self.point(entry["at_i"], table, "at_i", scope, side)
            at_j = self.point(entry["at_j"], table, "at_j", scope, side)
        else:
            raise self.error(table, "at", "missing: the point (vehicle frame) of the "
                             "element, or at_i and at_j")
        raw = dict(entry)
        if "axis" in raw and shorthand:
            raw["axis_i"] = raw["axis_j"] = raw.pop("axis")
        values = {}
        for key, value in raw.items():
            if key not in fields or (key == "preload" and static):
                continue
            if ek.is_plain(cls, key):
                values[key] = value
                continue
            if key in ek.NOMINAL_LENGTHS and value == "nominal":
                try:
                    values[key] = ek.nominal_length(at_i, at_j)
                except ValueError as error:
                    raise self.error(table, key, str(error)) from None
                continue
            unit = ek.expected_unit(cls, key)
            q = self.number(value, table, key, unit, ek.is_direction(key))
            values[key] = ek.mirrored(cls, key, plain(q)) if side == -1 else plain(q)
        missing = [f for f in ek.required(cls) if f not in values and not
                   (f == "preload" and static)]
        if missing:
            raise self.error(table, missing[0], f"missing (kind {cls.kind!r} needs "
                             f"{', '.join(missing)})")
        return Link(cls.kind, cls, base + SIDES[side], *bodies, at_i, at_j, values, static,
                    table)

    def read(self) -> VehicleModel:
        vehicle = self.data.get("vehicle", {})
        if not isinstance(vehicle, dict):
            raise self.error("vehicle", "", "must be a table")
        self.visit(self.data, "", _Scope(None, 0.0, 0, None))
        self.items.sort(key=lambda item: item[5])
        copies = [(item, side) for item in self.items
                  for side in ((1, -1) if item[1].get("mirror", False) else (0,))]
        self.body_names = {base + SIDES[side] for (what, _, _, _, base, _), side in copies
                           if what in ("body", "wheelset")}
        bodies, wheelsets, joints, elements = [], [], [], []
        for (what, entry, table, scope, base, _), side in copies:
            if what in ("body", "wheelset"):
                body, wheelset = self.body(entry, table, scope, base, side, what == "wheelset")
                bodies.append(body)
                wheelsets += [wheelset] if wheelset else []
            else:
                (joints if what == "joint" else elements).append(
                    self.link(what, entry, table, scope, base, side))
        for group in (bodies, joints, elements):
            seen = {}
            for part in group:
                if part.name in seen or part.name == "ground":
                    raise self.error(part.table, "name", f"{part.name!r} is also the name of "
                                     f"{seen.get(part.name, 'the fixed frame')}")
                seen[part.name] = part.table
        return VehicleModel(self.where, vehicle, self.parameters, tuple(bodies),
                            tuple(wheelsets), tuple(joints), tuple(elements))


def _check_inertia(value, error) -> np.ndarray:
    """The inertia (3,) or (3, 3) as an array, or ``error(problem)`` raised."""
    try:
        j = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise error(f"give (roll, pitch, yaw) or a 3 x 3 tensor, got {value}") from None
    if j.shape == (3,):
        if not np.all(j > 0.0):
            raise error(f"principal moments must be positive, got {j.tolist()}")
    elif j.shape == (3, 3):
        if not np.allclose(j, j.T, rtol=1e-12, atol=1e-12 * np.abs(j).max()):
            raise error("the tensor must be symmetric")
        if not np.all(np.linalg.eigvalsh(j) > 0.0):
            raise error("the tensor must be positive definite")
    else:
        raise error(f"give (roll, pitch, yaw) or a 3 x 3 tensor, got shape {j.shape}")
    return j


def _check_table(q):
    """A characteristic table: rows of two quantities with different dimensions
    (e.g. mm and kN): its first column must increase strictly."""
    if not (isinstance(q, list) and len(q) > 1 and all(isinstance(r, list) and len(r) == 2
                                                     and not isinstance(r[0], list) for r in q)):
        return
    x = [r[0].value for r in q]
    columns = [{r[k].dimension for r in q} - {None} for k in (0, 1)]
    if all(columns) and columns[0] != columns[1] and any(b <= a for a, b in zip(x, x[1:])):
        raise ValueError(f"the table's first column must increase strictly, got {x}")


def read_vehicle_model(data: dict, where: str = "<data>", overrides=None) -> VehicleModel:
    """The :class:`VehicleModel` of a parsed vehicle file; ``where`` names it in errors,
    ``overrides`` ``{"group.name": SI value}`` replace named parameters."""
    return _Reader(data, str(where), overrides).read()


def data_folder() -> Path:
    """The folder of the built-in vehicle files."""
    return Path(__file__).parent / "data"
