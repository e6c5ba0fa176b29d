"""UIC60 (60E1, EN 13674-1) rail head, canted by the rail inclination.

Head geometry in the **uncanted** rail frame (mm; ``y`` lateral from the rail
centreline, positive toward the field side; ``z`` up; top of the head at (0, 0)), from
``reference/profiles.md`` section 2.1, mirrored on the gauge side (``y < 0``):

- R300 crown, centre (0, -300), for ``|y| <= 10.228``;
- R80 arcs tangent to the crown, from ``|y| = 10.228`` to ``|y| = 26.0265``;
- R13 arcs tangent to the R80 arcs, down to the head flanks;
- flanks: straight lines inclined 1:20 (1 mm outward per 20 mm down), tangent to the
  R13 arcs at ``(+-35.99981, -14.29996)`` (head width 72.00 mm).

**Inclination.** The rail is rotated about the profile origin (0, 0) toward the track
centre by the inclination angle ``theta`` (1:40 means ``theta = atan(1/40)``): a point
``(y, z)`` of the uncanted head moves to ``(y cos - z sin, y sin + z cos)``. The top
of the canted head then lies on the field side (+7.498 mm for 1:40, on the crown;
+11.49 mm for 1:20, on the field-side R80 arc). The canted profile is still a chain of
circle arcs (rotated centres) and two lines, evaluated in closed form.

**Domain** (static, set from the inclination at construction): starting at the top
and going down each side of the head, each end is the first point where either the
tangent reaches 87 degrees from horizontal or the depth below the highest point
reaches 16 mm. It covers the running surface and the gauge corner past the gauge
point (14 mm below the top) on both sides and stops short of any vertical tangent
(uncanted: the R13 arcs at 87 degrees, 14.27 mm deep; 1:40 gauge side: R13 at 87
degrees, 14.93 mm deep; 1:20 gauge side, whose flank is vertical: R13 at 87 degrees,
15.75 mm deep; field sides at 1:40 and 1:20: on the flank, 16 mm deep). Outside the
domain the height is continued along the end tangent (finite, not the real rail).
"""

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from ..compilation import computed_once
from ._base import ClosedFormProfile, below_tangent

_MM = 1e-3

# Defining dimensions of the 60E1 head [m] (reference table 2.1).
CROWN_RADIUS = 300.0 * _MM
SIDE_RADIUS = 80.0 * _MM
CORNER_RADIUS = 13.0 * _MM
CROWN_HALF_WIDTH = 10.228 * _MM  # |y| of the R300/R80 tangency
SIDE_HALF_WIDTH = 26.0265 * _MM  # |y| of the R80/R13 tangency
FLANK_INCLINATION = 1.0 / 20.0  # lateral run per unit drop of the head flank

# The domain rule (module docstring).
END_TANGENT_ANGLE = math.radians(87.0)
END_DEPTH = 16.0 * _MM

# Largest |inclination| accepted [rad]: 1:10 is far beyond any track standard.
MAX_INCLINATION = math.atan(0.1)


def _uncanted_field_side():
    """Centres and tangency points of the field-side half of the uncanted head [m]."""
    crown_centre = np.array([0.0, -CROWN_RADIUS])
    u1 = np.array([CROWN_HALF_WIDTH / CROWN_RADIUS, 0.0])
    u1[1] = math.sqrt(1.0 - u1[0] ** 2)
    side_centre = crown_centre + (CROWN_RADIUS - SIDE_RADIUS) * u1
    crown_side = crown_centre + CROWN_RADIUS * u1
    u2 = np.array([(SIDE_HALF_WIDTH - side_centre[0]) / SIDE_RADIUS, 0.0])
    u2[1] = math.sqrt(1.0 - u2[0] ** 2)
    corner_centre = side_centre + (SIDE_RADIUS - CORNER_RADIUS) * u2
    side_corner = side_centre + SIDE_RADIUS * u2
    # Outward normal of a flank running (+1/20, -1) downward.
    n3 = np.array([1.0, FLANK_INCLINATION]) / math.hypot(1.0, FLANK_INCLINATION)
    corner_flank = corner_centre + CORNER_RADIUS * n3
    flank_down = np.array([FLANK_INCLINATION, -1.0]) / math.hypot(1.0, FLANK_INCLINATION)
    return dict(
        crown_centre=crown_centre,
        side_centre=side_centre,
        corner_centre=corner_centre,
        joints=(crown_side, side_corner, corner_flank),
        flank_down=flank_down,
    )


