"""The wear per km of every wheel in steady curving and its gradient in named parameters:
the patches of the steady curving state (:mod:`jaxrail.stability.curving`) through
FASTSIM and a wear law, differentiated by the implicit function theorem
(:class:`jaxrail.stability.curving_wear.CurvingWear`, whose ``measure`` it is).

Unlike the wear of a run (:mod:`.sensitivity`), this is a smooth function of the
parameters: no transient, no window, only the steady state of the arc, which the
suspension and the contact set. It is the design sensitivity: how the wear of a curve
changes with a stiffness, the friction or the wheelbase.
"""

import jax
import jax.numpy as jnp

from ..stability.curving import SteadyCurving
from ..stability.curving_wear import CurvingWear
from .patch_wear import patch_wear


def wear_per_km(law):
    """``measure(patch_forces, params, speed)`` -> (W, 2) [mm^3/km]: each wheel's wear
    volume per km run at ``speed`` [m/s] from its patches ``(W, 2, P)``
    (:class:`~jaxrail.vehicles.wheel_rail.PatchForces`) through ``law``."""
    def measure(forces, params, speed):
        c = params.contact

        def one(n, a, b, xi, eta, phi):
            return patch_wear(law, n, a, b, xi, eta, phi, c.friction, speed,
                              c.shear_modulus, c.poisson).rate
        fields = (forces.normal_force, forces.semi_axis_a, forces.semi_axis_b,
                  forces.creepage_x, forces.creepage_y, forces.spin)
        rate = jax.vmap(one)(*(f.reshape(-1) for f in fields)).reshape(fields[0].shape)
        return jnp.sum(rate, axis=-1) / speed * 1e12  # m^3/s over m/s: m^3/m -> mm^3/km
    return measure


def steady_wear(vehicle, params, track, law, names=(), model=None) -> CurvingWear:
    """``steady_wear(...)(speed)`` -> :class:`~jaxrail.stability.curving_wear.CurvingWearPoint`
    whose ``wear_number_n`` is each wheel's wear per km [mm^3/km] in the steady curving
    state of ``vehicle`` on ``track`` (one arc) and ``gradient[name]`` its derivative."""
    return CurvingWear(SteadyCurving(vehicle, params, track, model), names,
                       measure=wear_per_km(law))
