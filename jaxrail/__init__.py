"""jaxrail: differentiable railway vehicle dynamics in JAX.

The names a user starts from are here (:data:`__all__`); each is imported from its
subpackage on first use, so ``import jaxrail`` stays cheap and starts nothing (JAX's
backend included: ``jax.distributed.initialize`` can still follow it). The functions
``simulate`` and ``identify`` share their names with their modules: call
``jaxrail.simulation.simulate`` and ``jaxrail.identification.identify``.
"""

import importlib

from ._devices import use_host_devices as use_host_devices
from ._float64 import enable_float64 as enable_float64
from ._float64 import require_float64 as require_float64

__version__ = "0.1.0"

_LAZY = {
    "simulate": "simulation", "solve": "simulation", "SolverOptions": "simulation",
    "DerailmentLimits": "simulation", "SimulationResult": "simulation",
    "load_scenario": "scenarios", "parse_scenario": "scenarios", "run_scenario": "scenarios",
    "trailer": "vehicles", "bogie": "vehicles", "single_wheelset": "vehicles",
    "ContactParameters": "vehicles", "contact_model": "vehicles",
    "s1002": "profiles", "simplified_s1002": "profiles", "uic60": "profiles",
    "read_profile": "profiles", "rail_offset": "profiles",
    "Track": "track", "straight_track": "track", "Straight": "track",
    "Transition": "track", "Arc": "track", "Rails": "track",
    "identify": "identification", "Measurements": "identification",
    "read_measurements": "identification",
    "run_montecarlo": "montecarlo", "run_samples": "montecarlo",
    "summarize": "results", "write_results": "results", "read_results": "results",
    "use_loop_kernels": "compilation.loop_kernels",
}
__all__ = ["__version__", "enable_float64", "require_float64", "use_host_devices",
           *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'jaxrail' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
