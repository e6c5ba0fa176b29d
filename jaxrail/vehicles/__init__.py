"""Vehicles: wheel-rail coupling of wheelsets (the vehicle models follow)."""

from .wheel_rail import ContactParameters as ContactParameters
from .wheel_rail import PatchForces as PatchForces
from .wheel_rail import wheelset_contact_loads as wheelset_contact_loads
