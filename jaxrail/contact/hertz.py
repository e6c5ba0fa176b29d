"""Hertz contact of two elastic bodies: semi-axes, approach, stiffness, peak pressure.

Geometry: the undeformed gap near the contact point is h(x, y) = A x^2 + B y^2 [m], x
the rolling direction, y lateral (contact frame), with the curvature sums [1/m]

    A = 1/2 (1/R1x + 1/R2x),    B = 1/2 (1/R1y + 1/R2y),

radii positive for convex surfaces, negative for concave ones. Both A and B must be
positive (non-conformal contact). Material: identical elastic bodies with shear
modulus G [Pa] and Poisson ratio nu [-], so E* = G / (1 - nu) = E / (2 (1 - nu^2)).

Formulas (reference/contact-mechanics.md section 3.1; Johnson 1985 section 4.2): with
c0 = [3N / (4 E* (A + B))]^(1/3), a = m c0 and b = n c0 for the major (m >= 1) and
minor (n <= 1) coefficients, the **larger semi-axis along the smaller curvature
coefficient**. The eccentricity e^2 = 1 - (b_min/a_maj)^2 solves

    C_large / C_small = [E/(1 - e^2) - K] / (K - E)     (K, E: complete integrals).

Numerics. The equation is solved for w = log(a/b) (signed: w > 0 when B > A, i.e. when
the patch is longer along x), a smooth odd function of t = log(B/A): near the sphere
t = 1.5 w + O(w^3), far out t ~ 2|w|. With u = |w| and s = log(1 - e^2) = -2u the
curvature ratio is (1/2 - Q)/((1 - e^2)(1/2 + Q)) (Q: AGM tail, see
:mod:`jaxrail.contact.elliptic`), free of cancellation at e = 0. A safeguarded Newton
iteration with a fixed number of steps solves it (dt/du lies in [1.5, 2], so the
root lies in u in [|t|/2, 2|t|/3]), and the derivative of w comes from the
implicit function theorem (``jax.custom_jvp``), so gradients are exact and smooth,
including at A = B (sphere) where a, b, K_H are even functions of w. Tested for
curvature ratios up to 1e12.

Table (the default, ``method="table"``). The Newton solve runs 6 steps of 12 AGM steps
for each patch at each evaluation; the functions of t it feeds are tabulated instead:
w(t), g(t) = log sqrt(m n) and h(t) = log r, as piecewise cubic Hermite interpolants
on a uniform grid in t (step 0.02, |t| <= 32, i.e. B/A in [1.3e-14, 7.9e13]) whose
node values and node derivatives come from the exact path (jax.jvp through the
implicit derivative). The interpolant is C1 (continuous gradients), exactly odd/even in
t, exact at the sphere (a node), and within 1e-10 relative of the exact path in every
returned field (tests/contact/test_hertz_table.py). Beyond |t| = 32 the e -> 1
asymptote K = log 4 + u, E = 1 is used (there exact to rounding): t = 2u - log(K - 1),
m^3 = 2 (K - 1)(1 + B/A)/pi; its seven logarithms are computed only where some patch
of a batch needs them (:func:`jaxrail.compilation.seldom.seldom`). The table is built
from the exact path on first use (``functools.cache``), not at import.
``method="exact"`` evaluates the Newton/elliptic path, the reference.

Zero load: a = b = approach = p0 = 0 with zero (finite) gradient at N = 0, although
the true derivative d a / d N ~ N^(-2/3) is infinite there. Negative N counts as 0.
"""

import functools
import inspect
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from jaxrail._constants import STEEL_POISSON, STEEL_SHEAR_MODULUS
from jaxrail._float64 import require_float64
from jaxrail.compilation import computed_once
from jaxrail.compilation.seldom import seldom
from jaxrail.contact._checks import check_range
from jaxrail.contact.elliptic import agm_kq

