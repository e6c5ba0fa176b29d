"""Track irregularities: the four channels that displace each rail from its design place.

Channels, each a function of the arc length ``s`` [m] of the design centreline, in
metres inside the library (files and the command line speak millimetres):

- ``alignment`` a: lateral displacement of the track centre, along the canted track
  frame's ``n`` (positive **left**);
- ``vertical`` v: vertical displacement of the track centre, along ``b`` (positive up);
- ``cross_level`` c: height of the **left** rail over the right one [m], measured over
  the rail-centre distance (1.5 m), on top of the design cant;
- ``gauge`` g: widening of the gauge [m] (positive: the rails further apart).

Each rail's profile origin moves in the plane of its design cross-section by

    lateral:  y_L = a + g / 2,   y_R = a - g / 2      (along n, positive left)
    vertical: z_L = v + c / 2,   z_R = v - c / 2      (along b, positive up)

that is ``y = a + side g / 2``, ``z = v + side c / 2`` with ``side`` +1 for the left
rail and -1 for the right. The rails are translated, not rotated: their tangent and
cant stay the design frame's (the slopes of irregularities are a few mrad at most; the
wheel's yaw and roll relative to the design frame carry the rest of the geometry).

:class:`Irregularity` holds the channels as samples on a uniform grid in ``s`` and
interpolates them by cubic Hermite polynomials with central-difference slopes
(Catmull-Rom: C1, exact for quadratics, four samples per evaluation). Beyond the
sampled span each channel keeps its end value. ``scale`` multiplies every channel:
the irregularity is differentiable in its amplitude, and a batch of realisations is a
batch of ``values`` (``jax.vmap``). Spectra, measured files and isolated defects all
become an :class:`Irregularity` (:mod:`.spectra`, :mod:`.measured`, :mod:`.defects`).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._float64 import f64

CHANNELS = ("alignment", "vertical", "cross_level", "gauge")
"""The channels, in the order of :attr:`Irregularity.values`' columns."""


class Irregularity(eqx.Module):
    """Irregularity channels sampled on a uniform grid of arc length (traced: a new
    realisation of the same size does not recompile).

    Fields:
        values: (N, 4) channels at ``start + step * k`` [m], columns :data:`CHANNELS`.
        start: arc length of the first sample [m].
        step: sample spacing [m] (> 0).
        scale: factor on every channel [-] (1: as sampled).
    """

    values: Float[Array, "n 4"] = eqx.field(converter=f64)
    start: Float[Array, ""] = eqx.field(converter=f64)
    step: Float[Array, ""] = eqx.field(converter=f64)
    scale: Float[Array, ""] = eqx.field(converter=f64, default=1.0)

    def __check_init__(self):
        shape = np.shape(self.values)
        if len(shape) < 2 or shape[-1] != len(CHANNELS) or shape[-2] < 2:
            raise ValueError(f"Irregularity values must have shape (N >= 2, {len(CHANNELS)}) "
                             f"(columns {', '.join(CHANNELS)}), got {shape}")

    @property
    def end(self) -> Float[Array, ""]:
        """Arc length of the last sample [m]."""
        return self.start + self.step * (self.values.shape[-2] - 1)

    def at(self, s) -> Float[Array, "4"]:
        """The four channels [m] at arc length ``s`` [m] (scalar), times ``scale``."""
        count = self.values.shape[0]
        u = jnp.clip((jnp.asarray(s, jnp.float64) - self.start) / self.step, 0.0, count - 1.0)
        i = jnp.clip(jnp.floor(u), 0, count - 2)
        t = u - i
        rows = jnp.clip(i.astype(jnp.int32) + jnp.arange(-1, 3), 0, count - 1)
        p0, p1, p2, p3 = self.values[rows]
        # Catmull-Rom: Hermite with slopes (p2 - p0) / 2 and (p3 - p1) / 2
        t2, t3 = t * t, t * t * t
        value = (p1 + 0.5 * t * (p2 - p0) + t2 * (p0 - 2.5 * p1 + 2.0 * p2 - 0.5 * p3)
                 + t3 * (1.5 * (p1 - p2) + 0.5 * (p3 - p0)))
        return self.scale * value

    def rail_displacement(self, s, side) -> tuple[Float[Array, ""], Float[Array, ""]]:
        """``(lateral, vertical)`` [m] of the ``side`` rail (+1 left, -1 right) at ``s``
        [m] (:func:`rail_offsets`)."""
        return rail_offsets(self.at(s), side)


def rail_offsets(channels, side):
    """``(lateral, vertical)`` [m] of the ``side`` rail (+1 left, -1 right; an array of
    sides gives one of each) from the four ``channels`` (4,) [m]: ``a + side g / 2``
    along the track's ``n``, ``v + side c / 2`` along ``b``."""
    a, v, c, g = channels
    return a + 0.5 * side * g, v + 0.5 * side * c


def sampled(values, start: float, step: float, scale: float = 1.0) -> Irregularity:
    """:class:`Irregularity` from host samples ``values`` (N, 4) [m] with checks that name
    what is wrong (non-finite values, a step that is not positive)."""
    values = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(values)):
        raise ValueError("irregularity values must be finite")
    if not float(step) > 0.0:
        raise ValueError(f"irregularity step must be > 0 m, got {step}")
    if not float(scale) >= 0.0:
        raise ValueError(f"irregularity amplitude scale must be >= 0, got {scale}")
    return Irregularity(values, start, step, scale)
