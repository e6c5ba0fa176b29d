"""Quasi-static wheel-rail geometry: contact point functions, rolling radius
difference, equivalent conicity (EN 15302)."""

from .conicity import equivalent_conicity as equivalent_conicity
from .quasistatic import WheelsetGeometry as WheelsetGeometry
from .quasistatic import wheelset_geometry as wheelset_geometry

__all__ = ["equivalent_conicity", "wheelset_geometry", "WheelsetGeometry"]
