"""The wear of one contact patch: its FASTSIM elements (:mod:`.fastsim`) through a wear
law (:mod:`.laws`), summed per strip across the patch."""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._constants import STEEL_POISSON, STEEL_SHEAR_MODULUS
from .fastsim import ELEMENTS, STRIPS, fastsim_patch


class PatchWear(eqx.Module):
    """Wear rates of one patch (vmap for more).

    Fields: strip_offset (strips,) [m] the strips' centres across the patch, along the
    contact frame's lateral axis ``l``; strip_rate (strips,) [m^3/s] the wear volume
    rate of each strip (wheel and rail alike: the law gives the volume each loses);
    extrapolated_rate [m^3/s] the part of the total from elements beyond the law's
    published range; slip_area [m^2] the area of the slip elements; area [m^2].
    """

    strip_offset: Float[Array, " strips"]
    strip_rate: Float[Array, " strips"]
    extrapolated_rate: Float[Array, ""]
    slip_area: Float[Array, ""]
    area: Float[Array, ""]

    @property
    def rate(self):
        """Total wear volume rate [m^3/s]."""
        return jnp.sum(self.strip_rate, axis=-1)


def patch_wear(law, normal_force, a, b, creepage_x, creepage_y, spin, friction, speed,
               G=STEEL_SHEAR_MODULUS, nu=STEEL_POISSON, strips: int = STRIPS,
               elements: int = ELEMENTS) -> PatchWear:
    """:class:`PatchWear` of one patch: normal force [N], Hertz semi-axes a, b [m],
    creepages [-] and spin [1/m], friction [-], rolling speed V [m/s] (|V| is used), G
    [Pa], nu [-]; ``law`` a wear law of :mod:`jaxrail.wear.laws`."""
    grid = fastsim_patch(normal_force, a, b, creepage_x, creepage_y, spin, friction, G, nu,
                         strips, elements)
    speed = jnp.abs(jnp.asarray(speed, dtype=jnp.float64))
    rate = law.volume_rate(grid, speed)
    outside = law.extrapolated(grid, speed)
    return PatchWear(strip_offset=grid.strip_y, strip_rate=jnp.sum(rate, axis=-1),
                     extrapolated_rate=jnp.sum(jnp.where(outside, rate, 0.0)),
                     slip_area=jnp.sum(jnp.where(grid.stick, 0.0, grid.area)),
                     area=jnp.sum(grid.area))
