"""The gradient of wear in named parameters (:mod:`jaxrail.vehicles.parameters`: the
primary longitudinal stiffness, friction, the wheelbase, ...) through the runs
themselves: forward-mode differentiation of the simulation and of
:func:`~jaxrail.wear.run_wear.run_wear` together, one tangent per parameter.

Differentiable because every step is: the integration (diffrax), the contact, the
FASTSIM elements (their stick/slip switch moves an element's traction continuously)
and the wear laws (the KTH map's edges blended, :mod:`jaxrail.wear.laws`). A run with
adaptive steps differentiates the steps it took; fixed steps make the wear a smooth
function of the parameters, which is what a comparison with finite differences needs.
"""

import dataclasses

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..compilation import compile_program
from ..simulation.integrate import solve
from ..vehicles.parameters import (check_contact_follows, get_values, set_values_and_track,
                                   vehicle_parameters)
from .distribution import lateral_grid
from .run_wear import run_wear

GRID_SPACING = 0.5e-3  # [m]


@dataclasses.dataclass
class WearGradient:
    """Wear per km of every wheel and its derivatives (host arrays, W wheelsets).

    names (k,); values (k,) the parameters' values; volume_per_km (W, 2) [mm^3/km];
    flange_per_km (W, 2) [mm^3/km] the part on the flange; d_volume_per_km,
    d_flange_per_km (W, 2, k) their derivatives [mm^3/km per parameter unit]."""

    names: tuple
    values: np.ndarray
    volume_per_km: np.ndarray
    flange_per_km: np.ndarray
    d_volume_per_km: np.ndarray
    d_flange_per_km: np.ndarray

    def relative(self):
        """(W, 2, k): d ln(volume per km) / d ln(parameter), the elasticities."""
        v = np.where(self.volume_per_km > 0, self.volume_per_km, np.nan)
        return self.d_volume_per_km * self.values / v[..., None]


@eqx.filter_jit
def _wear_and_tangents(vehicle, params, track, model, values, law, wheel_nodes, rail_nodes,
                       t_from, *, names, duration, speed, misalignment, options):
    def wear_of(v):
        p, t = set_values_and_track(vehicle, params, track, names, v)
        result = solve(vehicle, p, t, duration, speed, misalignment, options=options,
                       contact_model=model, adjoint=diffrax.ForwardMode())
        wear = run_wear(result, vehicle, p, law, wheel_nodes, rail_nodes, t_from=t_from)
        return jnp.stack([wear.per_km(wear.volume), wear.per_km(wear.flange_volume)])

    basis = jnp.eye(values.shape[0], dtype=values.dtype)
    primal, tangents = jax.vmap(lambda e: jax.jvp(wear_of, (values,), (e,)),
                                out_axes=(None, -1))(basis)
    return primal, tangents


def wear_gradient(scenario, names, law, contact=None, duration=None, t_from=0.0,
                  built=None, model=None, values=None) -> WearGradient:
    """:class:`WearGradient` of ``scenario``'s run (``duration`` [s], default the
    scenario's) in the parameters ``names`` at ``values`` (default the scenario's:
    the program compiles once for any values); wear through
    ``law`` counted from ``t_from`` [s]; ``contact`` the mode (default the scenario's),
    or ``model`` a contact model; ``built`` the scenario's ``build()``."""
    names = tuple(names)
    vehicle, params, track = scenario.build() if built is None else built
    known = vehicle_parameters(vehicle, params)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown}: use {sorted(known)}")
    mode = scenario.contact if contact is None else contact
    check_contact_follows(names, mode)
    if model is None:
        model = scenario.contact_model(vehicle, params, track, mode)
    duration = scenario.duration if duration is None else float(duration)
    if values is None:
        values = get_values(vehicle, params, names, track)
    values = jnp.asarray(values, dtype=jnp.float64)
    wheel_nodes = jnp.asarray(lateral_grid(params.wheel.surfaces[0].domain, GRID_SPACING))
    rail_nodes = jnp.asarray(lateral_grid(track.rails.profile.domain, GRID_SPACING))
    args = (vehicle, params, track, model, values, law, wheel_nodes, rail_nodes,
            jnp.asarray(t_from, dtype=jnp.float64))
    static = {"names": names, "duration": duration, "speed": scenario.speed,
              "misalignment": scenario.misalignment,
              "options": scenario.solver_options(duration)}
    compiled, _ = compile_program(_wear_and_tangents, *args, **static)
    primal, tangents = compiled(*args, **static)
    primal, tangents = np.asarray(primal), np.asarray(tangents)
    return WearGradient(names, np.asarray(values), primal[0], primal[1], tangents[0],
                        tangents[1])