_HEAD = _uncanted_field_side()

# Pieces from the gauge side to the field side, as one constant table of the uncanted
# head. Each piece has four points (rows of _POINTS): circle centre, a point of its line,
# the line direction (flanks only; circles get a harmless horizontal one), and the joint
# at its gauge-side end. The whole table is rotated at once and one row is gathered per
# evaluation: few operations to trace, differentiate and compile.
_PIECES = ("flank", "corner", "side", "crown", "side", "corner", "flank")
_IS_LINE = np.array([name == "flank" for name in _PIECES])
_GAUGE = np.array([-1.0, 1.0])  # mirror a field-side point to the gauge side
_JOINT_ARC = np.array([1, 1, 2, 3, 4, 5])  # an arc piece at each of the six joints


def _point_table():
    j1, j2, j3 = _HEAD["joints"]
    joints = [_GAUGE * j3, _GAUGE * j3, _GAUGE * j2, _GAUGE * j1, j1, j2, j3]
    centres = [_GAUGE * _HEAD["corner_centre"], _GAUGE * _HEAD["corner_centre"],
               _GAUGE * _HEAD["side_centre"], _HEAD["crown_centre"],
               _HEAD["side_centre"], _HEAD["corner_centre"], _HEAD["corner_centre"]]
    line_points = [_GAUGE * j3] + [j3] * 6  # used by the flanks only
    directions = [_GAUGE * _HEAD["flank_down"]] + [[1.0, 0.0]] * 5 + [_HEAD["flank_down"]]
    return np.stack([np.array(centres), np.array(line_points), np.array(directions),
                     np.array(joints)], axis=1)  # (7 pieces, 4 points, (y, z))


_POINTS = _point_table()
# Per piece: radius (flanks carry their neighbour's, unused) and a line flag.
_CONSTANTS = np.stack([np.array([CORNER_RADIUS, CORNER_RADIUS, SIDE_RADIUS, CROWN_RADIUS,
                                 SIDE_RADIUS, CORNER_RADIUS, CORNER_RADIUS]),
                       _IS_LINE.astype(np.float64)], axis=1)  # (7, 2)


def _canted_table(xp, theta):
    """Per piece (7, 10): canted y of the 4 points, their z, then radius and line flag."""
    c, s = xp.cos(theta), xp.sin(theta)
    y, z = _POINTS[..., 0], _POINTS[..., 1]
    return xp.concatenate([c * y - s * z, s * y + c * z, xp.asarray(_CONSTANTS)], axis=1)


def _breaks(table):
    """Canted y [m] of the six joints (gauge side first): piece k+1 starts at break k."""
    return table[1:, 3]


def _piece_derivatives(xp, row, y):
    """Height, slope and second derivative [m, -, 1/m] of the piece whose table row is
    ``row``, continued to ``y`` [m] beyond its joints (circles beyond their vertical
    tangents give a finite dummy; the gradient-safe double ``where`` keeps NaN out of
    derivatives). A circle ``zc + sqrt(r^2 - d^2)`` has slope ``-d / root`` and second
    derivative ``-r^2 / root^3``; a line has its slope and zero."""
    yc, y0, dy, zc, z0, dz, radius, is_line = (row[i] for i in (0, 1, 2, 4, 5, 6, 8, 9))
    d = y - yc
    arg = radius * radius - d * d
    ok = arg > 0.0
    root = xp.sqrt(xp.where(ok, arg, 1.0))
    circle_h = zc + xp.where(ok, root, 0.0)
    circle_s = xp.where(ok, -d / root, 0.0)
    circle_c = xp.where(ok, -radius * radius / (root * root * root), 0.0)
    # The gauge flank turns vertical at 1:20 (dy = 0); it lies outside the domain then.
    steep = xp.abs(dy) <= 1e-12
    m = xp.where(steep, 0.0, dz / xp.where(steep, 1.0, dy))
    line = is_line > 0.5
    return (xp.where(line, z0 + m * (y - y0), circle_h), xp.where(line, m, circle_s),
            xp.where(line, 0.0, circle_c))


