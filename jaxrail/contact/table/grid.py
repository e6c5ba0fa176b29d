"""A contact table's layout: the grid of wheel poses, the fields stored per patch slot
and level, and the :class:`ContactTable` that holds them (:mod:`jaxrail.contact.table`)."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


# A slot's contact point as the search makes it (its deepest point, the centre and
# breadth of its interpenetration: the point is blended from the first two by the
# breadth), the rail point's offset from it on the profiles and the Hertz curvature
GEOMETRY = ("y_deepest", "centre", "breadth", "rail_from_wheel", "curvature_contact_y")
# each slot's depth as a line in the wheel's height, the geometry, and the geometry's
# rates [per m the wheel comes down]: the tangents of the interpolation across levels
FIELDS = ("depth_offset", "depth_slope") + GEOMETRY + tuple(f"{name}_rate" for name in GEOMETRY)
_VALUES = slice(2, 2 + len(GEOMETRY))  # the geometry's columns of FIELDS
_RATES = slice(2 + len(GEOMETRY), len(FIELDS))  # and its rates'
_WHERE = len(FIELDS)  # at build time only: the contact point y_wheel [m], for tracking


class Axis(eqx.Module):
    """A uniform grid axis: ``count`` nodes from ``start`` with spacing ``step``."""

    start: float = eqx.field(static=True)
    step: float = eqx.field(static=True)
    count: int = eqx.field(static=True)

    @property
    def nodes(self) -> np.ndarray:
        return self.start + self.step * np.arange(self.count)

    @classmethod
    def span(cls, lo: float, hi: float, step: float) -> "Axis":
        """Nodes covering ``[lo, hi]`` with spacing at most ``step`` (one node if equal)."""
        if hi < lo or step <= 0.0:
            raise ValueError(f"axis needs lo <= hi and step > 0, got {lo}, {hi}, {step}")
        if hi == lo:
            return cls(float(lo), 1.0, 1)
        count = math.ceil((hi - lo) / step - 1e-9) + 1
        return cls(float(lo), (hi - lo) / (count - 1), count)


class TableGrid(eqx.Module):
    """Grid of a contact table: lateral [m], yaw [rad] and roll [rad] axes, and the
    approach axis in the square root of the deepest patch's depth [m^0.5] (the search
    runs at the depths ``approach.nodes ** 2``: denser where a conformal patch's
    contact point moves fastest with the depth, near first contact). Conformal contact
    is sensitive to roll: on UIC60 1:20 the S1002 contact point moves up to 1.5 mm per
    mrad, and on 1:40 the tread's twin patches are born and die within 1-4.5 mrad of
    roll, which irregular track's cross level reaches; the default 1 mrad roll step
    follows them (docs/contact-table.md)."""

    lateral: Axis = Axis.span(-0.016, 0.016, 1.0e-4)
    yaw: Axis = Axis.span(-0.01, 0.01, 0.005)
    roll: Axis = Axis.span(-0.008, 0.008, 0.001)
    approach: Axis = Axis.span(2.0e-3, 1.5e-2, 2.6e-3)

    @property
    def levels(self) -> tuple[float, ...]:
        """Depths [m] of the deepest patch at the approach nodes."""
        return tuple(float(x) ** 2 for x in self.approach.nodes)


class ContactTable(eqx.Module):
    """Tabulated contact of one wheel profile on its rail, both sides.

    Built from ``values`` (2, lateral, yaw, roll, approach, slots + 1, len(FIELDS))
    float64, sides (left, right): quadratic B-spline coefficients along lateral, yaw
    and roll (two more than the nodes along every axis of two or more nodes) of the
    fields of :data:`FIELDS` per patch slot at each approach level, and in the last slot
    the wheel's vertical position at that level (first field). Kept as ``heights``, the
    levels of each (side, lateral, yaw, roll) node, and ``rows``, the slots of each
    node per side and level, the level ahead of the pose axes: a lookup takes the
    block of nodes around a pose at two levels as one window of each array as it is
    (reshaping a traced table inside the integrator's loop makes XLA:CPU's loop emitters
    slow), and the window comes out as (level, node, slot field), the order in which
    the lookup's weighted sum over the nodes reads it; ``values`` gives them back in
    their shape.

    Fields:
        rows: (2, approach, lateral, yaw, roll, slots len(FIELDS)) float64.
        heights: (2, lateral, yaw, roll, approach) float64 [m].
        shape: the shape of ``values`` (static).
        grid: the :class:`TableGrid`.
        surfaces: wheel surface index of each slot (static).
        radius: nominal wheel radius [m] that places the taping point.
    """

    rows: jax.Array
    heights: jax.Array
    shape: tuple[int, ...] = eqx.field(static=True)
    grid: TableGrid = eqx.field(static=True)
    surfaces: tuple[int, ...] = eqx.field(static=True)
    radius: float = eqx.field(static=True)

    def __init__(self, values, grid: TableGrid, surfaces, radius):
        self.shape = tuple(int(n) for n in values.shape)
        values = jnp.asarray(values)
        slots = self.shape[5] - 1
        self.rows = jnp.moveaxis(values[..., :slots, :], 4, 1).reshape(
            self.shape[:1] + self.shape[4:5] + self.shape[1:4] + (-1,))
        self.heights = values[..., slots, 0]
        self.grid, self.surfaces, self.radius = grid, tuple(surfaces), float(radius)

    @property
    def values(self) -> jax.Array:
        """The coefficients in their shape (see the class docstring)."""
        slots = jnp.moveaxis(self.rows, 1, 4).reshape(self.shape[:5] + (self.shape[5] - 1,
                                                                       self.shape[6]))
        last = jnp.zeros(self.shape[:5] + (1, self.shape[6])).at[..., 0, 0].set(
            self.heights.reshape(self.shape[:5]))
        return jnp.concatenate([slots, last], axis=-2)