_NEWTON_STEPS = 6  # from the bracket midpoint: converged to 1e-15 after 3 steps (t <= 40)
_STATIC_KWARGS = ("min_curvature_ratio", "method")
METHODS = ("table", "exact")
"""Evaluation methods of the Hertz coefficients: ``"table"`` (default) or ``"exact"``."""


def _compiled(fn):
    """``eqx.filter_jit`` with every argument but ``min_curvature_ratio`` and ``method``
    traced, and ``A``, ``B``, ``G``, ``nu`` checked when they are concrete.

    filter_jit alone treats Python floats as static (one compilation per value); the
    conversion to float64 arrays happens outside, so jit traces them. The check runs
    here, on the host, so that the compiled programs hold no error callback (programs
    with callbacks cannot go into JAX's persistent compilation cache); traced
    non-positive sums give NaN.
    """
    jitted = eqx.filter_jit(fn)
    signature = inspect.signature(fn)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        require_float64(fn.__name__)
        args = [jnp.asarray(x, dtype=jnp.float64) for x in args]
        kwargs = {
            k: v if k in _STATIC_KWARGS else jnp.asarray(v, dtype=jnp.float64)
            for k, v in kwargs.items()
        }
        _check_inputs(signature.bind_partial(*args, **kwargs).arguments)
        return jitted(*args, **kwargs)

    return wrapper


class HertzContact(eqx.Module):
    """A Hertz contact ellipse (all fields traced float64 arrays of the input shape).

    Fields:
        a: semi-axis along x, the rolling direction [m].
        b: semi-axis along y, lateral in the contact plane [m].
        approach: mutual approach (penetration) delta of the two bodies [m].
        stiffness: Hertz stiffness K_H [N/m^1.5], with N = K_H * delta^1.5.
        p0: peak pressure 3N / (2 pi a b) [Pa].
    """

    a: Float[Array, "..."]
    b: Float[Array, "..."]
    approach: Float[Array, "..."]
    stiffness: Float[Array, "..."]
    p0: Float[Array, "..."]


class HertzCoefficients(eqx.Module):
    """Classical dimensionless Hertz coefficients (functions of B/A only).

    Fields:
        m: major coefficient, a_major / c0 (>= 1).
        n: minor coefficient, b_minor / c0 (<= 1).
        r: approach coefficient 2K(e)/(pi m); delta = r c0^2 (A + B).
        a_over_c0: a / c0 (x direction); equals m if B >= A, else n.
        b_over_c0: b / c0 (y direction).
        stiffness_factor: K_H sqrt(A + B) / E* = (4/3) r^(-3/2).
    """

    m: Float[Array, "..."]
    n: Float[Array, "..."]
    r: Float[Array, "..."]
    a_over_c0: Float[Array, "..."]
    b_over_c0: Float[Array, "..."]
    stiffness_factor: Float[Array, "..."]


def _log_ratio(u):
    """t(u) = log(C_large / C_small) for u = log(a_major / b_minor) >= 0."""
    s = -2.0 * u  # log(1 - e^2)
    _, q = agm_kq(-jnp.expm1(s), jnp.exp(s))
    return jnp.log1p(-2.0 * q / (0.5 + q)) - s


def _newton_solve(t_abs):
    """u >= 0 with _log_ratio(u) = t_abs; fixed-step Newton safeguarded by bisection."""
    # The root lies in [t/2, 2t/3] (dt/du in [1.5, 2]); widened so that rounding
    # never rejects a Newton step near the sphere, where u -> 2t/3.
    lo = 0.49 * t_abs
    hi = 0.68 * t_abs

    def step(_, state):
        u, lo, hi = state
        g, dg = jax.jvp(_log_ratio, (u,), (jnp.ones_like(u),))
        g = g - t_abs
        # g is increasing in u: shrink the bracket, then take Newton's step unless it
        # leaves the bracket (not observed; it keeps the iteration safe).
        lo = jnp.where(g < 0.0, u, lo)
        hi = jnp.where(g > 0.0, u, hi)
        u_newton = u - g / dg
        inside = (u_newton >= lo) & (u_newton <= hi)
        return jnp.where(inside, u_newton, 0.5 * (lo + hi)), lo, hi

    u, _, _ = jax.lax.fori_loop(0, _NEWTON_STEPS, step, (0.5 * (lo + hi), lo, hi))
    return u