def _canted_pieces(theta):
    """Canted geometry (numpy) for a concrete inclination ``theta`` [rad]: dict of
    ``breaks``, ``joint_z`` (6,), per piece ``yc, zc, radius`` and the line ``y0, z0, m``
    (7,) [m]."""
    table = _canted_table(np, np.float64(theta))
    m = np.array([_piece_derivatives(np, row, 0.0)[1] for row in table])
    return dict(breaks=_breaks(table), joint_z=table[1:, 7], yc=table[:, 0], zc=table[:, 4],
                radius=table[:, 8], y0=table[:, 1], z0=table[:, 5], m=m)


def _domain(theta: float) -> tuple[float, float]:
    """Static domain [m] for a concrete inclination (rule in the module docstring)."""
    p = _canted_pieces(theta)
    b = p["breaks"]
    lows = np.concatenate([[-np.inf], b])
    highs = np.concatenate([b, [np.inf]])
    tol = 1e-12

    # Highest point: the top of whichever arc has its topmost point inside its range.
    tops = [(p["zc"][k] + p["radius"][k], p["yc"][k]) for k in range(1, 6)
            if lows[k] - tol <= p["yc"][k] <= highs[k] + tol]
    z_top, _ = max(tops)
    z_end = z_top - END_DEPTH
    sin_end, cos_end = math.sin(END_TANGENT_ANGLE), math.cos(END_TANGENT_ANGLE)

    def side_end(sign, arcs, line):
        candidates = []
        for k in arcs:
            yc, zc, r = p["yc"][k], p["zc"][k], p["radius"][k]
            y_angle = yc + sign * r * sin_end  # tangent at END_TANGENT_ANGLE
            if lows[k] - tol <= y_angle <= highs[k] + tol:
                candidates.append((zc + r * cos_end, y_angle))
            if z_end >= zc and r * r >= (z_end - zc) ** 2:
                y_depth = yc + sign * math.sqrt(r * r - (z_end - zc) ** 2)
                if lows[k] - tol <= y_depth <= highs[k] + tol:
                    candidates.append((z_end, y_depth))
        m = p["m"][line]
        if sign * m < 0.0:  # the flank still descends outward (not vertical/overhanging)
            y_line = p["y0"][line] + (z_end - p["z0"][line]) / m
            if lows[line] - tol <= y_line <= highs[line] + tol:
                candidates.append((z_end, y_line))
        if not candidates:
            raise ValueError(f"UIC60: no domain end found for inclination {theta}")
        return max(candidates)[1]  # the highest candidate is reached first going down

    y_min = side_end(-1.0, (3, 2, 1), 0)
    y_max = side_end(+1.0, (3, 4, 5), 6)
    return float(y_min), float(y_max)


