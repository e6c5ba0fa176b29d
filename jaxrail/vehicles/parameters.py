"""Named scalar parameters of a vehicle and its track that can be fitted or differentiated.

Each name reads and writes one number of :class:`jaxrail.vehicles.VehicleParams`, or of
the :class:`jaxrail.track.Track` for ``track_gauge`` (traced: writing it never
recompiles): :func:`get_values` reads both, :func:`set_values` writes the vehicle's and
:func:`set_values_and_track` both. Contact: ``contact_stiffness`` (the factor on
the Hertz stiffness, 1 = Hertz), ``friction`` [-], ``restitution`` (the normal law's
c_e, eq. 17 and the damped Hertz laws). Suspension (every element of the family at
once, per element): ``primary_longitudinal_stiffness``, ``primary_lateral_stiffness``,
``primary_vertical_stiffness`` [N/m], ``primary_vertical_damping`` [N s/m] and the
``secondary_*`` ones (lateral and vertical damping too) for vehicles with a secondary
suspension: older names of the bushings' element parameters
(:mod:`jaxrail.vehicles.element_parameters`), ``primary_lateral_stiffness`` reading and
writing ``primary.lateral_stiffness`` of the bushings of family ``primary``. Geometry:
``track_gauge`` [m] (the track's: moves both rails, keeping their profile) and
``wheelbase`` [m] (the axle spacing of each bogie: moves the axles with their axleboxes
and the primary suspension's seats on the frame; masses and inertias stay).
"""

import dataclasses
from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp

from .._ranges import within
from ..profiles.analytic import ConicalProfile
from ..track import Rails
from .vehicle import VehicleParams


@dataclasses.dataclass(frozen=True)
class Parameter:
    """A named parameter: unit, meaning, how to read and write it, and the range
    ``(low, high)`` of values accepted from users (draws, initial values, bounds).
    ``on``: ``"vehicle"`` (``get(vehicle, params)``, ``set(vehicle, params, value)`` ->
    params) or ``"track"`` (``get(track)``, ``set(track, value)`` -> track)."""

    name: str
    unit: str
    description: str
    get: Callable[..., object]
    set: Callable[..., object]
    range: tuple[float, float]
    on: str = "vehicle"

    def check(self, value, where: str, key: str | None = None) -> float:
        """``value`` as a float if it is finite and within :attr:`range`, else
        ValueError naming ``where``, ``key`` (default the name), the range and the value."""
        return within(value, *self.range, self.unit, f"{where}: {key or self.name}")


def _contact(field, unit, description, range_):
    return Parameter(
        field if field != "stiffness_scale" else "contact_stiffness", unit, description,
        lambda vehicle, params: getattr(params.contact, field),
        lambda vehicle, params, value: eqx.tree_at(lambda p: getattr(p.contact, field),
                                                   params, jnp.asarray(value, jnp.float64)),
        range_)


def _restitution_get(vehicle, params):
    law = params.contact.normal_law
    if not hasattr(law, "restitution"):
        raise ValueError(f"the normal law {type(law).__name__} has no restitution")
    return law.restitution


def _restitution_set(vehicle, params, value):
    _restitution_get(vehicle, params)
    return eqx.tree_at(lambda p: p.contact.normal_law.restitution, params,
                       jnp.asarray(value, jnp.float64))


def _bushing_group(vehicle, family):
    """The bushing group and the indices (list) of its bushings named ``<family>_...``."""
    for group in vehicle.system.force_groups:
        if group.kind == "bushing":
            rows = [i for i, name in enumerate(group.names) if name.startswith(family + "_")]
            if rows:
                return group, rows
    raise ValueError(f"vehicle {vehicle.name!r} has no {family} suspension bushings")


def _bushing_rows(vehicle, family):
    """Indices of the bushings named ``<family>_...`` in the vehicle's bushing group."""
    return jnp.asarray(_bushing_group(vehicle, family)[1])


def _gauge_set(track, value):
    return track.with_rails(Rails.at_gauge(track.rails.profile, value))


def _wheelbase_get(vehicle, params):
    rows = _bushing_rows(vehicle, "primary")
    return jnp.mean(2.0 * jnp.abs(params.system.forces["bushing"].point_j[rows, 0]))


