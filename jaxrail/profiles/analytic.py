"""Simple analytic profiles with closed-form contact geometry, for tests and studies.

- :class:`ConicalProfile`: a coned wheel, ``height(y) = -tan(cone_angle) * y`` (the
  rolling radius shrinks toward the field side, as on a real tread). With it a single
  wheelset hunts with Klingel's wavelength.
- :class:`CircularProfile`: a circular arc of radius ``radius``, convex upward as a rail
  head (``height = sqrt(R^2 - y^2) - R``) or convex toward the rail as a wheel
  (``height = R - sqrt(R^2 - y^2)``, ``wheel=True``), centred at ``y = 0``.

Conventions are those of :mod:`jaxrail.profiles._base` (``y`` toward the field side).
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from ._base import Profile, WheelProfile


class ConicalProfile(Profile):
    """Straight-coned wheel tread over ``[-half_width, half_width]`` [m]."""

    cone_angle: Float[Array, ""]
    half_width: float = eqx.field(static=True, default=0.06)

    def __init__(self, cone_angle: float = 0.05, half_width: float = 0.06):
        require_float64("ConicalProfile")
        self.cone_angle = jnp.asarray(cone_angle, dtype=jnp.float64)
        self.half_width = float(half_width)

    @property
    def domain(self) -> tuple[float, float]:
        return (-self.half_width, self.half_width)

    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        return -jnp.tan(self.cone_angle) * jnp.asarray(y, dtype=jnp.float64)


class CircularProfile(Profile):
    """Circular arc of radius ``radius`` [m] centred on ``y = 0`` over
    ``[-half_width, half_width]`` (half_width < radius)."""

    radius: Float[Array, ""]
    half_width: float = eqx.field(static=True, default=0.03)
    wheel: bool = eqx.field(static=True, default=False)

    def __init__(self, radius: float = 0.3, half_width: float = 0.03, wheel: bool = False):
        require_float64("CircularProfile")
        if not 0.0 < half_width < radius:
            raise ValueError(f"CircularProfile: need 0 < half_width < radius, got {half_width}, {radius}")
        self.radius = jnp.asarray(radius, dtype=jnp.float64)
        self.half_width = float(half_width)
        self.wheel = bool(wheel)

    @property
    def domain(self) -> tuple[float, float]:
        return (-self.half_width, self.half_width)

    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        y = jnp.asarray(y, dtype=jnp.float64)
        sag = self.radius - jnp.sqrt(self.radius**2 - y * y)
        return sag if self.wheel else -sag


def conical_wheel(cone_angle: float = 0.05, nominal_radius: float = 0.46) -> WheelProfile:
    """A coned wheel (one surface) of cone angle ``cone_angle`` [rad]."""
    return WheelProfile(
        surfaces=(ConicalProfile(cone_angle),),
        nominal_radius=jnp.asarray(nominal_radius, dtype=jnp.float64),
        name=f"cone {cone_angle:g} rad",
    )