class UIC60(ClosedFormProfile):
    """UIC60 / 60E1 rail head, canted by ``inclination`` toward the track centre.

    Fields:
        inclination: rail inclination angle [rad] (traced float64 scalar; positive
            tilts the rail top toward the track centre, as in track).
        y_min, y_max: the lateral domain [m] (static; see the module docstring).
        name: label (static).

    ``y`` [m] is measured from the profile origin (top of the uncanted centreline,
    which the cant rotates about), positive toward the field side; ``height`` [m] is
    up, in the plane of the track. To differentiate with respect to the inclination,
    build the rail once and replace the field:
    ``eqx.tree_at(lambda r: r.inclination, rail, theta)`` (the static domain stays).
    """

    inclination: Float[Array, ""]
    y_min: float = eqx.field(static=True)
    y_max: float = eqx.field(static=True)
    name: str = eqx.field(static=True, default="UIC60")

    def __init__(self, inclination: Float[ArrayLike, ""],
                 domain: tuple[float, float] | None = None, name: str | None = None):
        """Arguments:
            inclination: rail inclination [rad], scalar.
            domain: ``(y_min, y_max)`` [m]; default from the concrete inclination.
            name: label; default ``"UIC60 <angle> rad"``.
        """
        require_float64("UIC60")
        incl = jnp.asarray(inclination, dtype=jnp.float64)
        if incl.shape != ():
            raise ValueError(f"UIC60: inclination must be a scalar, got shape {incl.shape}")
        self.inclination = incl
        if domain is None:
            try:
                theta = float(np.asarray(incl))
            except Exception as err:  # a tracer: the domain must be static
                raise ValueError(
                    "UIC60: domain must be given when inclination is traced "
                    "(or use eqx.tree_at on a built rail)") from err
            if not abs(theta) <= MAX_INCLINATION:
                raise ValueError(
                    f"UIC60: inclination {theta} rad is outside +-{MAX_INCLINATION:.4f} rad (1:10)")
            domain = _domain(theta)
            if name is None:
                name = f"UIC60 {theta:.6g} rad"
        y_min, y_max = (float(v) for v in domain)
        if not y_min < 0.0 < y_max:
            raise ValueError(f"UIC60: domain must satisfy y_min < 0 < y_max, got {domain}")
        self.y_min, self.y_max = y_min, y_max
        self.name = "UIC60" if name is None else str(name)

    @property
    def domain(self) -> tuple[float, float]:
        return (self.y_min, self.y_max)

    def _table(self):
        return _canted_table(jnp, self.inclination)

    def joints(self) -> tuple[Float[Array, "6"], Float[Array, "6"]]:
        """Canted (y, z) [m] of the six tangency points, gauge side first:
        R13/flank, R80/R13, R300/R80 (gauge), then R300/R80, R80/R13, R13/flank (field)."""
        table = self._table()
        return _breaks(table), table[1:, 7]

    def piece_height_slope(self, y: Float[ArrayLike, ""], piece: int) -> tuple[Array, Array]:
        """Height [m] and slope [-] at ``y`` [m] of one analytic piece, continued beyond
        its joints (pieces 0..6 from the gauge flank to the field flank)."""
        y = jnp.asarray(y, dtype=jnp.float64)
        return _piece_derivatives(jnp, self._table()[piece], y)[:2]

    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        """Height [m], slope [-] and second derivative [1/m] at ``y`` [m], in closed
        form (zero second derivative on the end tangents outside the domain)."""
        y = jnp.asarray(y, dtype=jnp.float64)
        # Continue along the end tangent outside the domain; `where` rather than clip
        # keeps the derivatives exact at the ends themselves.
        y_in = jnp.where(y > self.y_max, self.y_max, jnp.where(y < self.y_min, self.y_min, y))
        table = self._table()
        index = jnp.sum((y_in > _breaks(table)).astype(jnp.int32))
        h, s, c = _piece_derivatives(jnp, table[index], y_in)
        return computed_once(h + s * (y - y_in), s, jnp.where(y == y_in, c, 0.0))

    def normal_foot(self, eta: Float[ArrayLike, ""], zeta: Float[ArrayLike, ""]) -> Array:
        """The coordinate ``u`` [m] whose normal passes through ``(eta, zeta)`` [m], in
        closed form, clipped to the domain (:meth:`Profile.normal_foot`).

        The head is a chain of arcs and two flank lines, tangent at their joints, so the
        normal lines at the joints divide the plane near the head into one sector per
        piece: a point lies past joint ``j`` (toward the field side) when its offset from
        the joint has a positive component along the head's tangent there. In its piece
        the foot is the arc's point on the ray from the centre through the point, or the
        point's projection on the flank line. Exact for points closer to the head than
        its smallest radius (13 mm) on its concave side. A point past the normal line at
        a domain end gets that end, where the search's Newton steps end too."""
        return self._foot_and_depth(eta, zeta)[0]

    def normal_foot_depth(self, eta: Float[ArrayLike, ""], zeta: Float[ArrayLike, ""]) -> Array:
        """Signed depth [m] of ``(eta, zeta)`` [m] below the head along the normal at its
        :meth:`normal_foot` (:meth:`Profile.normal_foot_depth`), in closed form: the
        radius less the distance from the centre in an arc's sector, the distance below
        the line in a flank's, the distance below the end's tangent line past a domain
        end. Its derivatives are exact (no foot derivative enters the distance to a
        circle or a line)."""
        return self._foot_and_depth(eta, zeta)[1]

    def _foot_and_depth(self, eta, zeta):
        """:meth:`normal_foot` and :meth:`normal_foot_depth` [m], from one sector."""
        table = self._table()
        joint_y, joint_z = table[1:, 3], table[1:, 7]
        # the centre of an arc at each joint (the joint's normal line passes through it)
        centre_y, centre_z = table[_JOINT_ARC, 0], table[_JOINT_ARC, 4]
        along = (eta - joint_y) * (joint_z - centre_z) - (zeta - joint_z) * (joint_y - centre_y)
        row = table[jnp.sum((along > 0.0).astype(jnp.int32))]
        yc, y0, dy, zc, z0, dz, radius, is_line = (row[i] for i in (0, 1, 2, 4, 5, 6, 8, 9))
        is_line = is_line > 0.5
        ray_sq = (eta - yc) ** 2 + (zeta - zc) ** 2
        centred = ray_sq > 0.0  # double where: no NaN in a derivative at the centre
        ray = jnp.sqrt(jnp.where(centred, ray_sq, 1.0))
        on_arc = yc + radius * (eta - yc) / ray
        on_line = y0 + dy * ((eta - y0) * dy + (zeta - z0) * dz) / (dy * dy + dz * dz)
        foot = jnp.where(is_line, on_line, on_arc)
        # a line's depth as signed_depth takes it (slope 0 on a vertical flank, which
        # lies outside the domain)
        steep = jnp.abs(dy) <= 1e-12
        m = jnp.where(steep, 0.0, dz / jnp.where(steep, 1.0, dy))
        below_line = below_tangent(eta, zeta, y0, z0, m)
        depth = jnp.where(is_line, below_line, jnp.where(centred, radius - ray, radius))
        # past the normal line at a domain end (also deep beside the head, where the
        # joints' normal lines cross), or a foot beyond an end: that end, the nearer one
        # where past both, and the depth below its tangent line
        past, distance, below_end = [], [], []
        for end in self.domain:
            height, slope, _ = self.height_derivatives(end)
            past.append((eta - end) + (zeta - height) * slope)
            distance.append((eta - end) ** 2 + (zeta - height) ** 2)
            below_end.append(below_tangent(eta, zeta, end, height, slope))
        past_low, past_high = past[0] < 0.0, past[1] > 0.0
        low = past_low & ~(past_high & (distance[1] < distance[0]))
        high = ~low & (past_high | (foot >= self.y_max))
        low = low | ~high & (foot <= self.y_min)
        foot = jnp.where(low, self.y_min, jnp.where(high, self.y_max, foot))
        return foot, jnp.where(low, below_end[0], jnp.where(high, below_end[1], depth))


