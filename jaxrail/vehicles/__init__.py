"""Vehicles: wheel-rail coupling of wheelsets, a single free wheelset (the trailer
model follows)."""

from .single_wheelset import simulate_single_wheelset as simulate_single_wheelset
from .single_wheelset import touching_height as touching_height

from .wheel_rail import ContactParameters as ContactParameters
from .wheel_rail import PatchForces as PatchForces
from .wheel_rail import wheelset_contact_loads as wheelset_contact_loads
