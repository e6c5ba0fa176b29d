"""Constrained rigid multibody systems: Cartesian coordinates with Euler parameters
(Nikravesh), joints as constraints, force elements, and eq. (19) with Baumgarte
stabilisation integrated by diffrax. See docs/multibody.md.

Static structure (`System`) and traced parameters (`SystemParams`) come from
`build_system`; a solve takes them with the loads on the bodies as one term
(`SystemLoads`, or any `AbstractLoads`); the Euler-parameter helpers are in
`jaxrail.multibody.quaternion`.
"""

from . import quaternion as quaternion
from .bodies import BodyParams as BodyParams
from .bodies import RigidBody as RigidBody
from .bodies import angular_velocity as angular_velocity
from .bodies import body_pose as body_pose
from .bodies import join_coordinates as join_coordinates
from .bodies import point_position as point_position
from .bodies import point_velocity as point_velocity
from .bodies import split_coordinates as split_coordinates
from .bodies import velocities_from_twists as velocities_from_twists
from .forces import Bushing as Bushing
from .forces import BushingParams as BushingParams
from .forces import BumpStop as BumpStop
from .forces import BumpStopParams as BumpStopParams
from .forces import SpringDamper as SpringDamper
from .forces import SpringDamperParams as SpringDamperParams
from .anti_roll_bar import AntiRollBar as AntiRollBar
from .anti_roll_bar import AntiRollBarParams as AntiRollBarParams
from .friction_damper import FrictionDamper as FrictionDamper
from .friction_damper import FrictionDamperParams as FrictionDamperParams
from .table_spring import TableSpring as TableSpring
from .table_spring import TableSpringParams as TableSpringParams
from .traction_rod import TractionRod as TractionRod
from .traction_rod import TractionRodParams as TractionRodParams
from .joints import GROUND as GROUND
from .joints import Fixed as Fixed
from .joints import JointParams as JointParams
from .joints import Prismatic as Prismatic
from .joints import Revolute as Revolute
from .joints import Spherical as Spherical
from .system import System as System
from .system import SystemParams as SystemParams
from .system import build_system as build_system
from .equations import acceleration_response as acceleration_response
from .equations import accelerations as accelerations
from .equations import accelerations_dense as accelerations_dense
from .equations import constraints as constraints
from .equations import element_rates as element_rates
from .equations import generalized_forces as generalized_forces
from .equations import initial_element_states as initial_element_states
from .equations import initial_state as initial_state
from .equations import mass_matrix as mass_matrix
from .equations import quadratic_velocity as quadratic_velocity
from .diagnostics import angular_momentum as angular_momentum
from .diagnostics import constraint_violation as constraint_violation
from .diagnostics import dissipated_power as dissipated_power
from .diagnostics import kinetic_energy as kinetic_energy
from .diagnostics import potential_energy as potential_energy
from .projection import consistent_initial_conditions as consistent_initial_conditions
from .projection import project_state as project_state
from .loads import AbstractLoads as AbstractLoads
from .loads import FixedLoads as FixedLoads
from .loads import SystemLoads as SystemLoads
from .integrate import rhs as rhs
from .integrate import simulate_system as simulate_system
from .state import State as State
from ._when import computed_when as computed_when
from .elements_series import AirSpring as AirSpring
from .elements_series import MaxwellDamper as MaxwellDamper

__all__ = ["AbstractLoads", "acceleration_response", "accelerations",
           "accelerations_dense", "AirSpring", "dissipated_power", "element_rates",
           "FixedLoads", "initial_element_states", "initial_state", "MaxwellDamper",
           "State", "angular_momentum", "angular_velocity", "body_pose", "BodyParams",
           "build_system", "BumpStop", "BumpStopParams", "Bushing", "BushingParams",
           "computed_when", "consistent_initial_conditions", "constraint_violation",
           "constraints",
           "Fixed", "generalized_forces", "GROUND", "join_coordinates", "JointParams",
           "kinetic_energy", "mass_matrix", "point_position", "point_velocity",
           "potential_energy", "Prismatic", "project_state", "quadratic_velocity",
           "quaternion", "Revolute", "rhs", "RigidBody", "simulate_system",
           "Spherical", "split_coordinates", "SpringDamper", "SpringDamperParams",
           "System", "SystemLoads", "SystemParams", "velocities_from_twists",
           "AntiRollBar", "AntiRollBarParams", "FrictionDamper",
           "FrictionDamperParams", "TableSpring", "TableSpringParams", "TractionRod",
           "TractionRodParams"]
