"""A co-moving flexible track: the rail under each wheel on a lateral and a vertical
mass-spring-damper to ground, moving along the track with its wheelset.

This is GENSYS's standard track model (Lau & Hoff's "moving mass model"): per
wheelset and per rail (left, right), a lateral and a vertical rail mass (the rail and
its share of the sleeper) on the pad and ballast, reduced to one spring and one damper
per direction. Its coordinates are the rail's deflections ``w`` [m] from its unloaded
place, along the design track frame's canted ``n`` (lateral, positive left) and ``b``
(vertical, positive up), at the wheelset's section:

    m w'' = -k w - c w' + F_rail,

``F_rail`` the wheels' force on that rail along the same axis. The rail's own weight is
carried by its support and is not counted: at rest under a wheel load Q the rail sits
``-Q / k`` low.

State layout: ``deflection`` and ``rate`` arrays of shape (W, 2, 2): wheelset (leading
first), rail (left, right), direction (lateral, vertical). The rail seam
(:mod:`jaxrail.track.rails`) adds the deflection to the rail's place; the contact's
creepages and penetration rate use the rail's velocity (:mod:`jaxrail.vehicles.loads`).
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._float64 import f64

# Defaults, one value per direction (lateral, vertical); sources in docs/track.md.
# Vertical: DLR's co-moving track (AdvancedNoise SimpleRailwayTrack): 165 kg on
# 7.5e7 N/m, which lies in the 63-82 MN/m of a UIC60 rail on Zhai et al.'s pads and
# ballast as a beam on an elastic foundation; damping 7.5e7 N/m times 0.92 ms, the
# low-frequency relaxation time (c/k) of Zhai's pad and ballast in series (DLR's damping
# value, 9.4e7 N s/m, is taken as a misprint). Lateral: the rail mass of the vertical
# direction, 5e7 N/m and 1e5 N s/m, the values usual in the literature (no primary
# source found: docs/track.md says so).
DEFAULT_MASS = (165.0, 165.0)  # [kg]
DEFAULT_STIFFNESS = (5.0e7, 7.5e7)  # [N/m]
DEFAULT_DAMPING = (1.0e5, 6.9e4)  # [N s/m]


class FlexibleTrack(eqx.Module):
    """The support of each rail under each wheel; arrays (2,): (lateral, vertical).

    Fields (traced, differentiable): mass [kg], stiffness [N/m], damping [N s/m].
    """

    mass: Float[Array, "2"] = eqx.field(converter=f64, default=DEFAULT_MASS)
    stiffness: Float[Array, "2"] = eqx.field(converter=f64, default=DEFAULT_STIFFNESS)
    damping: Float[Array, "2"] = eqx.field(converter=f64, default=DEFAULT_DAMPING)

    def accelerations(self, deflection, rate, rail_force):
        """``w''`` [m/s^2] of rails at ``deflection`` [m] and ``rate`` [m/s] under the
        wheels' ``rail_force`` [N], all (..., 2) (lateral, vertical)."""
        return (rail_force - self.stiffness * deflection - self.damping * rate) / self.mass

    def static_deflection(self, rail_force):
        """The rest deflection [m] under a constant ``rail_force`` [N] (..., 2)."""
        return rail_force / self.stiffness