_NAMED_INCLINATIONS = {"1:40": 1.0 / 40.0, "1:20": 1.0 / 20.0, "none": 0.0, "0": 0.0}


def uic60(inclination: float | str = 1.0 / 40.0) -> UIC60:
    """UIC60 rail with the given inclination.

    Arguments:
        inclination: the slope ``tan(theta)`` as a float (``1/40``, ``0.05``, ``0``), or
            one of the strings ``"1:40"``, ``"1:20"``, ``"none"``, ``"0"``.
    """
    if isinstance(inclination, str):
        key = inclination.strip().lower()
        if key not in _NAMED_INCLINATIONS:
            raise ValueError(
                f"uic60: unknown inclination {inclination!r}; use a float slope or one of "
                f"{sorted(_NAMED_INCLINATIONS)}")
        slope = _NAMED_INCLINATIONS[key]
    elif isinstance(inclination, (int, float)) and not isinstance(inclination, bool):
        slope = float(inclination)
    else:
        raise ValueError(f"uic60: inclination must be a float slope or a string, got {inclination!r}")
    if slope == 0.0:
        label = "UIC60 no inclination"
    elif abs(round(1.0 / slope) - 1.0 / slope) < 1e-9:
        label = f"UIC60 1:{round(1.0 / slope)}"
    else:
        label = f"UIC60 1:{1.0 / slope:.4g}"
    return UIC60(math.atan(slope), name=label)
