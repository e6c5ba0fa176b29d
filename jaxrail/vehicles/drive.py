"""A speed drive: a longitudinal force that holds one body to a programmed speed.

Without a drive a vehicle coasts: it starts at its speed and the wheel-rail creep
forces slow it (a hunting wheelset loses a few mm/s per second). The nonlinear
stability methods need the speed prescribed, as GENSYS and SIMPACK do by moving the
vehicle's reference frame: constant for the brute-force runs, decreasing at a stated
rate for the ramp-down (:mod:`jaxrail.stability.nonlinear`). The drive is a force along
global x (the straight track's direction) on one body (the frame, the carbody):

    F = M (a_ref(t) - (v(t) - V_ref(t)) / tau),

with ``V_ref(t) = speed - deceleration * max(t - hold, 0)`` and ``a_ref`` its
derivative. ``M`` is the vehicle's whole mass, so the feed-forward ``M a_ref``
decelerates the vehicle along the ramp and the feedback, a damper of ``M / tau`` to
the reference speed, takes up the creep forces' drag: with ``tau`` = 0.05 s a 5 kN
drag leaves the body 0.02 m/s behind its reference.

The drive is explicit in the IMEX method (it is not part of the wheel-rail load
Jacobian): its eigenvalue, about ``-M / (m_body tau)``, is slow beside the contact's.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._float64 import f64

TIME_CONSTANT = 0.05
"""[s] of the drive's speed feedback [A]: a few hunting periods' worth of the creep
drag is taken up within it, and its eigenvalue stays slow beside the contact's."""


class SpeedDrive(eqx.Module):
    """Holds body ``body``'s velocity along global x to ``speed`` [m/s] for ``hold`` [s],
    then to a speed decreasing at ``deceleration`` [m/s^2]; ``mass`` [kg] the vehicle's
    whole mass, ``time_constant`` [s] the feedback's (module docstring). Traced numbers:
    changing them does not recompile; ``body`` is static."""

    body: int = eqx.field(static=True)
    speed: jnp.ndarray = eqx.field(converter=f64)
    mass: jnp.ndarray = eqx.field(converter=f64)
    deceleration: jnp.ndarray = eqx.field(converter=f64, default=0.0)
    hold: jnp.ndarray = eqx.field(converter=f64, default=0.0)
    time_constant: jnp.ndarray = eqx.field(converter=f64, default=TIME_CONSTANT)

    def reference_speed(self, t):
        """V_ref(t) [m/s]."""
        return self.speed - self.deceleration * jnp.maximum(t - self.hold, 0.0)

    def force(self, t, qdot):
        """The drive's force [N] along global x at time ``t`` [s] with the bodies'
        velocities ``qdot`` (7 n,)."""
        ramping = jnp.where(t > self.hold, self.deceleration, 0.0)
        error = qdot[7 * self.body] - self.reference_speed(t)
        return self.mass * (-ramping - error / self.time_constant)

    def add_to(self, t, qdot, forces):
        """``forces`` (n, 3) [N] with the drive's force added on its body."""
        return forces.at[self.body, 0].add(self.force(t, qdot))


class ConstantForce(eqx.Module):
    """A constant force ``force`` (3,) [N], global, on body ``body`` (static): the
    tangential force that holds a vehicle's speed in its steady curving state
    (:mod:`jaxrail.stability.curving`)."""

    body: int = eqx.field(static=True)
    force: jnp.ndarray = eqx.field(converter=f64)

    def add_to(self, t, qdot, forces):
        """``forces`` (n, 3) [N] with the force added on its body."""
        return forces.at[self.body].add(self.force)


def check_drive(drive: SpeedDrive, n_bodies: int) -> None:
    """A clear error, before compiling, for a drive on a body the system lacks or with
    numbers that are not usable."""
    if not 0 <= drive.body < n_bodies:
        raise ValueError(f"the speed drive's body {drive.body} is not one of the system's "
                         f"{n_bodies} bodies")
    values = {name: np.asarray(getattr(drive, name)) for name in
              ("speed", "mass", "deceleration", "hold", "time_constant")}
    for name, value in values.items():
        if not np.all(np.isfinite(value)):
            raise ValueError(f"the speed drive's {name} must be finite, got {value}")
    for name in ("mass", "time_constant"):
        if np.any(values[name] <= 0.0):
            raise ValueError(f"the speed drive's {name} must be positive, got {values[name]}")
    if np.any(values["hold"] < 0.0):
        raise ValueError(f"the speed drive's hold must be >= 0 s, got {values['hold']}")
