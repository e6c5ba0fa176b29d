"""A rail vehicle: a multibody system some of whose bodies are wheelsets on the track.

:class:`Vehicle` is the static part (the multibody structure, which bodies are
wheelsets and axleboxes, the search settings); :class:`VehicleParams` is the pytree
of every number that may be changed, batched or differentiated without recompiling
(masses, suspension, contact parameters, the wheel profile, and the layout that sets
the wheelbase). The rails, their profile and the gauge, are the track's
(:class:`jaxrail.track.Rails`).

Vehicle frame (used for the nominal layout): x forward, y left, z up, origin on the
track centreline at the reference point of the vehicle (the carbody centre), z = 0
at the rail tops.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..contact.search import SearchConfig
from ..multibody import System, SystemParams
from ..multibody import quaternion as qt
from ..profiles import WheelProfile
from .wheel_rail import ContactParameters


class Vehicle(eqx.Module):
    """Static structure of a vehicle: what changing recompiles.

    Fields:
        name: label for outputs.
        system: multibody structure (:func:`jaxrail.multibody.build_system`).
        wheelsets: indices of the wheelset bodies, leading first (tuple of ints).
        config: contact search settings.
        axleboxes: indices of bodies that ride on the wheelsets (same order as
            ``wheelsets``, or empty): they start at their wheelset's height and roll.
    """

    name: str = eqx.field(static=True)
    system: System
    wheelsets: tuple[int, ...] = eqx.field(static=True)
    config: SearchConfig = eqx.field(static=True, default=SearchConfig())
    axleboxes: tuple[int, ...] = eqx.field(static=True, default=())

    @property
    def n_wheelsets(self) -> int:
        return len(self.wheelsets)


class VehicleParams(eqx.Module):
    """Every number of a vehicle, traced (changing one never recompiles; each can be
    batched or differentiated).

    Fields:
        system: masses, inertias, joints, suspension (:class:`jaxrail.multibody.SystemParams`).
        contact: :class:`ContactParameters`.
        wheel: profile of every wheel.
        layout: (n, 3) nominal centre of each body in the vehicle frame [m] at rest
            (wheelset heights are placeholders: the static equilibrium on the rails
            sets them, and shifts the sprung bodies with them).
    """

    system: SystemParams
    contact: ContactParameters
    wheel: WheelProfile
    layout: Float[Array, "n 3"] = eqx.field(converter=lambda x: jnp.asarray(x, jnp.float64))

    @property
    def nominal_radius(self):
        """Nominal wheel radius [m]."""
        return self.wheel.nominal_radius


def wheelset_states(vehicle: Vehicle, q, qdot):
    """Positions (W, 3), rotations (W, 3, 3), velocities (W, 3) and angular velocities
    (W, 3) of the wheelsets, global [m, -, m/s, rad/s]."""
    index = np.asarray(vehicle.wheelsets)
    body = q.reshape(-1, 7)[index]
    rate = qdot.reshape(-1, 7)[index]
    rotation = jax.vmap(qt.rotation_matrix)(body[:, 3:])
    omega = 2.0 * jnp.einsum("wij,wj->wi", jax.vmap(qt.e_matrix)(body[:, 3:]), rate[:, 3:])
    return body[:, :3], rotation, rate[:, :3], omega
