"""jaxrail: differentiable railway vehicle dynamics in JAX."""

from ._devices import use_host_devices as use_host_devices
from ._float64 import enable_float64 as enable_float64
from ._float64 import require_float64 as require_float64

__version__ = "0.1.0"