@jax.custom_jvp
def _axis_log_ratio(t):
    """w = log(a/b) as a function of t = log(B/A) (odd, smooth, dw/dt = 2/3 at 0)."""
    return jnp.sign(t) * _newton_solve(jnp.abs(t))


@_axis_log_ratio.defjvp
def _axis_log_ratio_jvp(primals, tangents):
    (t,), (dt,) = primals, tangents
    w = _axis_log_ratio(t)
    # Implicit function theorem on t = sign(w) T(|w|): dt/dw = T'(|w|) (even in w).
    u = jnp.abs(w)
    _, dt_dw = jax.jvp(_log_ratio, (u,), (jnp.ones_like(u),))
    return w, dt / dt_dw


def _coefficients_from_w(w):
    u = jnp.abs(w)
    s = -2.0 * u
    k, q = agm_kq(-jnp.expm1(s), jnp.exp(s))
    # Curvature ratio C_large/C_small, and (A+B)/C_small = 1 + ratio.
    ratio = (0.5 - q) / (jnp.exp(s) * (0.5 + q))
    # m^3 = 3N(K - E)/(2 pi E* C_small e^2) / c0^3 with (K - E)/e^2 = K (1/2 + Q).
    m = jnp.cbrt(2.0 * k * (0.5 + q) * (1.0 + ratio) / jnp.pi)
    n = m * jnp.exp(-u)
    r = 2.0 * k / (jnp.pi * m)
    # sqrt(m n) is even in w (and smooth through w = 0); a/b = exp(w).
    log_mean = jnp.log(m) - 0.5 * u
    return HertzCoefficients(
        m=m,
        n=n,
        r=r,
        a_over_c0=jnp.exp(log_mean + 0.5 * w),
        b_over_c0=jnp.exp(log_mean - 0.5 * w),
        stiffness_factor=(4.0 / 3.0) * r ** (-1.5),
    )


def _coefficients_from_logs(w, g, h):
    """HertzCoefficients from w = log(a/b), g = log sqrt(m n) and h = log r."""
    half_u = 0.5 * jnp.abs(w)
    return HertzCoefficients(
        m=jnp.exp(g + half_u),
        n=jnp.exp(g - half_u),
        r=jnp.exp(h),
        a_over_c0=jnp.exp(g + 0.5 * w),
        b_over_c0=jnp.exp(g - 0.5 * w),
        stiffness_factor=(4.0 / 3.0) * jnp.exp(-1.5 * h),
    )


def _exact_logs(t):
    """(w, g, h) at one t = log(B/A) by the exact (Newton, elliptic) path."""
    w = _axis_log_ratio(t)
    c = _coefficients_from_w(w)
    return jnp.stack([w, jnp.log(c.a_over_c0 * c.b_over_c0) / 2.0, jnp.log(c.r)])


TABLE_HALF_RANGE = 32.0
"""The table covers |log(B/A)| <= 32; beyond, the e -> 1 asymptote (exact to ~1e-14)."""
_TABLE_STEP = 0.02  # Hermite error ~ step^4 / 384 * |4th derivative|: ~1e-10 near t = 0
_TABLE_NODES = round(2 * TABLE_HALF_RANGE / _TABLE_STEP) + 1


