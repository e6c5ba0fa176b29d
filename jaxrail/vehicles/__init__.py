"""Vehicles: wheel-rail coupling of wheelsets, the paper's 11-body trailer, a loaded
bogie (half of it), a single free wheelset, and their initial static equilibrium;
any vehicle from a vehicle file (docs/vehicle-files.md)."""

from .bogie import bogie as bogie
from .initial import initial_state as initial_state
from .initial import wheelset_rest_pose as wheelset_rest_pose
from .single_wheelset import single_wheelset as single_wheelset
from .single_wheelset import touching_height as touching_height
from .trailer import read_vehicle_data as read_vehicle_data
from .trailer import static_loads as static_loads
from .trailer import trailer as trailer
from .trailer import trailer_values as trailer_values
from .vehicle import Vehicle as Vehicle
from .vehicle import VehicleParams as VehicleParams
from .from_file import vehicle_from_data as vehicle_from_data
from .from_file import vehicle_from_file as vehicle_from_file
from .from_file import vehicle_names as vehicle_names
from .loads import CONTACT_MODELS as CONTACT_MODELS
from .loads import OnlineContact as OnlineContact
from .loads import TableContact as TableContact
from .loads import contact_model as contact_model
from .loads import VehicleLoads as VehicleLoads
from .loads import contact_loads as contact_loads
from .loads import vehicle_accelerations as vehicle_accelerations
from .loads import wheelset_loads as wheelset_loads
from .wheel_rail import ContactParameters as ContactParameters
from .wheel_rail import PatchForces as PatchForces
from .wheel_rail import patch_loads as patch_loads
from .wheel_rail import wheelset_contact_loads as wheelset_contact_loads
from .parameters import PARAMETERS as PARAMETERS
from .parameters import get_values as get_values
from .parameters import parameter as parameter
from .parameters import set_values as set_values
from .parameters import set_values_and_track as set_values_and_track

__all__ = ["bogie", "contact_loads", "contact_model", "CONTACT_MODELS",
           "ContactParameters", "get_values", "initial_state", "OnlineContact",
           "parameter", "PARAMETERS", "patch_loads", "PatchForces",
           "read_vehicle_data", "set_values", "set_values_and_track", "single_wheelset",
           "static_loads", "TableContact", "touching_height",
           "trailer", "trailer_values", "Vehicle", "vehicle_accelerations",
           "vehicle_from_data", "vehicle_from_file", "vehicle_names",
           "VehicleLoads", "VehicleParams", "wheelset_contact_loads", "wheelset_loads",
           "wheelset_rest_pose"]
