"""Stability of a vehicle's steady motion: its modes against speed and the critical
speed where hunting sets in (docs/stability.md); the modes of a vehicle standing on the
track (docs/vehicles.md)."""

from .linear import Modes as Modes
from .linear import linear_system as linear_system
from .linear import modes as modes
from .critical import LinearStability as LinearStability
from .critical import SpeedPoint as SpeedPoint
from .standing import StandingMode as StandingMode
from .standing import VehicleModes as VehicleModes
from .standing import vehicle_modes as vehicle_modes
