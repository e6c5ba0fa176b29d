"""Polach's creep-force method (1999) with spin, and its 2005 extension.

Sign convention (Kalker, docs/design.md §3): creepages are the slip of the wheel over
the rail divided by the rolling speed (see :mod:`jaxrail.contact.creepage`); the
returned forces act **on the wheel**, in the contact frame's tangent plane
(longitudinal ``t``, lateral ``l``), and oppose the creepage:
``Fx = -G a b c11 xi`` and ``Fy = -G a b c22 eta - G (ab)^(3/2) c23 phi`` for small
creepages. The force on the rail is the opposite.

Formula chain (Polach 1999, VSD 33 suppl. 728-739; reference/contact-mechanics.md 4.2),
with Q the normal force and ``s = |(sx, sy)|``:

1. spin-modified lateral creepage ``s_yC = s_y + psi a`` if ``|s_y + psi a| > |s_y|``,
   else ``s_y``. Only ``|s_yC| = max(|s_y + psi a|, |s_y|)`` enters below, so the
   forces are continuous (with a kink where the two are equal, s_y = -psi a / 2).
2. ``s_C = sqrt(sx^2 + s_yC^2)``, ``C = sqrt((c11 sx/s)^2 + (c22 sy/s)^2)``.
3. ``eps = pi G a b C s_C / (4 Q mu)``,
   ``F = (2 Q mu / pi) [k_A eps / (1 + (k_A eps)^2) + arctan(k_S eps)]``
   (1999: k_A = k_S = 1); ``Fx = -F sx / s_C``, ``Fy,creep = -F sy / s_C``.
4. spin: ``k_s = 1 + 6.3 (1 - exp(-a/b))``,
   ``eps_psi = (8/3) G b sqrt(ab) c23 |s_yC| / (Q mu k_s)`` and Polach's
   ``K_M = |eps_psi| (d^3/3 - d^2/2 + 1/6) - sqrt((1 - d^2)^3) / 3``,
   ``d = (eps_psi^2 - 1)/(eps_psi^2 + 1)``, which simplifies exactly to
   ``K_M = -(2/3) eps_psi / (1 + eps_psi^2)^2``. Then
   ``F_yS = -(9/16) a Q mu |K_M| k_s psi / s_C
   = -G (ab)^(3/2) c23 psi (|s_yC| / s_C) / (1 + eps_psi^2)^2``.

The last form, and ``F / s_C = (G a b C / 2) g(eps)`` with
``g = k_A / (1 + (k_A eps)^2) + arctan(k_S eps) / eps``, have finite limits at
``s_C = 0``, which is how they are evaluated here: no NaN in values or gradients at
zero creepage, zero spin or zero load. At ``s = 0`` the direction-dependent C is taken
as c11 for Fx and c22 for Fy, so the gradient there is Kalker's linear one.

Polach 2005 (Wear 258, 992-1000), via :class:`PolachParameters`: reduction factors
k_A (area of adhesion) and k_S (area of slip), and friction falling with the slip
velocity ``w = s_C V``: ``mu = mu0 [(1 - A) exp(-B w) + A]``. The spin term uses the
current mu and is not reduced by k_A, k_S (reference 4.3).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._constants import STEEL_POISSON, STEEL_SHEAR_MODULUS
from .._float64 import f64, require_float64
from ._checks import check_range
from .kalker import kalker_coefficients

_F64 = jnp.float64


class PolachParameters(eqx.Module):
    """Parameters of the Polach 2005 extension. The defaults give Polach 1999.

    Fields (traced scalars or arrays that broadcast with the contacts):

    - `k_A`: reduction of the initial slope of F(eps) (area of adhesion) [-].
    - `k_S`: reduction of the slope in the area of slip [-]; Polach: k_S <= k_A <= 1.
    - `A_ratio`: ``A = mu_inf / mu0``, ratio of friction at infinite slip velocity to
      the maximum friction ``mu0`` (the ``mu`` argument of :func:`polach`) [-].
    - `B`: exponential rate of friction decrease with slip velocity [s/m].

    The friction law is ``mu = mu0 [(1 - A) exp(-B w) + A]`` with ``w`` the slip velocity
    magnitude [m/s]; ``A_ratio = 1`` or ``B = 0`` keeps ``mu = mu0``.
    """

    k_A: Float[Array, "*batch"] = eqx.field(converter=f64, default=1.0)
    k_S: Float[Array, "*batch"] = eqx.field(converter=f64, default=1.0)
    A_ratio: Float[Array, "*batch"] = eqx.field(converter=f64, default=1.0)
    B: Float[Array, "*batch"] = eqx.field(converter=f64, default=0.0)

    @classmethod
    def dry(cls) -> "PolachParameters":
        """Polach 2005 'dry' set: k_A = 1, k_S = 0.4, A = 0.4, B = 0.6 s/m (use with
        mu0 = 0.55). Recalled values, marked [R] in the reference: check before use."""
        return cls(k_A=1.0, k_S=0.4, A_ratio=0.4, B=0.6)

    @classmethod
    def wet(cls) -> "PolachParameters":
        """Polach 2005 'wet' set: k_A = 0.3, k_S = 0.75, A = 0.4, B = 0.2 s/m (use with
        mu0 = 0.30). Recalled values, marked [R] in the reference: check before use."""
        return cls(k_A=0.3, k_S=0.75, A_ratio=0.4, B=0.2)


def _atan_over(x):
    """arctan(x)/x for x >= 0, with its Taylor series near 0 (finite value and gradient)."""
    small = x < 1e-4
    safe = jnp.where(small, 1.0, x)
    x2 = x * x
    return jnp.where(small, 1.0 - x2 / 3.0 + x2 * x2 / 5.0, jnp.arctan(safe) / safe)


def _safe_sqrt(x):
    """sqrt(x) for x >= 0 with gradient 0 (not inf/NaN) at x = 0."""
    positive = x > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def polach(
    normal_force: Float[ArrayLike, "*batch"],
    mu: Float[ArrayLike, "*batch"],
    a: Float[ArrayLike, "*batch"],
    b: Float[ArrayLike, "*batch"],
    creepage_x: Float[ArrayLike, "*batch"],
    creepage_y: Float[ArrayLike, "*batch"],
    spin: Float[ArrayLike, "*batch"],
    G: Float[ArrayLike, "*batch"] = STEEL_SHEAR_MODULUS,
    nu: Float[ArrayLike, "*batch"] = STEEL_POISSON,
    *,
    parameters: PolachParameters | None = None,
    rolling_speed: Float[ArrayLike, "*batch"] | None = None,
    coefficients: tuple | None = None,
    kalker_method: str = "table",
) -> tuple[Float[Array, "*batch"], Float[Array, "*batch"]]:
    """Tangential creep forces ``(fx, fy)`` [N] on the wheel, Polach's method with spin.

    **Arguments** (scalars or broadcastable arrays; one entry per contact):

    - `normal_force`: normal load Q >= 0 [N]. Q = 0 gives zero force.
    - `mu`: friction coefficient [-] (mu0, the maximum, with the 2005 extension).
    - `a`, `b`: contact-ellipse semi-axes [m] along the rolling direction and lateral,
      >= 0 (e.g. from Hertz).
    - `creepage_x`, `creepage_y`: longitudinal and lateral creepages xi, eta [-].
    - `spin`: spin creepage phi [1/m].
    - `G`: shear modulus [Pa]; `nu`: Poisson's ratio [-] (for Kalker's coefficients).
    - `parameters`: :class:`PolachParameters` for the 2005 extension; ``None`` is 1999.
    - `rolling_speed`: V [m/s], required with `parameters` (slip velocity w = s_C V for
      the falling friction; pass 0.0 if B = 0).
    - `coefficients`: optional ``(c11, c22, c23)`` to use instead of
      :func:`~jaxrail.contact.kalker.kalker_coefficients` at ``a/b``.
    - `kalker_method`: ``method`` of
      :func:`~jaxrail.contact.kalker.kalker_coefficients` (``"table"``, the default,
      or ``"direct"``).

    **Returns** ``(fx, fy)``: longitudinal and lateral force on the wheel [N] in the
    contact frame (t, l), Kalker's sign convention (opposing the creepage). The spin
    moment is neglected (m_z = 0, as in the paper's eq. 18).
    """
    if parameters is not None and not isinstance(parameters, PolachParameters):
        raise TypeError(
            f"parameters must be a PolachParameters or None, got {type(parameters).__name__}"
        )
    if parameters is not None and rolling_speed is None:
        raise ValueError(
            "rolling_speed is required with parameters (Polach 2005): the friction falls "
            "with the slip velocity s_C * V; pass rolling_speed=0.0 if B = 0"
        )
    if coefficients is not None and len(coefficients) != 3:
        raise ValueError("coefficients must be a tuple (c11, c22, c23)")
    require_float64("polach")
    check_range("polach: friction mu", mu, 0.0, np.inf, low_open=False)
    check_range("polach: shear modulus G [Pa]", G, 0.0, np.inf)
    check_range("polach: Poisson's ratio nu", nu, -1.0, 0.5)

    q, mu0, a, b = f64(normal_force), f64(mu), f64(a), f64(b)
    sx, sy, psi = f64(creepage_x), f64(creepage_y), f64(spin)
    G, nu = f64(G), f64(nu)

    # Kalker coefficients at a/b; a/b = 1 stands in where the ellipse is empty.
    has_area = (a > 0.0) & (b > 0.0)
    ratio = jnp.where(has_area, a / jnp.where(has_area, b, 1.0), 1.0)
    if coefficients is None:
        c11, c22, c23 = kalker_coefficients(ratio, nu, method=kalker_method)
    else:
        c11, c22, c23 = (f64(c) for c in coefficients)
    ab = a * b
    sqrt_ab = _safe_sqrt(ab)

    # 1.-2. Spin-modified creepage; only |s_yC| matters (Polach's rule picks the larger).
    syc_abs = jnp.maximum(jnp.abs(sy + psi * a), jnp.abs(sy))
    sc2 = sx * sx + syc_abs * syc_abs
    sc = _safe_sqrt(sc2)
    s2 = sx * sx + sy * sy
    moving = s2 > 0.0
    # C^2 as a weighted mean of c11^2 and c22^2; at s = 0 its direction is undefined and
    # c11 (for Fx) and c22 (for Fy) give the axis-wise limits.
    c2_mix = (c11 * c11 * sx * sx + c22 * c22 * sy * sy) / jnp.where(moving, s2, 1.0)
    c_for_x = jnp.sqrt(jnp.where(moving, c2_mix, c11 * c11))
    c_for_y = jnp.sqrt(jnp.where(moving, c2_mix, c22 * c22))

    # Friction (2005: falling with the slip velocity).
    if parameters is None:
        k_a = k_s = jnp.asarray(1.0, dtype=_F64)
        mu_now = mu0
    else:
        k_a, k_s = parameters.k_A, parameters.k_S
        w = sc * f64(rolling_speed)
        a_r = parameters.A_ratio
        mu_now = mu0 * ((1.0 - a_r) * jnp.exp(-parameters.B * w) + a_r)
    qmu = q * mu_now
    loaded = qmu > 0.0
    inv_qmu = jnp.where(loaded, 1.0 / jnp.where(loaded, qmu, 1.0), 0.0)

    # 3. F / s_C = (G a b C / 2) g(eps), finite at s_C = 0.
    def force_over_sc(c):
        eps = jnp.pi * G * ab * c * sc * inv_qmu / 4.0
        ka_eps = k_a * eps
        g = k_a / (1.0 + ka_eps * ka_eps) + k_s * _atan_over(k_s * eps)
        return 0.5 * G * ab * c * g

    fx = -force_over_sc(c_for_x) * sx
    fy_creep = -force_over_sc(c_for_y) * sy

    # 4. Spin: F_yS = -G (ab)^1.5 c23 psi (|s_yC|/s_C) / (1 + eps_psi^2)^2.
    ks_spin = 1.0 + 6.3 * (1.0 - jnp.exp(-ratio))
    eps_psi = (8.0 / 3.0) * G * b * sqrt_ab * c23 * syc_abs * inv_qmu / ks_spin
    spinning = sc2 > 0.0
    # s_C = 0 only when sx = sy = psi a = 0; the directional limit along psi is 1.
    direction = jnp.where(spinning, syc_abs / jnp.where(spinning, sc, 1.0), 1.0)
    fy_spin = -G * ab * sqrt_ab * c23 * psi * direction / (1.0 + eps_psi * eps_psi) ** 2

    fy = fy_creep + fy_spin
    zero = jnp.zeros_like(fx)
    return jnp.where(loaded, fx, zero), jnp.where(loaded, fy, zero)
