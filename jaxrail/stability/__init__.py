"""Stability of a vehicle's steady motion: its modes against speed and the critical
speed where hunting sets in (docs/stability.md)."""

from .linear import Modes as Modes
from .linear import linear_system as linear_system
from .linear import modes as modes
from .critical import LinearStability as LinearStability
from .critical import SpeedPoint as SpeedPoint
