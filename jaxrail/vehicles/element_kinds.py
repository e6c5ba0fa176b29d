"""The description dataclasses of force elements and joints, found by their ``kind``.

A vehicle file's ``[[element]]`` names a ``kind`` of :data:`jaxrail.multibody.forces.FORCE_KINDS`
and a ``[[joint]]`` one of :data:`jaxrail.multibody.joints.JOINT_KINDS`; its other keys are
the fields of that kind's build-time description (:class:`~jaxrail.multibody.Bushing`,
:class:`~jaxrail.multibody.Revolute`, ...). The description of a kind is the frozen
dataclass whose class variable ``kind`` is that kind: every such dataclass in the
modules of :mod:`jaxrail` is found (a new kind in a new module needs no change here),
and :func:`register` adds one from elsewhere.

What the loader knows of a field, from its name or from optional class variables of
the dataclass:

- ``units`` (class variable ``{field: unit or [unit per entry]}``, or :data:`UNITS`
  for the kinds written before it): the dimension a field's value must have;
- directions: fields named ``axis*`` and ``frame*`` take plain numbers;
- mirroring (``mirror = true``, y -> -y): ``axis*`` vectors flip their y entry,
  ``frame*`` matrices F become R F R (R = diag(1, -1, 1), right-handed again), a
  six-entry ``preload`` (force, then moment, in the element's frame) becomes
  (fx, -fy, fz, -mx, my, -mz); class variable ``mirror_signs`` ``{field: signs}``
  gives other fields' sign patterns; every other field is kept.
"""

import dataclasses
import importlib
import pkgutil
import sys
import typing

import numpy as np

from ..multibody import forces as fc
from ..multibody import joints as jt

LOADER_FIELDS = ("body_i", "body_j", "point_i", "point_j", "name")
"""Fields the loader fills itself (from ``body_i``/``body_j`` names and ``at``)."""

_SIX_TRANSLATION = ["N/m"] * 3 + ["N m/rad"] * 3
UNITS = {
    "bushing": {"stiffness": _SIX_TRANSLATION,
                "damping": ["N s/m"] * 3 + ["N m s/rad"] * 3,
                "preload": ["N"] * 3 + ["N m"] * 3},
    "spring_damper": {"stiffness": "N/m", "free_length": "m", "damping": "N s/m"},
    "bump_stop": {"clearance": "m", "stiffness": "N/m", "damping": "N s/m"},
}
"""Dimensions of the fields of the kinds that declare no ``units`` class variable."""

