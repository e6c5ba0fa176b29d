"""Simulation of a vehicle on a track: initial equilibrium, integration, outputs.

``simulate(vehicle, params, track, t1, speed=..., misalignment=...)`` puts the vehicle
at rest on its wheels (:func:`jaxrail.vehicles.initial_state`), integrates the
equations of motion (eq. 19 with Baumgarte stabilisation) with the wheel-rail loads of
every wheelset by diffrax, and returns a :class:`SimulationResult`: body states at the
output times, the contact details of every wheel and patch recomputed from them, and a
status. A run stops early, keeping its results so far, when a wheel derails (a
wheelset moves sideways or a wheel rises beyond the limits of
:class:`DerailmentLimits`) or the integration fails (non-finite state, step size
collapse, too many steps).

Solver: Tsit5 with a PID step-size controller by default, or the IMEX method of
:mod:`jaxrail.multibody.imex` (``SolverOptions(integrator="imex")``); the measurements that
chose them are in docs/simulation.md.

One job per module: :mod:`.options` (the settings), :mod:`.result` (what a run
returns), :mod:`.integrate` (:func:`solve`, the traceable core), :mod:`.outputs` (the
outputs recomputed from the saved states), :mod:`.run` (:func:`simulate`: compile once
through :mod:`jaxrail.compilation`, time, warn at the track's ends) and
:mod:`.single_wheelset` (a free wheelset rolled along the track).
"""

from ..compilation import PROGRAMS_KEPT as PROGRAMS_KEPT
# the compile layer's entry point under its former private name, for scripts that
# still import it from here (jaxrail's own packages use jaxrail.compilation)
from ..compilation import compile_program as _compile  # noqa: F401
from .integrate import evaluations_per_step as evaluations_per_step
from .integrate import solve as solve
from .options import INTEGRATORS as INTEGRATORS
from .options import DerailmentLimits as DerailmentLimits
from .options import SolverOptions as SolverOptions
from .result import SimulationResult as SimulationResult
from .result import WheelOutputs as WheelOutputs
from .run import run_span as run_span
from .run import simulate as simulate
from .run import warn_beyond_track as warn_beyond_track
from .single_wheelset import simulate_single_wheelset as simulate_single_wheelset

__all__ = ["DerailmentLimits", "INTEGRATORS", "PROGRAMS_KEPT", "SimulationResult",
           "SolverOptions", "WheelOutputs", "evaluations_per_step", "run_span", "simulate",
           "simulate_single_wheelset", "solve", "warn_beyond_track"]