@functools.cache
def _table() -> np.ndarray:
    """(nodes, 6) float64 NumPy: w, g, h at t = -32, ..., 32 and their t-derivatives.

    Built once, on first use, from the exact path (values and jax.jvp derivatives);
    evaluated eagerly even when the first use is inside a jit trace.
    """
    t = np.linspace(-TABLE_HALF_RANGE, TABLE_HALF_RANGE, _TABLE_NODES)
    with jax.ensure_compile_time_eval():
        values, slopes = jax.jit(
            jax.vmap(lambda x: jax.jvp(_exact_logs, (x,), (jnp.ones_like(x),)))
        )(jnp.asarray(t, dtype=jnp.float64))
        table = np.concatenate([np.asarray(values), np.asarray(slopes)], axis=1)
    table.setflags(write=False)
    return table


_ASYMPTOTE_STEPS = 3  # Newton from the estimate below: converged for |t| >= 32


def _asymptotic_logs(t_abs):
    """(|w|, g, h) for large |t| (e -> 1): K = log 4 + u, E = 1."""
    c = math.log(4.0) - 1.0
    # t = 2u - log(K - 1), K - 1 = c + u.
    u = 0.5 * (t_abs + jnp.log(c + 0.5 * t_abs))
    for _ in range(_ASYMPTOTE_STEPS):
        u = u - (2.0 * u - jnp.log(c + u) - t_abs) / (2.0 - 1.0 / (c + u))
    k = math.log(4.0) + u
    log_m = (jnp.log((2.0 / math.pi) * (k - 1.0)) + t_abs + jnp.log1p(jnp.exp(-t_abs))) / 3.0
    return u, log_m - 0.5 * u, jnp.log((2.0 / math.pi) * k) - log_m


def _asymptote_row(t):
    """(w, g, h) (3,) by the asymptote at one t = log(B/A) beyond the table."""
    far = jnp.maximum(jnp.abs(t), TABLE_HALF_RANGE)
    u, g, h = _asymptotic_logs(far)
    return jnp.stack([jnp.sign(t) * u, g, h])


def _table_logs(t):
    """(w, g, h) at t = log(B/A) (any shape) from the Hermite table or, beyond it (never
    in a vehicle: B/A above 8e13), the asymptote, computed only where some element of
    the batch needs it (:func:`jaxrail.compilation.seldom.seldom`)."""
    table = jnp.asarray(_table())
    inside = jnp.abs(t) <= TABLE_HALF_RANGE
    # Each branch sees t moved into its own range (by `where`, so the unused branch and
    # its gradient stay finite).
    x = (jnp.where(inside, t, 0.0) + TABLE_HALF_RANGE) / _TABLE_STEP
    i = jnp.clip(jnp.floor(x), 0, _TABLE_NODES - 2).astype(jnp.int32)
    s = (x - i)[..., None]
    ends = table[jnp.stack([i, i + 1], axis=-1)]  # (..., 2, 6)
    f0, d0 = ends[..., 0, :3], ends[..., 0, 3:] * _TABLE_STEP
    f1, d1 = ends[..., 1, :3], ends[..., 1, 3:] * _TABLE_STEP
    r = 1.0 - s
    interp = r * r * ((1.0 + 2.0 * s) * f0 + s * d0) + s * s * ((3.0 - 2.0 * s) * f1 - r * d1)
    asym = seldom(_asymptote_row, ~inside, t)
    out = computed_once(jnp.where(inside[..., None], interp, asym))
    return out[..., 0], out[..., 1], out[..., 2]


def _coefficients_of_t(t, method):
    if method == "exact":
        return _coefficients_from_w(_axis_log_ratio(t))
    if method == "table":
        return _coefficients_from_logs(*_table_logs(t))
    raise ValueError(f"hertz: method must be one of {METHODS}, got {method!r}")


def _check_inputs(arguments):
    """ValueError if a concrete curvature sum ``A``, ``B`` [1/m] or shear modulus ``G``
    [Pa] is not > 0, or Poisson's ratio ``nu`` is outside (-1, 0.5]."""
    for name in ("A", "B"):
        check_range(f"hertz: curvature sum {name} [1/m]", arguments.get(name), 0.0, np.inf)
    check_range("hertz: shear modulus G [Pa]", arguments.get("G"), 0.0, np.inf)
    check_range("hertz: Poisson's ratio nu", arguments.get("nu"), -1.0, 0.5)


