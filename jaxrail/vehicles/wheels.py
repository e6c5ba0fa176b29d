"""Wheel profiles named in a vehicle file, and the back-to-back distance.

A profile is a built-in name (``S1002``, ``S1002-simplified``) or a profile file
(``.prw``, or two-column text in mm in jaxrail's conventions), relative to the vehicle
file's folder. The rail profile is the track's (:class:`jaxrail.track.Rails`).

**Back-to-back.** The code places each wheel's profile origin, its taping line, at
:data:`~jaxrail.track.rails.HALF_TAPING_DISTANCE` (0.75 m) from the wheelset centre
along the axle, and the EN 13715 profiles have their flange back
:data:`FLANGE_BACK` (70 mm) inside the taping line: a back-to-back distance of
2 (0.75 - 0.070) = 1.360 m. A file's ``back_to_back`` B moves each wheel's profile
outward by ``B / 2 + 0.070 - 0.75`` (:class:`ShiftedProfile`): the flange backs are then
B apart and the nominal radius is that of the moved taping line. At 1.360 m the
profile is used as it is.
"""

from pathlib import Path

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float
import equinox as eqx

from ..profiles import Profile, WheelProfile, read_profile, s1002, simplified_s1002
from ..track.rails import HALF_TAPING_DISTANCE

FLANGE_BACK = 0.070  # [m] from the flange back to the taping line (EN 13715)
SHIFT_TOLERANCE = 1e-12  # [m] below which a back-to-back distance moves nothing
WHEELS = {"s1002": s1002, "s1002-simplified": simplified_s1002}


class ShiftedProfile(Profile):
    """``surface`` moved by ``shift`` [m] toward the field side (static):
    ``height(y) = surface.height(y - shift)``."""

    surface: Profile
    shift: float = eqx.field(static=True)

    @property
    def domain(self) -> tuple[float, float]:
        lo, hi = self.surface.domain
        return lo + self.shift, hi + self.shift

    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        return self.surface.height(jnp.asarray(y, dtype=jnp.float64) - self.shift)

    def height_derivatives(self, y):
        return self.surface.height_derivatives(jnp.asarray(y, dtype=jnp.float64) - self.shift)


def profile_shift(back_to_back: float) -> float:
    """Outward move [m] of each wheel's profile for a back-to-back distance [m]."""
    return 0.5 * back_to_back + FLANGE_BACK - HALF_TAPING_DISTANCE


def wheel_profile(name: str, nominal_radius: float, back_to_back=None,
                  folder: Path | None = None) -> WheelProfile:
    """The wheel profile ``name`` with ``nominal_radius`` [m], moved for
    ``back_to_back`` [m] (module docstring). ValueError for an unknown name."""
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"a profile is a name or a file, got {name!r}")
    key = name.strip().lower()
    if key in WHEELS:
        wheel = WHEELS[key](nominal_radius=nominal_radius)
    else:
        path = Path(name) if folder is None else Path(folder) / name
        if not path.exists():
            raise ValueError(f"unknown wheel profile {name!r}: use "
                             f"{', '.join(n.upper() for n in WHEELS)} or a profile file "
                             f"({path} does not exist)")
        wheel = read_profile(path, kind="wheel", nominal_radius=nominal_radius)
    shift = 0.0 if back_to_back is None else profile_shift(back_to_back)
    if abs(shift) <= SHIFT_TOLERANCE:
        return wheel
    surfaces = tuple(ShiftedProfile(s, float(shift)) for s in wheel.surfaces)
    return WheelProfile(surfaces, wheel.nominal_radius,
                        f"{wheel.name} at {1e3 * back_to_back:g} mm back-to-back")

