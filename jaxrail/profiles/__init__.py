"""Wheel and rail profiles (conventions in :mod:`jaxrail.profiles._base`)."""

from ._base import Profile as Profile
from ._base import WheelProfile as WheelProfile
from ._base import below_tangent as below_tangent
from ._base import frozen as frozen
from .files import read_profile as read_profile
from .files import sample_profile as sample_profile
from .files import write_profile_csv as write_profile_csv
from .measures import flange_angle as flange_angle
from .measures import flange_height as flange_height
from .measures import flange_qr as flange_qr
from .measures import flange_thickness as flange_thickness
from .measures import gauge_point as gauge_point
from .measures import highest_point as highest_point
from .measures import rail_offset as rail_offset
from .s1002 import S1002 as S1002
from .s1002 import s1002 as s1002
from .simplified import SimplifiedFlange as SimplifiedFlange
from .simplified import SimplifiedTread as SimplifiedTread
from .simplified import simplified_s1002 as simplified_s1002
from .tabulated import TabulatedProfile as TabulatedProfile
from .tabulated import tabulated_rail as tabulated_rail
from .tabulated import tabulated_wheel as tabulated_wheel
from .uic60 import UIC60 as UIC60
from .uic60 import uic60 as uic60

__all__ = ["below_tangent", "flange_angle", "flange_height", "flange_qr", "flange_thickness",
           "frozen", "gauge_point", "highest_point", "Profile", "rail_offset", "read_profile",
           "S1002", "s1002", "sample_profile", "simplified_s1002", "SimplifiedFlange",
           "SimplifiedTread", "tabulated_rail", "tabulated_wheel", "TabulatedProfile",
           "UIC60", "uic60", "WheelProfile", "write_profile_csv"]