@_compiled
def hertz_coefficients(
    A: Float[ArrayLike, "..."], B: Float[ArrayLike, "..."], method: str = "table"
) -> HertzCoefficients:
    """Dimensionless Hertz coefficients m, n, r for curvature sums A, B [1/m] (> 0).

    ``method``: ``"table"`` (default, within 1e-10 of the exact path) or ``"exact"``
    (Newton solve with elliptic integrals); see the module docstring.
    """
    require_float64("hertz_coefficients")
    A, B = jnp.asarray(A, dtype=jnp.float64), jnp.asarray(B, dtype=jnp.float64)
    return _coefficients_of_t(jnp.log(B / A), method)


def _effective_modulus(G, nu):
    G = jnp.asarray(G, dtype=jnp.float64)
    nu = jnp.asarray(nu, dtype=jnp.float64)
    return G / (1.0 - nu)


@_compiled
def hertz_stiffness(
    A: Float[ArrayLike, "..."],
    B: Float[ArrayLike, "..."],
    G: Float[ArrayLike, "..."] = STEEL_SHEAR_MODULUS,
    nu: Float[ArrayLike, "..."] = STEEL_POISSON,
    method: str = "table",
) -> Float[Array, "..."]:
    """Hertz stiffness K_H [N/m^1.5] (N = K_H delta^1.5), independent of the load.

    K_H = (4/3) E* (pi m / (2 K(e)))^(3/2) / sqrt(A + B), A, B [1/m] > 0, G [Pa], nu [-].
    Sphere (A = B = 1/(2R)): (4/3) E* sqrt(R). ``method``: as :func:`hertz_coefficients`.
    """
    coeffs = hertz_coefficients(A, B, method=method)
    A, B = jnp.asarray(A, dtype=jnp.float64), jnp.asarray(B, dtype=jnp.float64)
    return coeffs.stiffness_factor * _effective_modulus(G, nu) / jnp.sqrt(A + B)


@_compiled
def hertz(
    normal_force: Float[ArrayLike, "..."],
    A: Float[ArrayLike, "..."],
    B: Float[ArrayLike, "..."],
    G: Float[ArrayLike, "..."] = STEEL_SHEAR_MODULUS,
    nu: Float[ArrayLike, "..."] = STEEL_POISSON,
    method: str = "table",
) -> HertzContact:
    """Hertz contact ellipse for a normal load.

    Arguments:
        normal_force: N [N] (values <= 0 give the empty contact, all fields but the
            stiffness zero).
        A: curvature sum along x (rolling direction) [1/m], > 0.
        B: curvature sum along y (lateral) [1/m], > 0.
        G: shear modulus [Pa] (steel 8.2e10); nu: Poisson ratio [-] (steel 0.28).
        method: ``"table"`` (default) or ``"exact"``, as :func:`hertz_coefficients`.

    All arguments broadcast; returns a :class:`HertzContact` of the broadcast shape.
    """
    coeffs = hertz_coefficients(A, B, method=method)
    A, B = jnp.asarray(A, dtype=jnp.float64), jnp.asarray(B, dtype=jnp.float64)
    n_force = jnp.asarray(normal_force, dtype=jnp.float64)
    e_star = _effective_modulus(G, nu)
    loaded = n_force > 0.0
    # Double where: cbrt has an infinite slope at N = 0.
    c0_cubed = 3.0 * jnp.where(loaded, n_force, 1.0) / (4.0 * e_star * (A + B))
    c0 = jnp.where(loaded, jnp.cbrt(c0_cubed), 0.0)
    return HertzContact(
        a=coeffs.a_over_c0 * c0,
        b=coeffs.b_over_c0 * c0,
        approach=coeffs.r * c0 * c0 * (A + B),
        stiffness=coeffs.stiffness_factor * e_star / jnp.sqrt(A + B),
        # 3N/(2 pi a b) with 3N = 4 E* (A+B) c0^3: finite, -> 0 with N.
        # m n = (a/c0)(b/c0).
        p0=2.0 * e_star * (A + B) * c0 / (jnp.pi * coeffs.a_over_c0 * coeffs.b_over_c0),
    )


