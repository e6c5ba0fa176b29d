"""The traction rod: a link between a bogie and the carbody (or a wheelset and a bogie
frame) that transmits the longitudinal traction and braking forces.

A rod with a rubber bushing at each end acts along the line between its end points:
the rod and its two bushings are springs in series, given here as one axial stiffness
k = 1 / (1 / k_rod + 1 / k_bushing,1 + 1 / k_bushing,2) [N/m] (the steel rod is far
stiffer than its bushings, which set k), with the bushings' damping c [N s/m] and the
rod's free length L0 [m], the distance between the end points at which it carries no
load. Its coordinate is the length L = |r_Pj - r_Pi|, its law and energy the
spring-damper's (``forces._spring_coords``, ``_spring_law``, ``_spring_potential``):

    F = k (L - L0) + c Ldot   (tension positive),   V = k (L - L0)^2 / 2.

Being a pin-jointed link it carries only axial load: the bushings' small radial and
torsional stiffness is left to other elements (a `Bushing` where it matters). Its own
kind and description keep a vehicle's traction rods apart from its coil springs (one
entry of ``params.forces`` to study or identify them by).
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, Float

from ._values import checked_scalar, element_label, float64_array, point_arrays


@dataclasses.dataclass(frozen=True)
class TractionRod:
    """Traction rod between point_i of body i and point_j of body j (body frames).

    stiffness k [N/m] >= 0: the axial stiffness of rod and end bushings in series;
    free_length L0 [m] > 0: the unloaded distance between the end points (the points
    must not meet); damping c [N s/m] >= 0. Tension positive.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    stiffness: float
    free_length: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "traction_rod"


class TractionRodParams(eqx.Module):
    """(k, 3) end points [m]; (k,) stiffness [N/m], damping [N s/m], free_length [m]
    (the fields of ``SpringDamperParams``, whose law it shares)."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    stiffness: Float[Array, " k"]
    damping: Float[Array, " k"]
    free_length: Float[Array, " k"]


def params(specs, what) -> TractionRodParams:
    """Checks the descriptions (k, c >= 0, L0 > 0) and makes their traced parameters."""
    for n, spec in enumerate(specs):
        label = element_label(what, spec, n)
        checked_scalar(spec.stiffness, f"{label}: stiffness")
        checked_scalar(spec.damping, f"{label}: damping")
        checked_scalar(spec.free_length, f"{label}: free_length", positive=True)
    return TractionRodParams(
        **point_arrays(specs),
        stiffness=float64_array([s.stiffness for s in specs]),
        damping=float64_array([s.damping for s in specs]),
        free_length=float64_array([s.free_length for s in specs]),
    )
