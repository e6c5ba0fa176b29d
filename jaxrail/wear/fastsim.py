"""A contact patch cut into strips and elements, Kalker's FASTSIM: the normal pressure,
the tangential traction, the stick and slip areas and the local sliding velocity that
the wear laws need.

Frame: the contact frame of :mod:`jaxrail.contact.creepage`, ``x`` along the rolling
direction ``t`` (the leading edge at ``x = +a_j``), ``y`` along ``l`` (to the left of
``t``), both in the contact plane [m]. The rigid slip at ``(x, y)`` is
``w = (xi - phi y, eta + phi x)`` [-] (times the rolling speed V it is a velocity).

The ellipse ``x^2/a^2 + y^2/b^2 <= 1`` is cut into ``strips`` strips of equal width
across ``y``; strip j of half-length ``a_j = a sqrt(1 - y_j^2/b^2)`` is cut into
``elements`` equal elements along ``x``. Each element carries (Kalker 1982, Vehicle
System Dynamics 11, 1-13; the one-flexibility form used by the wear studies, e.g.
Enblom and Berg 2005, Wear 258, 1055-1063):

- the traction bound ``mu p_F``, ``p_F = 2N/(pi a b) (1 - x^2/a^2 - y^2/b^2)`` the
  simplified theory's parabolic pressure;
- the flexibility ``L = (L1 |xi| + L2 |eta| + L3 c |phi|) / sqrt(xi^2 + eta^2 + c^2
  phi^2)``, ``L1 = 8a/(3 G c11)``, ``L2 = 8a/(3 G c22)``, ``L3 = pi a^2/(4 G c c23)``,
  ``c = sqrt(a b)``: pure creepage of one kind reproduces Kalker's linear theory;
- the traction, marched from the leading edge in half elements (to each element's
  centre, where it is reported, and on to its trailing edge): ``p(x - h) = p(x) - w h /
  L`` while it sticks, cut back to the bound there along its own direction where it
  would exceed it (slip);
- the local slip at the centre ``s = w - L (p(x_lead) - p(x_c)) / h``, ``h = dx/2``
  [-]: zero in the stick area, antiparallel to the traction in the slip area, ``V |s|``
  the sliding velocity [m/s] there;
- the Hertz pressure ``p_H = 3N/(2 pi a b) sqrt(1 - x^2/a^2 - y^2/b^2)`` [Pa] that the
  wear laws use (the KTH map is drawn against it).

Both pressures are scaled so that their values at the element centres sum to ``N``
over the elements exactly: the discretisation then conserves the normal force, which the
wear volumes inherit. Traction on the wheel, opposing its slip (Kalker's convention, as
:func:`jaxrail.contact.polach.polach`).

Differentiable: the norms and the flexibility's direction weights are guarded (double
``where``) at zero creepage and zero traction; an empty patch (``N <= 0`` or a zero
semi-axis) gives zeros. At exactly zero creepage ``L`` has no direction to weigh and is
``L1``: the derivative there is taken along xi's flexibility in every direction.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._constants import STEEL_POISSON, STEEL_SHEAR_MODULUS
from ..contact.kalker import kalker_coefficients

STRIPS = 21  # across the patch
ELEMENTS = 24  # along each strip
_TINY = 1e-300


class PatchGrid(eqx.Module):
    """One patch in elements; arrays (..., strips, elements) unless stated.

    Fields: x, y [m] element centres (contact frame); area [m^2]; pressure [Pa] (Hertz,
    scaled to sum to N); traction_x, traction_y [Pa] on the wheel (at the centre); slip_x, slip_y [-] (times V: the sliding velocity); sliding [-] =
    |slip|; stick (bool): the element sticks; strip_y (..., strips) [m] the strip
    centres.
    """

    x: Float[Array, "... strips elements"]
    y: Float[Array, "... strips elements"]
    area: Float[Array, "... strips elements"]
    pressure: Float[Array, "... strips elements"]
    traction_x: Float[Array, "... strips elements"]
    traction_y: Float[Array, "... strips elements"]
    slip_x: Float[Array, "... strips elements"]
    slip_y: Float[Array, "... strips elements"]
    sliding: Float[Array, "... strips elements"]
    stick: Array
    strip_y: Float[Array, "... strips"]

    def forces(self):
        """``(fx, fy)`` [N]: the patch's creep force on the wheel, contact frame."""
        return (jnp.sum(self.traction_x * self.area, axis=(-2, -1)),
                jnp.sum(self.traction_y * self.area, axis=(-2, -1)))


def _safe_norm(x, y):
    """sqrt(x^2 + y^2) with a finite gradient at zero (0 there)."""
    r2 = x * x + y * y
    positive = r2 > _TINY
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, r2, 1.0)), 0.0)


def _flexibility(a, b, xi, eta, phi, G, nu):
    """Kalker's weighted flexibility L [m/Pa] of FASTSIM (module docstring); at zero
    creepage (no traction anywhere) L1."""
    c11, c22, c23 = kalker_coefficients(a / b, nu)
    c = jnp.sqrt(a * b)
    l1 = 8.0 * a / (3.0 * G * c11)
    l2 = 8.0 * a / (3.0 * G * c22)
    l3 = jnp.pi * a * a / (4.0 * G * c * c23)
    cphi = c * phi
    total = _safe_norm(_safe_norm(xi, eta), cphi)
    moving = total > 1e-30
    weighted = (l1 * jnp.abs(xi) + l2 * jnp.abs(eta) + l3 * jnp.abs(cphi)) / jnp.where(
        moving, total, 1.0)
    return jnp.where(moving, weighted, l1)


