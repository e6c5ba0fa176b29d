"""The wear of a run: every patch of every wheel at every output time through a wear law,
integrated over time and spread over the wheel and rail profiles.

The patches come from the run's outputs (:class:`~jaxrail.simulation.WheelOutputs`:
normal force, Hertz semi-axes, creepages, contact point and angle); the rolling speed is
each wheelset's speed. The rates are integrated over the output times by the trapezoidal
rule (the output rate must resolve the contact's changes, as for any output); times the
run did not reach count nothing. Friction is the contact's ``friction`` (mu0 of
Polach 2005: the falling friction is not in the wear). A patch is on the flange where
its contact angle exceeds ``flange_angle`` (0.6 rad, as the summary's flange contact
fraction).

All of it is JAX: :func:`run_wear` runs under ``jit`` and ``grad`` on the result of a
differentiated run, and ``vmap`` over a batch.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..vehicles.vehicle import wheelset_states
from .distribution import deposit, height_loss, strip_positions
from .patch_wear import patch_wear

FLANGE_ANGLE = 0.6  # [rad] contact angle above which a patch is on the flange
SIDE_SIGNS = np.array([1.0, -1.0])  # left wheel/rail: l toward the field side; right: not


class RunWear(eqx.Module):
    """Wear of one run (arrays; W wheelsets leading first, wheels left then right).

    Fields: distance (W,) [m] each wheelset travelled; volume (W, 2) [m^3] each wheel
    lost; flange_volume (W, 2) [m^3] of it on the flange; extrapolated_volume (W, 2)
    [m^3] from elements beyond the law's range; wheel_nodes (Kw,), rail_nodes (Kr,) [m]
    the profiles' lateral grids; wheel_volume (W, 2, Kw) [m^3] each wheel's volume at
    the wheel grid's nodes; rail_volume (2, Kr) [m^3] the left and right rails' volume
    at the rail grid's nodes, all wheels together; wheel_radius [m] nominal.
    """

    distance: Float[Array, " W"]
    volume: Float[Array, "W 2"]
    flange_volume: Float[Array, "W 2"]
    extrapolated_volume: Float[Array, "W 2"]
    wheel_nodes: Float[Array, " Kw"]
    rail_nodes: Float[Array, " Kr"]
    wheel_volume: Float[Array, "W 2 Kw"]
    rail_volume: Float[Array, "2 Kr"]
    wheel_radius: Float[Array, ""]

    def per_km(self, volume):
        """(W, 2) [mm^3/km]: a volume per wheel (W, 2) [m^3] per km run."""
        return volume * 1e9 / (self.distance[:, None] * 1e-3)

    def volume_per_km(self):
        """(W, 2) [mm^3/km]: each wheel's wear volume per km run."""
        return self.per_km(self.volume)

    def flange_fraction(self):
        """(W, 2) [-]: the share of each wheel's wear volume on its flange (0 where it
        wore nothing)."""
        worn = self.volume > 0.0
        return jnp.where(worn, self.flange_volume / jnp.where(worn, self.volume, 1.0), 0.0)

    def wheel_depth_per_km(self):
        """(W, 2, Kw) [m/km]: each wheel's radial height loss per km run
        (:func:`jaxrail.wear.distribution.height_loss` over its circumference)."""
        circumference = 2.0 * jnp.pi * self.wheel_radius
        return height_loss(self.wheel_nodes, self.wheel_volume, circumference) \
            / (self.distance[:, None, None] * 1e-3)

    def rail_depth_per_pass(self):
        """(2, Kr) [m]: the rails' height loss per pass of the vehicle."""
        return height_loss(self.rail_nodes, self.rail_volume, jnp.mean(self.distance))


def _trapezoid_weights(t, valid):
    """Weights (T,) [s] of the trapezoidal rule over the reached output times."""
    t = jnp.where(valid, t, 0.0)
    dt = jnp.where(valid[1:] & valid[:-1], t[1:] - t[:-1], 0.0)
    zero = jnp.zeros((1,), dtype=dt.dtype)
    return 0.5 * (jnp.concatenate([dt, zero]) + jnp.concatenate([zero, dt]))