def _wheelbase_set(vehicle, params, value):
    """Each primary bushing's seat on its frame (point_j, frame axes) at +-value/2
    ahead of the frame's centre, and its axlebox and wheelset (or its wheelset that
    carries its axleboxes) there in the layout."""
    group, rows = _bushing_group(vehicle, "primary")
    seats = params.system.forces["bushing"].point_j
    ahead = jnp.sign(seats[jnp.asarray(rows), 0]) * 0.5 * jnp.asarray(value, jnp.float64)
    layout = params.layout
    for x, row in zip(ahead, rows):
        carried = group.body_i[row]
        if carried in vehicle.axleboxes:
            moved = [carried, vehicle.wheelsets[vehicle.axleboxes.index(carried)]]
        elif carried in vehicle.wheelsets:
            moved = [carried]
        else:
            raise ValueError(f"vehicle {vehicle.name!r}: the primary bushings' body i is "
                             f"neither an axlebox body nor a wheelset")
        layout = layout.at[jnp.asarray(moved), 0].set(layout[group.body_j[row], 0] + x)
    return eqx.tree_at(lambda p: (p.system.forces["bushing"].point_j, p.layout), params,
                       (seats.at[jnp.asarray(rows), 0].set(ahead), layout))


def _bushing(family, axis, field, unit, range_):
    """``<family>_<axis>_<field>``: the older name of the bushings' element parameter
    ``<family>.<axis>_<field>``, which reads and writes the numbers."""
    target = f"{family}.{axis}_{field}"

    def generated(vehicle, params):
        from .element_parameters import element_parameters
        found = element_parameters(vehicle, params, kinds=("bushing",)).get(target)
        if found is None:
            raise ValueError(f"vehicle {vehicle.name!r} has no {family} suspension bushings")
        return found

    return Parameter(f"{family}_{axis}_{field}", unit,
                     f"{family} suspension {axis} {field}, per element (the bushings' "
                     f"{target})",
                     lambda vehicle, params: generated(vehicle, params).get(vehicle, params),
                     lambda vehicle, params, value: generated(vehicle, params).set(
                         vehicle, params, value),
                     range_)


def _wheelset_mass_get(vehicle, params):
    return jnp.mean(params.system.bodies.mass[jnp.asarray(vehicle.wheelsets)])


def _wheelset_mass_set(vehicle, params, value):
    where = lambda p: p.system.bodies.mass  # noqa: E731
    return eqx.tree_at(where, params, where(params).at[jnp.asarray(vehicle.wheelsets)].set(
        jnp.asarray(value, jnp.float64)))


def _cone(params):
    surfaces = getattr(params.wheel, "surfaces", ())
    if len(surfaces) != 1 or not isinstance(surfaces[0], ConicalProfile):
        raise ValueError(f"the wheel {getattr(params.wheel, 'name', '?')!r} has no cone angle "
                         f"(only conical_wheel's has; a measured profile such as S1002 is "
                         f"not parametric)")
    return surfaces[0]


def _cone_get(vehicle, params):
    return _cone(params).cone_angle


def _cone_set(vehicle, params, value):
    _cone(params)
    return eqx.tree_at(lambda p: p.wheel.surfaces[0].cone_angle, params,
                       jnp.asarray(value, jnp.float64))


PROFILE_PARAMETERS = ("track_gauge", "wheel_cone_angle")
"""The named parameters that change the wheel-rail geometry: a contact table, built for
one profile pair at one gauge, does not follow them."""


def check_contact_follows(names, contact: str) -> None:
    """ValueError, before anything is built, for :data:`PROFILE_PARAMETERS` among
    ``names`` with the ``contact`` mode ``"table"``."""
    fixed = [name for name in names if name in PROFILE_PARAMETERS]
    if fixed and contact == "table":
        raise ValueError(f"{fixed}: the contact table is built for one profile pair at one "
                         f"gauge and does not follow them; use the paper's search "
                         f"(contact 'online')")


