"""Profile measures: rail top, gauge point and rail position; wheel flange measures.

All functions are pure JAX with fixed iteration counts: a coarse grid search and a
bisection on a copy of the profile cut from the gradient (so those loops trace no
tangents), then one Newton step with the real profile from the converged estimate,
which carries the gradient of the implicit function theorem. They jit, vmap (over a
batch of profiles) and differentiate with respect to the profile parameters.

Conventions are those of :mod:`jaxrail.profiles._base`: ``y`` [m] toward the field
side, so the rail's gauge face and the wheel's flange lie at negative ``y``.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._base import Profile, frozen

GRID_POINTS = 257  # coarse search: 0.3 mm spacing on a rail head, 0.5 mm on a wheel
BISECTION_STEPS = 52  # brackets of ~0.1 m shrink below 1e-16 m
NEWTON_STEPS = 1  # after a converged bisection one step gives the exact gradient


def _where_clip(y, lo, hi):
    # Unlike jnp.clip, gives derivative 1 (not 1/2) when y sits exactly on a bound.
    return jnp.where(y > hi, hi, jnp.where(y < lo, lo, y))


def _bisect(f, lo, hi, zeros_on_lo_side: bool = False):
    """Sign change of ``f`` in ``[lo, hi]`` by bisection (no gradient).

    Points where ``f == 0`` count as the ``hi`` side, so the result is the left end of
    a flat zero set; with ``zeros_on_lo_side`` they count as the ``lo`` side (right
    end). If ``f`` keeps one sign throughout, the result converges to ``hi``.
    """
    lo, hi = jax.lax.stop_gradient(lo), jax.lax.stop_gradient(hi)
    sign_lo = jnp.sign(jax.lax.stop_gradient(f(lo)))

    def step(_, state):
        lo, hi = state
        mid = 0.5 * (lo + hi)
        f_mid = sign_lo * jax.lax.stop_gradient(f(mid))
        on_lo_side = (f_mid >= 0.0) if zeros_on_lo_side else (f_mid > 0.0)
        return jnp.where(on_lo_side, mid, lo), jnp.where(on_lo_side, hi, mid)

    lo, hi = jax.lax.fori_loop(0, BISECTION_STEPS, step, (lo, hi))
    return 0.5 * (lo + hi)


def _newton(f, df, y, lo, hi):
    """A few Newton steps on ``f(y) = 0`` kept inside ``[lo, hi]``; they carry the
    gradient (implicit function theorem) from the converged bisection estimate."""
    y = jax.lax.stop_gradient(y)
    lo, hi = jax.lax.stop_gradient(lo), jax.lax.stop_gradient(hi)
    for _ in range(NEWTON_STEPS):
        d = df(y)
        safe_d = jnp.where(d != 0.0, d, 1.0)
        y = _where_clip(y - jnp.where(d != 0.0, f(y) / safe_d, 0.0), lo, hi)
    return y


def _grid_argmax(g, lo: float, hi, n: int = GRID_POINTS):
    """Bracket ``[a, b]`` (two grid cells) around the grid maximum of ``g`` on ``[lo, hi]``."""
    lo = jnp.asarray(lo, dtype=jnp.float64)
    hi = jnp.asarray(hi, dtype=jnp.float64)
    t = jnp.linspace(0.0, 1.0, n, dtype=jnp.float64)
    ys = jax.lax.stop_gradient(lo + (hi - lo) * t)
    k = jnp.argmax(jax.vmap(g)(ys))
    return ys[jnp.maximum(k - 1, 0)], ys[jnp.minimum(k + 1, n - 1)]


def _maximizer(g, dg, lo, hi, plateau: bool = False):
    """Location (no gradient) of the maximum of ``g`` on ``[lo, hi]``: grid search,
    then bisection on the derivative ``dg`` inside the two cells around the grid max.
    With ``plateau``, a flat maximum (``dg == 0`` on an interval, as on a straight
    flank) gives its middle, where the value's gradient is that of the flat piece.
    Returns the location and the bracket."""
    a, b = _grid_argmax(g, lo, hi)
    y = _bisect(dg, a, b)
    if plateau:
        y = 0.5 * (y + _bisect(dg, a, b, zeros_on_lo_side=True))
    return y, (a, b)


def _level_crossing(profile: Profile, level, lo, hi):
    """``y`` in ``[lo, hi]`` where ``profile.height(y) == level`` (height monotone there)."""
    fixed, fixed_level = frozen(profile), jax.lax.stop_gradient(level)
    y = _bisect(lambda y: fixed.height(y) - fixed_level, lo, hi)
    return _newton(lambda y: profile.height(y) - level, profile.slope, y, lo, hi)


def _top_location(profile: Profile):
    """Location [m] of the highest point (no gradient) and its search bracket. The
    height there still has the right gradient (envelope theorem: slope 0)."""
    fixed = frozen(profile)
    return _maximizer(fixed.height, fixed.slope, *profile.domain)


def highest_point(rail: Profile) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Highest point ``(y, z)`` [m] of a profile over its domain (rail top).

    Arguments:
        rail: a rail profile (any :class:`Profile` whose height has one interior
            maximum, e.g. a convex head).

    Returns ``y`` [m] (profile frame, + toward the field side) and ``z = height(y)``.
    """
    y, (a, b) = _top_location(rail)
    y = _newton(rail.slope, rail.second_derivative, y, a, b)
    return y, rail.height(y)