MIRROR_SIX = (1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
REFLECT = np.diag([1.0, -1.0, 1.0])
_registry: dict[str, type] = {}


def register(cls) -> type:
    """Register a description dataclass under its class variable ``kind`` (for kinds
    defined outside :mod:`jaxrail`); returns it, so it serves as a decorator."""
    if not dataclasses.is_dataclass(cls) or not isinstance(getattr(cls, "kind", None), str):
        raise ValueError(f"{cls!r} is not a dataclass with a class variable 'kind'")
    _registry[cls.kind] = cls
    return cls


def _scan():
    """Import :mod:`jaxrail.multibody`'s modules, then register every dataclass with
    a ``kind`` class variable in the loaded modules of :mod:`jaxrail`."""
    import jaxrail.multibody as package

    for info in pkgutil.walk_packages(package.__path__, package.__name__ + ".",
                                      onerror=lambda name: None):
        try:
            importlib.import_module(info.name)
        except Exception:  # a module that does not import holds no usable kind
            continue
    modules = [(name, m) for name, m in list(sys.modules.items()) if m is not None
               and (name == "jaxrail" or name.startswith("jaxrail."))]
    # the multibody package's descriptions first: they win a clash of kind names
    modules.sort(key=lambda item: not item[0].startswith(package.__name__))
    for _, module in modules:
        for value in list(vars(module).values()):
            if (isinstance(value, type) and dataclasses.is_dataclass(value)
                    and isinstance(value.__dict__.get("kind"), str)):
                _registry.setdefault(value.kind, value)


def description(kind: str, family: str) -> type:
    """The description dataclass of ``kind``; ``family`` is "element" (FORCE_KINDS) or
    "joint" (JOINT_KINDS). ValueError lists the known kinds."""
    known = fc.FORCE_KINDS if family == "element" else jt.JOINT_KINDS
    if not isinstance(kind, str) or kind not in known:
        raise ValueError(f"unknown {family} kind {kind!r}; known kinds: "
                         f"{', '.join(sorted(known))}")
    if kind not in _registry:
        _scan()
    if kind not in _registry:
        raise ValueError(f"{family} kind {kind!r} has no description dataclass with "
                         f"kind = {kind!r} (register one with "
                         f"jaxrail.vehicles.element_kinds.register)")
    return _registry[kind]


def fields(cls) -> dict[str, dataclasses.Field]:
    """The fields of a description the file gives (all but :data:`LOADER_FIELDS`)."""
    return {f.name: f for f in dataclasses.fields(cls) if f.name not in LOADER_FIELDS}


def required(cls) -> list[str]:
    """Fields of a description without a default."""
    missing = dataclasses.MISSING
    return [n for n, f in fields(cls).items()
            if f.default is missing and f.default_factory is missing]


def is_direction(field: str) -> bool:
    """Fields that take plain numbers: axes and frames."""
    return field.startswith("axis") or field.startswith("frame")


def is_plain(cls, field: str) -> bool:
    """Fields typed ``str`` or ``bool`` (options, not numbers): taken as written."""
    return fields(cls)[field].type in (str, bool, "str", "bool")


def expected_unit(cls, field: str):
    """The unit a field's dimension must match (str, list per entry) or None."""
    declared = getattr(cls, "units", None)
    table = declared if isinstance(declared, dict) else UNITS.get(cls.kind, {})
    if field in table:
        return table[field]
    return "-" if is_direction(field) else None


def mirrored(cls, field: str, value):
    """The value of ``field`` in the mirror image (y -> -y) of an element."""
    signs = (getattr(cls, "mirror_signs", None) or {}).get(field)
    if value is None:
        return None
    array = np.asarray(value, dtype=np.float64)
    # + 0.0: the mirror image of a zero is +0.0, not the -0.0 of 0.0 * -1
    if signs is not None:
        return (array * np.asarray(signs) + 0.0).tolist()
    if field.startswith("axis") and array.shape == (3,):
        return (REFLECT @ array).tolist()
    if field.startswith("frame") and array.shape == (3, 3):
        return (REFLECT @ array @ REFLECT).tolist()
    if field == "preload" and array.shape == (6,):
        return (array * np.asarray(MIRROR_SIX) + 0.0).tolist()
    return value


def _bushing_static(values: dict, load: float, upper_is_j: bool) -> dict:
    """A six-component preload carrying ``load`` [N] vertically at zero deflection
    (it pushes the upper body up): the bushing's law F = K s + C sdot + F0 acts on body
    j as -B_i F, so F0 = -/+ B_i^T e_z load for an upper body j / i."""
    vertical = -load if upper_is_j else load
    frame = values.get("frame_i")
    if frame is None:
        force = [0.0, 0.0, vertical]
    else:
        force = (np.asarray(frame, dtype=np.float64).T @ np.array([0.0, 0.0, vertical])).tolist()
    return {**values, "preload": force + [0.0, 0.0, 0.0]}


def _air_spring_static(values: dict, load: float, upper_is_j: bool) -> dict:
    """An air spring's scalar vertical preload F0 [N] carrying ``load`` at zero
    deflection: its vertical force F0 + k1 u_z + ... acts like a bushing's (same sign as
    K u, in body i's axes), so F0 = -load pushes an upper body j up, +load an upper
    body i (:class:`~jaxrail.multibody.elements_series.AirSpring`)."""
    return {**values, "preload": -load if upper_is_j else load}


STATIC_PRELOADS: dict[str, typing.Callable] = {"bushing": _bushing_static,
                                               "air_spring": _air_spring_static}
"""kind -> ``f(values, load [N], upper_is_j) -> values``: how ``preload = "static"``
sets an element's fields to carry ``load`` at zero deflection. Kinds not listed but
with a six-entry ``preload`` field use the bushing's rule."""

NOMINAL_LENGTHS = ("free_length",)
"""Fields that take ``"nominal"``: the distance [m] between the element's two points
at the nominal layout (``at_i``, ``at_j``), so that a spring or rod along the line
between them (a Maxwell damper, a traction rod, a spring-damper) is unloaded there."""


def nominal_length(at_i, at_j) -> float:
    """|at_j - at_i| [m]: the distance between two points of the vehicle frame; a
    ``"nominal"`` length must not be zero (the line between the points is undefined)."""
    length = float(np.linalg.norm(np.subtract(at_j, at_i, dtype=np.float64)))
    if not length > 0.0:
        raise ValueError("\"nominal\": the element's points coincide, so the distance "
                         "between them is zero; give at_i and at_j apart")
    return length


def static_preload(cls, values: dict, load: float, upper_is_j: bool) -> dict:
    """``values`` with the element carrying ``load`` [N] at rest; ValueError if the
    kind cannot."""
    if cls.kind in STATIC_PRELOADS:
        return STATIC_PRELOADS[cls.kind](values, load, upper_is_j)
    preload = fields(cls).get("preload")
    if preload is not None and np.shape(preload.default) == (6,):
        return _bushing_static(values, load, upper_is_j)
    raise ValueError(f'preload = "static" needs a kind that carries a preload (bushing, '
                     f'or one listed in element_kinds.STATIC_PRELOADS); {cls.kind!r} '
                     f'does not')


def build(cls, values: dict, **loader_fields):
    """The description dataclass instance."""
    return cls(**loader_fields, **values)
