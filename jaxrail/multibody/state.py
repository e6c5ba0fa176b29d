"""The integrated state of a multibody system: one typed pytree, the ``y`` of diffrax.

:class:`State` holds the bodies' coordinates and velocities and, beside them, the
states that are not rigid bodies: a flexible track's rails (second order, integrated
with the bodies through ``external.coupled``) and the internal states of force
elements (first order, e.g. a Maxwell damper's piston displacement). Code asks a state
for what it holds by name (``state.track is None``), never by the length of a tuple.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float


def _float64(x):
    return jax.tree.map(lambda v: jnp.asarray(v, dtype=jnp.float64), x)


class State(eqx.Module):
    """The state of a multibody system.

    Fields:
        q: (7 n,) coordinates, each body's position [m] and Euler parameters (global).
        qdot: (7 n,) their rates [m/s, 1/s].
        track: the flexible track's rails ``(x, xdot)`` (arrays of one shape, [m],
            [m/s]), or None on rigid rails.
        elements: ``{kind: (k, r)}`` the internal states of the force elements of each
            kind that has some (``forces.FORCE_KINDS[kind].states`` = r); empty if none.
    """

    q: Float[Array, " n7"]
    qdot: Float[Array, " n7"]
    track: object = None
    elements: dict = eqx.field(default_factory=dict)

    @staticmethod
    def of(q, qdot, track=None, elements=None) -> "State":
        """A State of float64 arrays (``elements`` None: no internal states)."""
        return State(_float64(q), _float64(qdot), None if track is None else _float64(track),
                     {} if elements is None else _float64(dict(elements)))

    def with_bodies(self, q, qdot) -> "State":
        """This state with the bodies' coordinates and velocities replaced."""
        return State(q, qdot, self.track, self.elements)
