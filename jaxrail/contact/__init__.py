"""Wheel-rail contact: the paper's search (section 2), Hertz, normal laws, creep forces.

Functions share their module's name (``hertz``, ``polach``): ``jaxrail.contact.hertz``
is the function; import the module's other names with ``from jaxrail.contact.hertz
import ...``.
"""

from .creepage import creepages as creepages
from .hertz import HertzCoefficients as HertzCoefficients
from .hertz import HertzContact as HertzContact
from .hertz import convex_curvature as convex_curvature
from .hertz import hertz as hertz
from .hertz import hertz_coefficients as hertz_coefficients
from .hertz import hertz_from_curvatures as hertz_from_curvatures
from .hertz import hertz_stiffness as hertz_stiffness
from .kalker import kalker_coefficients as kalker_coefficients
from .normal import Eq17 as Eq17
from .normal import Flores as Flores
from .normal import Hertz as Hertz
from .normal import HuntCrossley as HuntCrossley
from .normal import LankaraniNikravesh as LankaraniNikravesh
from .normal import NormalLaw as NormalLaw
from .polach import PolachParameters as PolachParameters
from .polach import polach as polach
from .pose import wheelset_pose as wheelset_pose
from .search import ContactPatches as ContactPatches
from .search import SearchConfig as SearchConfig
from .search import deepest_depth as deepest_depth
from .search import search_vehicle as search_vehicle
from .search import search_wheel as search_wheel
from .search import search_wheelset as search_wheelset
from .table import ContactTable as ContactTable
from .table import TableGrid as TableGrid
from .table import build_contact_table as build_contact_table
from .table import table_patches as table_patches
from .table_cache import contact_table as contact_table

__all__ = ["build_contact_table", "contact_table", "ContactPatches", "ContactTable",
           "convex_curvature", "creepages", "deepest_depth", "Eq17", "Flores", "Hertz",
           "hertz", "hertz_coefficients", "hertz_from_curvatures", "hertz_stiffness",
           "HertzCoefficients", "HertzContact", "HuntCrossley", "kalker_coefficients",
           "LankaraniNikravesh", "NormalLaw", "polach", "PolachParameters",
           "search_vehicle", "search_wheel", "search_wheelset", "SearchConfig",
           "table_patches", "TableGrid", "wheelset_pose"]