_AXES = ("longitudinal", "lateral", "vertical")
PARAMETERS = {p.name: p for p in [
    _contact("stiffness_scale", "-", "factor on the Hertz contact stiffness (1 = Hertz)",
             (0.01, 100.0)),
    _contact("friction", "-", "wheel-rail friction coefficient", (0.01, 1.5)),
    Parameter("restitution", "-", "c_e of the normal law (effective e = sqrt(c_e))",
              _restitution_get, _restitution_set, (0.01, 1.0)),
    *[_bushing(family, axis, "stiffness", "N/m", (0.0, 1e10))
      for family in ("primary", "secondary") for axis in _AXES],
    *[_bushing(family, axis, "damping", "N s/m", (0.0, 1e8))
      for family in ("primary", "secondary") for axis in _AXES],
    # track gauges from narrow (600 mm) to broad (1676 mm)
    Parameter("track_gauge", "m", "distance between the rails' gauge points, 14 mm below "
              "their tops", lambda track: track.rails.gauge, _gauge_set, (0.6, 1.7),
              on="track"),
    Parameter("wheelbase", "m", "axle spacing of each bogie", _wheelbase_get,
              _wheelbase_set, (0.5, 5.0)),
    # the unsprung mass: each wheelset's weight adds to its wheel loads and to the rest
    # pose's load (the suspension's preloads carry the sprung masses, unchanged)
    Parameter("wheelset_mass", "kg", "mass of each wheelset body (its inertia unchanged)",
              _wheelset_mass_get, _wheelset_mass_set, (100.0, 1e4)),
    # the conicity of a coned wheel (lambda = tan of its angle on a rail inclined alike)
    Parameter("wheel_cone_angle", "rad", "cone angle of a coned wheel (conical_wheel)",
              _cone_get, _cone_set, (0.001, 0.2)),
]}


def vehicle_parameters(vehicle, params) -> dict[str, Parameter]:
    """Every named parameter of this vehicle: :data:`PARAMETERS` and those made from its
    force elements (:mod:`jaxrail.vehicles.element_parameters`, ``<family>.<field>``)."""
    from .element_parameters import element_parameters
    return PARAMETERS | element_parameters(vehicle, params)


def parameter(name: str, vehicle=None, params=None) -> Parameter:
    """The :class:`Parameter` called ``name``: one of :data:`PARAMETERS`, or with the
    vehicle and its params one of its elements' (``<family>.<field>``); ValueError lists
    the known names."""
    if name in PARAMETERS:
        return PARAMETERS[name]
    known = PARAMETERS if vehicle is None else vehicle_parameters(vehicle, params)
    if name not in known:
        raise ValueError(f"unknown parameter {name!r}; known: {', '.join(known)}")
    return known[name]


def get_values(vehicle, params, names, track=None) -> jnp.ndarray:
    """Values (k,) of the named parameters; ``track``: the track, needed for the
    track's (``track_gauge``)."""
    def value(name):
        p = parameter(name, vehicle, params)
        if p.on == "vehicle":
            return p.get(vehicle, params)
        if track is None:
            raise ValueError(f"{name} is the track's: give get_values the track (track=)")
        return p.get(track)
    return jnp.stack([jnp.asarray(value(n)) for n in names])


def set_values(vehicle, params, names, values) -> VehicleParams:
    """``params`` with the named parameters set to ``values`` (k,) (traced); ValueError
    for a track's parameter (:func:`set_values_and_track` writes those)."""
    return _set_values(vehicle, params, None, names, values, track_allowed=False)[0]


def set_values_and_track(vehicle, params, track, names, values):
    """``(params, track)`` with the named parameters, the vehicle's and the track's
    (``track_gauge``), set to ``values`` (k,) (traced)."""
    return _set_values(vehicle, params, track, names, values, track_allowed=True)


def _set_values(vehicle, params, track, names, values, track_allowed):
    for k, name in enumerate(names):
        p = parameter(name, vehicle, params)
        if p.on == "vehicle":
            params = p.set(vehicle, params, values[k])
        elif track_allowed:
            track = p.set(track, values[k])
        else:
            raise ValueError(f"{name} is the track's: set it with set_values_and_track("
                             f"vehicle, params, track, names, values)")
    return params, track