def run_wear(result, vehicle, params, law, wheel_nodes, rail_nodes,
             flange_angle: float = FLANGE_ANGLE, t_from=0.0) -> RunWear:
    """:class:`RunWear` of ``result`` (an unbatched
    :class:`~jaxrail.simulation.SimulationResult` of ``vehicle`` with ``params``)
    through the wear ``law`` (:mod:`jaxrail.wear.laws`), spread over the grids
    ``wheel_nodes`` and ``rail_nodes`` [m] (uniform; :func:`~jaxrail.wear.distribution.lateral_grid`),
    counting from the output time ``t_from`` [s] on (the distance too)."""
    w = result.wheels
    valid = jnp.asarray(result.valid) & (jnp.asarray(result.t) >= t_from)
    weights = _trapezoid_weights(jnp.asarray(result.t), valid)  # (T,)
    q = jnp.where(valid[:, None], result.q, 0.0)
    qdot = jnp.where(valid[:, None], result.qdot, 0.0)
    velocity = jax.vmap(lambda a, b: wheelset_states(vehicle, a, b)[2])(q, qdot)  # (T, W, 3)
    speed = jnp.sqrt(jnp.sum(velocity * velocity, axis=-1) + 1e-30)  # (T, W)
    distance = jnp.sum(weights[:, None] * speed, axis=0)

    present = jnp.asarray(w.active, dtype=bool) & valid[:, None, None, None]
    clean = lambda x: jnp.where(present, x, 0.0)  # noqa: E731 (NaN after an early stop)
    contact = params.contact
    one = lambda n, a, b, xi, eta, phi, v: patch_wear(  # noqa: E731
        law, n, a, b, xi, eta, phi, contact.friction, v, contact.shear_modulus,
        contact.poisson)
    fields = [clean(x) for x in (w.normal_force, w.semi_axis_a, w.semi_axis_b, w.creepage_x,
                                 w.creepage_y, w.spin)]
    speeds = jnp.broadcast_to(speed[:, :, None, None], fields[0].shape)
    flat = [x.reshape(-1) for x in fields + [speeds]]
    patches = jax.vmap(one)(*flat)
    shape = fields[0].shape  # (T, W, 2, P)
    strips = patches.strip_rate.shape[-1]
    strip_volume = (patches.strip_rate.reshape(shape + (strips,))
                    * weights[:, None, None, None, None])  # (T, W, 2, P, S) [m^3]
    patch_volume = jnp.sum(strip_volume, axis=-1)
    extrapolated = patches.extrapolated_rate.reshape(shape) * weights[:, None, None, None]
    angle = clean(w.contact_angle)
    on_flange = angle > flange_angle
    offsets = patches.strip_offset.reshape(shape + (strips,))
    sides = jnp.asarray(SIDE_SIGNS)[None, None, :, None, None]
    wheel_at = strip_positions(clean(w.y_wheel), angle, offsets, sides)
    rail_at = strip_positions(clean(w.y_rail), angle, offsets, sides)
    # (W, 2) grids: the wheel's own; each rail's, summed over the wheelsets
    wheel_volume = jax.vmap(jax.vmap(lambda y, v: deposit(wheel_nodes, y, v),
                                     in_axes=(1, 1)), in_axes=(1, 1))(wheel_at, strip_volume)
    rail_volume = jax.vmap(lambda y, v: deposit(rail_nodes, y, v), in_axes=(2, 2))(
        rail_at, strip_volume)
    return RunWear(
        distance=distance, volume=jnp.sum(patch_volume, axis=(0, 3)),
        flange_volume=jnp.sum(jnp.where(on_flange, patch_volume, 0.0), axis=(0, 3)),
        extrapolated_volume=jnp.sum(extrapolated, axis=(0, 3)),
        wheel_nodes=jnp.asarray(wheel_nodes, dtype=jnp.float64),
        rail_nodes=jnp.asarray(rail_nodes, dtype=jnp.float64),
        wheel_volume=wheel_volume, rail_volume=rail_volume,
        wheel_radius=jnp.asarray(params.nominal_radius, dtype=jnp.float64))
