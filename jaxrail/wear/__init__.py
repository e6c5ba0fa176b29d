"""Wheel and rail wear: where and how fast they wear, the profile a route wears a wheel
into, and the gradient of wear (docs/wear.md).

- :mod:`.fastsim`: a contact patch in strips and elements (Kalker's FASTSIM): stick and
  slip areas, traction, sliding velocity.
- :mod:`.laws`: Archard's law with the KTH wear map, the USFD Tgamma/A function.
- :mod:`.patch_wear`, :mod:`.distribution`: a patch's wear per strip, spread over the
  wheel and rail profiles' lateral coordinates.
- :mod:`.run_wear`: the wear of a run, per wheel, integrated over its output times.
- :mod:`.route`, :mod:`.evolution`: a route of sections, its wear per km, and the wheel
  profile's evolution over a distance (``jaxrail wear``).
- :mod:`.sensitivity`: the derivatives of wear in named parameters, through the runs.
"""

from .distribution import deposit as deposit
from .distribution import lateral_grid as lateral_grid
from .evolution import RouteWear as RouteWear
from .evolution import evolve as evolve
from .evolution import route_wear as route_wear
from .fastsim import PatchGrid as PatchGrid
from .fastsim import fastsim_patch as fastsim_patch
from .laws import MODELS as MODELS
from .laws import USFD as USFD
from .laws import ArchardKTH as ArchardKTH
from .laws import wear_law as wear_law
from .patch_wear import PatchWear as PatchWear
from .patch_wear import patch_wear as patch_wear
from .route import Route as Route
from .route import Section as Section
from .route import load_route as load_route
from .route import parse_route as parse_route
from .run_wear import RunWear as RunWear
from .run_wear import run_wear as run_wear
from .sensitivity import WearGradient as WearGradient
from .sensitivity import wear_gradient as wear_gradient

__all__ = ["MODELS", "USFD", "ArchardKTH", "PatchGrid", "PatchWear", "Route", "RouteWear",
           "RunWear", "Section", "WearGradient", "deposit", "evolve", "fastsim_patch",
           "lateral_grid", "load_route", "parse_route", "patch_wear", "route_wear",
           "run_wear", "wear_gradient", "wear_law"]