def _scale(shape_value, area, total):
    """The factor that makes ``shape_value``'s sum times ``area`` equal ``total`` (0 for
    a shape that sums to 0)."""
    integral = jnp.sum(shape_value * area)
    loaded = integral > 0.0
    return jnp.where(loaded, total / jnp.where(loaded, integral, 1.0), 0.0)


def fastsim_patch(
    normal_force: Float[ArrayLike, ""],
    a: Float[ArrayLike, ""],
    b: Float[ArrayLike, ""],
    creepage_x: Float[ArrayLike, ""],
    creepage_y: Float[ArrayLike, ""],
    spin: Float[ArrayLike, ""],
    friction: Float[ArrayLike, ""],
    G: Float[ArrayLike, ""] = STEEL_SHEAR_MODULUS,
    nu: Float[ArrayLike, ""] = STEEL_POISSON,
    strips: int = STRIPS,
    elements: int = ELEMENTS,
) -> PatchGrid:
    """One patch by FASTSIM (module docstring): scalars in, a :class:`PatchGrid` of
    shape (strips, elements) out. ``normal_force`` N [N]; ``a``, ``b`` the Hertz
    semi-axes [m] along and across the rolling direction; creepages xi, eta [-], spin
    phi [1/m]; ``friction`` mu [-]; G [Pa], nu [-]. vmap it over patches."""
    f = lambda v: jnp.asarray(v, dtype=jnp.float64)  # noqa: E731
    n, a, b, xi, eta, phi, mu, G, nu = map(f, (normal_force, a, b, creepage_x,
                                               creepage_y, spin, friction, G, nu))
    present = (n > 0.0) & (a > 0.0) & (b > 0.0)
    a_s, b_s = jnp.where(present, a, 1.0), jnp.where(present, b, 1.0)
    n_s = jnp.where(present, n, 0.0)

    dy = 2.0 * b_s / strips
    strip_y = -b_s + (jnp.arange(strips) + 0.5) * dy  # (S,)
    half = a_s * jnp.sqrt(1.0 - (strip_y / b_s) ** 2)  # (S,) strip half-lengths
    dx = 2.0 * half / elements
    x = half[:, None] - (jnp.arange(elements)[None, :] + 0.5) * dx[:, None]  # (S, E)
    y = jnp.broadcast_to(strip_y[:, None], x.shape)
    area = jnp.broadcast_to(dx[:, None] * dy, x.shape)
    parabola = lambda x: jnp.maximum(1.0 - (x / a_s) ** 2 - (y / b_s) ** 2, 0.0)  # noqa: E731
    inside = parabola(x)
    # One factor scales the parabolic pressure at the centres and at the trailing edges.
    scale = _scale(inside, area, n_s)
    bound_centre = mu * scale * inside
    bound_edge = mu * scale * parabola(x - 0.5 * dx[:, None])
    # sqrt's slope is infinite at 0: element centres never reach the rim, the guard
    # only keeps an empty patch finite.
    hertz_shape = jnp.sqrt(jnp.where(inside > 0.0, inside, 1.0)) * (inside > 0.0)
    hertz = hertz_shape * _scale(hertz_shape, area, n_s)

    flexibility = _flexibility(a_s, b_s, xi, eta, phi, G, nu)
    wx = xi - phi * y  # (S, E) rigid slip at the element centres
    wy = eta + phi * x

    def saturate(tx, ty, bound):
        size = _safe_norm(tx, ty)
        slips = size > bound
        factor = jnp.where(slips, bound / jnp.where(slips, size, 1.0), 1.0)
        return tx * factor, ty * factor, slips

    def step(edge, column):
        """From the element's leading edge half a step to its centre (the traction,
        slip and stick reported) and on to its trailing edge (the next one's start)."""
        px0, py0 = edge
        wx_i, wy_i, g_centre, g_edge, dx_i = column
        half_step = 0.5 * dx_i / flexibility
        px, py, slips = saturate(px0 - wx_i * half_step, py0 - wy_i * half_step, g_centre)
        sx = wx_i - (px0 - px) / half_step
        sy = wy_i - (py0 - py) / half_step
        qx, qy, _ = saturate(px - wx_i * half_step, py - wy_i * half_step, g_edge)
        return (qx, qy), (px, py, jnp.where(slips, sx, 0.0), jnp.where(slips, sy, 0.0),
                          ~slips)

    zero = jnp.zeros(strips, dtype=jnp.float64)
    columns = (wx.T, wy.T, bound_centre.T, bound_edge.T,
               jnp.broadcast_to(dx, (elements, strips)))
    _, (px, py, sx, sy, stick) = jax.lax.scan(step, (zero, zero), columns)
    px, py, sx, sy, stick = (v.T for v in (px, py, sx, sy, stick))
    keep = lambda v: jnp.where(present, v, 0.0)  # noqa: E731
    return PatchGrid(x=keep(x), y=keep(y), area=keep(area), pressure=keep(hertz),
                     traction_x=keep(px), traction_y=keep(py), slip_x=keep(sx),
                     slip_y=keep(sy), sliding=keep(_safe_norm(sx, sy)),
                     stick=jnp.where(present, stick, True), strip_y=keep(strip_y))
