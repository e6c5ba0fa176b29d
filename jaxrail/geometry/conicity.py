"""Equivalent conicity from the rolling radius difference function (EN 15302).

Variant implemented: the **integral (Klingel) method**. A rigid wheelset rolling
without slip obeys the nonlinear kinematic (Klingel) equation

    y'' = -dr(y) / (2 e r0),

with ``x`` the distance travelled, ``dr(y)`` the rolling radius difference (left minus
right) at lateral shift ``y``, ``e`` half the lateral distance between the contact
points and ``r0`` the nominal rolling radius. Its oscillation of amplitude ``A`` (the
largest positive shift) has the wavelength ``lambda(A)``, found from the energy
integral ``V(y) = int_0^y dr / (2 e r0)``:

    lambda = 2 int_{y-}^{A} dy / sqrt(2 (V(A) - V(y))),    V(y-) = V(A), y- < 0,

and the equivalent conicity is the cone angle of the linear wheelset with the same
wavelength: ``tan(gamma_e) = e r0 (2 pi / lambda)^2``. For a coned wheel
(``dr = 2 tan(gamma) y``) this returns ``tan(gamma)`` at every amplitude.

``dr`` is interpolated linearly between the samples (so ``V`` is piecewise quadratic,
integrated exactly), the negative turning point found by bisection then Newton, and the
integral, which has inverse-square-root singularities at both turning points, by
Gauss-Chebyshev quadrature of the smooth remainder.
"""

import jax
import jax.numpy as jnp

_BISECTION_STEPS = 60
_QUADRATURE_NODES = 64


def _potential(shifts, delta_r, scale):
    """Callable V(y) = scale * int_0^y dr, exact for linearly interpolated dr."""
    segment = 0.5 * (delta_r[1:] + delta_r[:-1]) * jnp.diff(shifts)
    cumulative = jnp.concatenate([jnp.zeros(1), jnp.cumsum(segment)])

    def integral_to(y):
        i = jnp.clip(jnp.searchsorted(shifts, y) - 1, 0, shifts.shape[0] - 2)
        h = y - shifts[i]
        slope = (delta_r[i + 1] - delta_r[i]) / (shifts[i + 1] - shifts[i])
        return cumulative[i] + delta_r[i] * h + 0.5 * slope * h * h

    origin = integral_to(jnp.asarray(0.0))
    return lambda y: scale * (integral_to(y) - origin)


@jax.jit
def equivalent_conicity(shifts, delta_r, amplitudes, half_contact_distance=0.75,
                        nominal_radius=0.46):
    """Equivalent conicity ``tan(gamma_e)`` [-] for each amplitude [m] (EN 15302 integral
    method, see the module docstring).

    Arguments:
        shifts: increasing lateral shifts [m], shape (n,), covering ``-A .. A`` for the
            largest amplitude (positive shift = to the left).
        delta_r: rolling radius difference left minus right [m] at each shift.
        amplitudes: amplitudes [m], shape (k,), > 0.
        half_contact_distance: ``e`` [m]; nominal_radius: ``r0`` [m].
    """
    shifts = jnp.asarray(shifts, dtype=jnp.float64)
    delta_r = jnp.asarray(delta_r, dtype=jnp.float64)
    scale = 1.0 / (2.0 * half_contact_distance * nominal_radius)
    potential = _potential(shifts, delta_r, scale)

    def one(amplitude):
        level = potential(amplitude)

        def bisect(bounds, _):
            lo, hi = bounds
            mid = 0.5 * (lo + hi)
            above = potential(mid) > level
            return (jnp.where(above, mid, lo), jnp.where(above, hi, mid)), None

        (lo, hi), _ = jax.lax.scan(bisect, (shifts[0], jnp.asarray(0.0)), None,
                                   length=_BISECTION_STEPS)
        turning = 0.5 * (lo + hi)
        # One Newton step: same value, and it carries the turning point's derivative.
        slope = scale * jnp.interp(turning, shifts, delta_r)
        turning = turning - jax.lax.stop_gradient(1.0 / slope) * (potential(turning) - level)
        k = jnp.arange(1, _QUADRATURE_NODES + 1)
        centre, half = 0.5 * (amplitude + turning), 0.5 * (amplitude - turning)
        y = centre + half * jnp.cos((2 * k - 1) * jnp.pi / (2 * _QUADRATURE_NODES))
        drop = 2.0 * (level - jax.vmap(potential)(y))
        g = jnp.sqrt((amplitude - y) * (y - turning) / drop)
        half_wavelength = jnp.pi / _QUADRATURE_NODES * jnp.sum(g)
        wavelength = 2.0 * half_wavelength
        return half_contact_distance * nominal_radius * (2.0 * jnp.pi / wavelength) ** 2

    return jax.vmap(one)(jnp.asarray(amplitudes, dtype=jnp.float64))
