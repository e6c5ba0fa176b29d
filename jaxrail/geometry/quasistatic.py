"""Quasi-static wheel-rail geometry functions of a rigid wheelset on straight track.

For each lateral shift ``y`` (positive to the left) and yaw ``yaw_per_shift * y``, the
wheelset's height and roll are solved so that each wheel reaches the same small
*virtual penetration* into its rail (both wheels touch), by Newton's method on the
refined deepest-strip depth of the contact search. The contact search at that pose then
gives the patches, rolling radii, contact angles and positions: the railway engineer's
"contact point functions", rolling radius difference ``dr(y)`` and roll angle.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..contact.pose import wheelset_pose
from ..contact.search import ContactPatches, SearchConfig, deepest_depth, search_wheelset
from ..track import Rails, straight_track

NEWTON_STEPS = 12
_PROBE = 1.0e-7  # [m] and [rad]: forward-difference step of the Newton Jacobian
_TRACK_LENGTH = 20.0
_STATION = 10.0
VIRTUAL_PENETRATION = 1.0e-6  # [m] default depth each wheel is pressed into its rail


class WheelsetGeometry(eqx.Module):
    """Geometry functions over a range of shifts (leading axis: shift).

    Fields:
        shift: lateral shift of the wheelset [m], positive left, shape (n,).
        yaw: yaw angle [rad], shape (n,).
        roll: roll angle [rad] (positive lifts the left wheel), shape (n,).
        height: wheelset centre height above the rail plane [m], shape (n,).
        patches: contact patches, shape (n, 2, P) for (left, right).
        main: slot of the deepest patch of each wheel, shape (n, 2).
        delta_r: rolling radius difference left minus right of the main patches [m].
        residual: largest depth error of the solve [m] (a check; should be ~1e-12).
    """

    shift: Float[Array, " n"]
    yaw: Float[Array, " n"]
    roll: Float[Array, " n"]
    height: Float[Array, " n"]
    patches: ContactPatches
    main: Array
    delta_r: Float[Array, " n"]
    residual: Float[Array, " n"]

    def main_patch(self, field: str) -> Float[Array, "n 2"]:
        """A field of :class:`ContactPatches` at the main patch of each wheel."""
        values = getattr(self.patches, field)
        return jnp.take_along_axis(values, self.main[..., None], axis=2)[..., 0]


@jax.jit
def wheelset_geometry(wheel, rails: Rails, shifts, yaw_per_shift=0.0,
                      virtual_penetration=VIRTUAL_PENETRATION,
                      config: SearchConfig = SearchConfig()):
    """Quasi-static geometry of a wheelset shifted across straight track.

    Arguments:
        wheel: the :class:`WheelProfile` of both wheels.
        rails: the track's :class:`~jaxrail.track.Rails` (their profile and offset, which
            sets the gauge: :meth:`~jaxrail.track.Rails.at_gauge`).
        shifts: lateral shifts [m], shape (n,), positive to the left; solved in order,
            each from the previous solution (give them sorted).
        yaw_per_shift: yaw [rad] per metre of shift (0 for the usual analysis).
        virtual_penetration: depth [m] each wheel is pressed into its rail; patches
            are the strips penetrating at that depth (1e-6 m = 0.001 mm by default, far
            below elastic approaches, so positions are those of rigid contact).
        config: search settings.

    Jitted (the entry point): calls with the same profile types and shift count reuse
    one compilation.
    """
    shifts = jnp.asarray(shifts, dtype=jnp.float64)
    track = straight_track(_TRACK_LENGTH, rails=rails)

    def pose(shift, height, roll):
        return wheelset_pose(track, _STATION, shift, height, roll, yaw_per_shift * shift)

    def depths(unknowns, shift):
        position, rotation = pose(shift, unknowns[0], unknowns[1])
        depth = lambda side: deepest_depth(wheel, track, position, rotation, side,  # noqa: E731
                                           config, _STATION)
        return jnp.stack([depth(1.0), depth(-1.0)]) - virtual_penetration

    def solve(unknowns, shift):
        def newton(x, _):
            # Forward differences (one vmapped evaluation) rather than jacfwd: the same
            # convergence here, at a fraction of the compile time.
            probes = x + jnp.concatenate([jnp.zeros((1, 2)), _PROBE * jnp.eye(2)])
            values = jax.vmap(lambda p: depths(p, shift))(probes)
            r, jac = values[0], (values[1:] - values[0]).T / _PROBE
            step = jnp.linalg.solve(jac, r)
            step = step * jnp.minimum(1.0, 2.0e-3 / (jnp.max(jnp.abs(step)) + 1e-30))
            return x - step, None

        x, _ = jax.lax.scan(newton, unknowns, None, length=NEWTON_STEPS)
        return x, (x, jnp.max(jnp.abs(depths(x, shift))))

    start = jnp.stack([wheel.nominal_radius, jnp.asarray(0.0)])
    _, (solution, residual) = jax.lax.scan(solve, start, shifts)

    def patches_at(shift, unknowns):
        position, rotation = pose(shift, unknowns[0], unknowns[1])
        return search_wheelset(wheel, track, position, rotation, config, _STATION)

    patches = jax.vmap(patches_at)(shifts, solution)
    main = jnp.argmax(patches.penetration, axis=2)
    radius = jnp.take_along_axis(patches.rolling_radius, main[..., None], axis=2)[..., 0]
    return WheelsetGeometry(shift=shifts, yaw=yaw_per_shift * shifts, roll=solution[:, 1],
                            height=solution[:, 0], patches=patches, main=main,
                            delta_r=radius[:, 0] - radius[:, 1], residual=residual)
