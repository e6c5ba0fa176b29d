"""Named parameters made from a vehicle's force elements: ``<family>.<field>``.

A vehicle file writes a part once and repeats it per bogie and axle and mirrors it left
and right (docs/vehicle-files.md): the copies of ``yaw_damper`` are ``yaw_damper_1_left``,
``yaw_damper_1_right``, ``yaw_damper_2_left``, ... Their *family* is the name without
those suffixes, and each number of the element's kind becomes a parameter of the
family: ``yaw_damper.series_stiffness``, ``yaw_damper.damping``,
``secondary.lateral_stiffness``. Reading one gives the mean over the family's elements;
writing one sets it in all of them (traced: never recompiles), so a study fits, draws
or differentiates the yaw dampers' damping as one number.

The numbers of each kind (units SI):

- scalar fields of the kind's parameters (stiffness [N/m], damping [N s/m],
  free_length [m], torsional_stiffness [N m/rad], friction_force [N], ...);
- a bushing's six stiffnesses and dampings, by axis: ``longitudinal_stiffness``,
  ``lateral_stiffness``, ``vertical_stiffness`` [N/m], ``roll_stiffness``,
  ``pitch_stiffness``, ``yaw_stiffness`` [N m/rad], and the ``_damping`` ones;
- a Maxwell damper's ``damping`` [N s/m]: the slope of its force-velocity
  characteristic at rest; writing it scales the whole characteristic's forces per
  velocity (a linear damper's c, a blow-off damper's slope below blow-off).
"""

import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..multibody import pchip
from .parameters import Parameter

_SUFFIX = re.compile(r"(_left|_right|_\d+)$")
_AXES = ("longitudinal", "lateral", "vertical", "roll", "pitch", "yaw")
_SKIPPED = ("point_i", "point_j", "frame_i", "frame_j", "axis_i", "preload", "forces",
            "velocities", "slopes", "displacements", "values")

# unit and accepted range of a field, by its name's ending (first match)
_FIELD_UNITS = (
    ("torsional_stiffness", "N m/rad", (0.0, 1e10)),
    ("stiffness", "N/m", (0.0, 1e10)),
    ("damping", "N s/m", (0.0, 1e8)),
    ("friction_force", "N", (0.0, 1e7)),
    ("velocity_scale", "m/s", (1e-7, 1.0)),
    ("clearance", "m", (0.0, 1.0)),
    ("free_length", "m", (0.0, 100.0)),
    ("arm_length", "m", (1e-3, 10.0)),
    ("half_spacing", "m", (1e-3, 10.0)),
)


def family(name: str) -> str:
    """The element name without its repetition and mirroring suffixes."""
    while True:
        shorter = _SUFFIX.sub("", name)
        if shorter == name or not shorter:
            return name
        name = shorter


def _unit(field: str):
    for ending, unit, range_ in _FIELD_UNITS:
        if field.endswith(ending):
            return unit, range_
    return "-", (-1e12, 1e12)


def _column(kind, field, axis):
    """(parameter field name, unit, range) of a bushing's column or a plain field."""
    if axis is None:
        return (field,) + _unit(field)
    rotation = axis >= 3
    unit = {"stiffness": ("N m/rad" if rotation else "N/m", (0.0, 1e10)),
            "damping": ("N m s/rad" if rotation else "N s/m", (0.0, 1e8))}[field]
    return (f"{_AXES[axis]}_{field}",) + unit


def _field_parameter(kind, fam, rows, field, axis):
    """The Parameter of ``field`` (column ``axis`` of a (k, 6) field) of the elements
    ``rows`` of ``kind``."""
    label, unit, range_ = _column(kind, field, axis)
    index = jnp.asarray(rows)

    def where(p):
        return getattr(p.system.forces[kind], field)

    def get(vehicle, params):
        values = where(params)[index]
        return jnp.mean(values if axis is None else values[:, axis])

    def set_(vehicle, params, value):
        value = jnp.asarray(value, jnp.float64)
        old = where(params)
        new = old.at[index].set(value) if axis is None else old.at[index, axis].set(value)
        return eqx.tree_at(where, params, new)

    return Parameter(f"{fam}.{label}", unit, f"{label.replace('_', ' ')} of each {fam} "
                     f"element ({kind})", get, set_, range_)


def _maxwell_damping(fam, rows):
    """``<family>.damping`` of Maxwell dampers: the characteristic's slope at rest."""
    index = jnp.asarray(rows)

    def slope_at_rest(e):
        # force per velocity of the table's interval that holds zero force (the one
        # pchip evaluates there): the interpolant's slope at rest where zero force is a
        # point between equal secants, as in a linear or a symmetric characteristic
        f, v = e.forces[index], e.velocities[index]
        pick = jax.vmap(pchip.interval, (0, None))(f, 0.0)
        f0, f1 = jnp.sum(pick * f[:, :-1], axis=1), jnp.sum(pick * f[:, 1:], axis=1)
        v0, v1 = jnp.sum(pick * v[:, :-1], axis=1), jnp.sum(pick * v[:, 1:], axis=1)
        return (f1 - f0) / (v1 - v0)

    def get(vehicle, params):
        return jnp.mean(slope_at_rest(params.system.forces["maxwell_damper"]))

    def set_(vehicle, params, value):
        e = params.system.forces["maxwell_damper"]
        factor = (slope_at_rest(e) / jnp.asarray(value, jnp.float64))[:, None]
        velocities = e.velocities.at[index].set(e.velocities[index] * factor)
        slopes = e.slopes.at[index].set(e.slopes[index] * factor)
        return eqx.tree_at(lambda p: (p.system.forces["maxwell_damper"].velocities,
                                      p.system.forces["maxwell_damper"].slopes),
                           params, (velocities, slopes))

    return Parameter(f"{fam}.damping", "N s/m", f"damping of each {fam} damper at rest "
                     f"(maxwell_damper; scales its characteristic)", get, set_, (1.0, 1e8))


def element_parameters(vehicle, params, kinds=None) -> dict[str, Parameter]:
    """``{name: Parameter}`` of every family of the vehicle's force elements (module
    docstring), or only of the element kinds in ``kinds``; ``params``: the vehicle's
    parameters (their fields' shapes)."""
    out = {}
    for group in vehicle.system.force_groups:
        if kinds is not None and group.kind not in kinds:
            continue
        families = {}
        for row, name in enumerate(group.names):
            if name:
                families.setdefault(family(name), []).append(row)
        fields = _fields(params.system.forces[group.kind], group.kind)
        for fam, rows in families.items():
            if group.kind == "maxwell_damper":
                out[f"{fam}.damping"] = _maxwell_damping(fam, rows)
            for field, columns in fields:
                for axis in columns:
                    p = _field_parameter(group.kind, fam, rows, field, axis)
                    out.setdefault(p.name, p)
    return out


def _fields(e, kind):
    """[(field, columns)] of the numbers of a kind's parameters ``e``: columns (None,)
    for a per-element scalar, range(6) for a bushing's six."""
    if kind == "bushing":
        return [("stiffness", range(6)), ("damping", range(6))]
    names = [f for f in e.__dataclass_fields__ if np.ndim(getattr(e, f)) == 1]
    return [(f, (None,)) for f in names if f not in _SKIPPED]