def convex_curvature(profile, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Lateral curvature [1/m] of a wheel or rail profile, positive where convex toward
    the other body.

    jaxrail's wheel height F(y) points radially outward (toward the rail) and the rail
    height z(y) points up (toward the wheel), so in both cases a surface that bulges
    toward the other body has a local maximum of its height: the convex curvature is
    -h''/(1 + h'^2)^(3/2) = -``profile.curvature(y)``. A plane curve's curvature does
    not change under rotation, so the value in the profile plane is also the value in
    the contact frame (tilted by the contact angle).
    """
    return -profile.curvature(y)


@_compiled
def hertz_from_curvatures(
    normal_force: Float[ArrayLike, "..."],
    rolling_radius: Float[ArrayLike, "..."],
    wheel_profile_curvature: Float[ArrayLike, "..."],
    rail_profile_curvature: Float[ArrayLike, "..."],
    G: Float[ArrayLike, "..."] = STEEL_SHEAR_MODULUS,
    nu: Float[ArrayLike, "..."] = STEEL_POISSON,
    contact_angle: Float[ArrayLike, "..."] = 0.0,
    min_curvature_ratio: float = 1e-3,
    method: str = "table",
) -> HertzContact:
    """Hertz contact of a wheel on a longitudinally straight rail.

    Arguments:
        normal_force: N [N].
        rolling_radius: wheel rolling radius r at the contact point [m].
        wheel_profile_curvature: lateral curvature of the wheel profile [1/m], **positive
            where convex toward the rail** (tread crown), negative where concave (the
            S1002 flange throat). From a jaxrail profile: :func:`convex_curvature`,
            i.e. -F''/(1 + F'^2)^1.5 with F the radial-outward profile height.
        rail_profile_curvature: lateral curvature of the rail head [1/m], positive where
            convex (the head crown): -z''/(1 + z'^2)^1.5 with z the upward height.
        G, nu: shear modulus [Pa] and Poisson ratio [-].
        contact_angle: angle gamma [rad] between the contact normal and the wheel's
            radial direction. The wheel's principal curvature in the rolling direction
            is cos(gamma)/r (Meusnier), which matters in the flange (gamma ~ 70 deg).
            Default 0 gives the common approximation A = 1/(2r).
        min_curvature_ratio: static floor on B/A. Nearly conformal contact (B -> 0 or
            negative, e.g. a worn hollow wheel on a matching rail) is not Hertzian; B is
            clipped to ``min_curvature_ratio * A`` there (zero gradient with respect to
            the curvatures while clipped), giving a long lateral ellipse (b/a ~ 50 at
            the default 1e-3) instead of NaN. Callers that care can test
            ``wheel + rail curvature < 2 * min_curvature_ratio * A`` themselves.
        method: ``"table"`` (default) or ``"exact"``, as :func:`hertz_coefficients`.

    Curvature sums: A = cos(gamma) / (2 r), B = (kappa_wheel + kappa_rail) / 2.
    """
    radius = jnp.asarray(rolling_radius, dtype=jnp.float64)
    gamma = jnp.asarray(contact_angle, dtype=jnp.float64)
    a_curv = 0.5 * jnp.cos(gamma) / radius
    b_curv = 0.5 * (
        jnp.asarray(wheel_profile_curvature, dtype=jnp.float64)
        + jnp.asarray(rail_profile_curvature, dtype=jnp.float64)
    )
    b_curv = jnp.maximum(b_curv, min_curvature_ratio * a_curv)
    return hertz(normal_force, a_curv, b_curv, G, nu, method=method)