def gauge_point(rail: Profile, gauge_height: Float[ArrayLike, ""] = 0.014) -> Float[Array, ""]:
    """Lateral position ``y`` [m] of the gauge point of a rail profile.

    The gauge point lies on the gauge side (``y`` below the highest point) where the
    head is ``gauge_height`` [m] below its highest point (14 mm for standard gauge).
    Raises (via ``equinox.error_if``, also under jit) if that depth is not reached
    inside the profile domain.
    """
    gauge_height = jnp.asarray(gauge_height, dtype=jnp.float64)
    y_top, _ = _top_location(rail)
    level = rail.height(y_top) - gauge_height
    lo = rail.domain[0]
    y = _level_crossing(rail, level, lo, y_top)
    return eqx.error_if(
        y, rail.height(lo) > level,
        "gauge_point: the gauge depth lies below the rail profile domain on the gauge side")


def rail_offset(rail: Profile, gauge: Float[ArrayLike, ""] = 1.435,
                gauge_height: Float[ArrayLike, ""] = 0.014) -> Float[Array, ""]:
    """Lateral distance [m] from the track centre to the rail profile origin.

    It places the two (mirrored) rails so that their gauge points are ``gauge`` [m]
    apart: ``offset = gauge/2 - y_gauge_point`` (``y_gauge_point < 0``). The highest
    point of the rail is then ``offset + y_top`` from the track centre (760.53 mm for
    UIC60 1:40 on 1435 mm gauge).
    """
    gauge = jnp.asarray(gauge, dtype=jnp.float64)
    return 0.5 * gauge - gauge_point(rail, gauge_height)


def _flange_tip(wheel_surface: Profile):
    """Flange tip: highest point ``(y, height)`` [m] of a wheel surface; ``y`` carries
    no gradient (it only brackets the flank), the height does."""
    y_tip, _ = _top_location(wheel_surface)
    return y_tip, wheel_surface.height(y_tip)


def _check_datum(wheel_surface: Profile) -> None:
    lo, hi = wheel_surface.domain
    if not lo < 0.0 < hi:
        raise ValueError(
            f"wheel_surface: the taping line y = 0 must lie inside the domain, got {(lo, hi)}")


def flange_height(wheel_surface: Profile) -> Float[Array, ""]:
    """Flange height [m]: highest point of the wheel profile minus its height at the
    taping line ``y = 0`` (28 mm for S1002)."""
    _check_datum(wheel_surface)
    _, z_tip = _flange_tip(wheel_surface)
    return z_tip - wheel_surface.height(0.0)


def _flank_point(wheel_surface: Profile, level, y_tip):
    """``y`` [m] on the active flank (between the tip and the taping line) at height
    ``level`` [m]; raises if the flank does not reach that height."""
    y = _level_crossing(wheel_surface, level, y_tip, 0.0)
    bad = (wheel_surface.height(y_tip) < level) | (wheel_surface.height(0.0) > level)
    return eqx.error_if(y, bad, "flange measure: height not reached on the flange flank")


def flange_thickness(wheel_surface: Profile,
                     height_above_datum: Float[ArrayLike, ""] = 0.010,
                     flange_back: Float[ArrayLike, ""] = -0.070) -> Float[Array, ""]:
    """Flange thickness Sd [m] (EN 15313): from the flange back at ``flange_back`` [m]
    (profile ``y``, -70 mm for S1002) to the active flank point ``height_above_datum``
    [m] above the height at the taping line (32.5 mm for S1002)."""
    _check_datum(wheel_surface)
    level = wheel_surface.height(0.0) + jnp.asarray(height_above_datum, dtype=jnp.float64)
    y_tip, _ = _flange_tip(wheel_surface)
    return _flank_point(wheel_surface, level, y_tip) - jnp.asarray(flange_back, dtype=jnp.float64)


def flange_qr(wheel_surface: Profile, height_above_datum: Float[ArrayLike, ""] = 0.010,
              below_tip: Float[ArrayLike, ""] = 0.002) -> Float[Array, ""]:
    """Flange steepness qR [m] (EN 15313): lateral distance between the active flank
    point ``below_tip`` [m] under the flange tip and the point ``height_above_datum``
    [m] above the taping-line height (10.79 mm for S1002 by its formulas)."""
    _check_datum(wheel_surface)
    y_tip, z_tip = _flange_tip(wheel_surface)
    datum = wheel_surface.height(0.0)
    level_low = datum + jnp.asarray(height_above_datum, dtype=jnp.float64)
    level_high = z_tip - jnp.asarray(below_tip, dtype=jnp.float64)
    return (_flank_point(wheel_surface, level_low, y_tip)
            - _flank_point(wheel_surface, level_high, y_tip))


def flange_angle(wheel_surface: Profile) -> Float[Array, ""]:
    """Flange angle [rad]: the largest inclination ``atan(-d height/dy)`` of the active
    flank between the flange tip and the taping line (70 degrees for S1002)."""
    _check_datum(wheel_surface)
    fixed = frozen(wheel_surface)
    y_tip, _ = _top_location(fixed)
    y, _ = _maximizer(lambda y: -fixed.slope(y), lambda y: -fixed.second_derivative(y),
                      y_tip, 0.0, plateau=True)
    # At an interior maximum the value's gradient needs no d y/d parameter (envelope).
    return jnp.arctan(-wheel_surface.slope(y))
