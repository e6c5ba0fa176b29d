"""Design track geometry: layout, evaluation at arc length, rails and projection.

Conventions: global X, Y horizontal, Z up; the track is planar. Track frame
``[t n b]``: t along the direction of travel, n to the left, b up, rolled about t by
the cant (banked toward the inside of the curve). Curvature and cant are signed:
positive for a left curve. A track may carry irregularities
(:mod:`jaxrail.track.irregularity`) that move each rail from its design place. Its
:class:`Rails` are the rail profile and the offset that sets the gauge;
:mod:`jaxrail.track.rails` is the one place that says where the rail under a wheel is.
See docs/track.md.
"""

from .geometry import cant_angle as cant_angle
from .geometry import centreline_and_frame as centreline_and_frame
from .geometry import centreline_position as centreline_position
from .geometry import curvature as curvature
from .geometry import heading as heading
from .geometry import superelevation as superelevation
from .geometry import track_frame as track_frame
from .irregularity import CHANNELS as CHANNELS
from .irregularity import Irregularity as Irregularity
from .layout import Arc as Arc
from .layout import Straight as Straight
from .layout import Track as Track
from .layout import Transition as Transition
from .layout import curve_layout as curve_layout
from .layout import straight_track as straight_track
from .projection import from_track_coordinates as from_track_coordinates
from .projection import project as project
from .projection import project_onto_centreline as project_onto_centreline
from .projection import to_track_coordinates as to_track_coordinates
from .flexible import FlexibleTrack as FlexibleTrack
from .rails import HALF_TAPING_DISTANCE as HALF_TAPING_DISTANCE
from .rails import Rails as Rails
from .rails import RAIL_KEYS as RAIL_KEYS
from .rails import STANDARD_GAUGE as STANDARD_GAUGE
from .rails import standard_rails as standard_rails
from .rails import rail_displacement as rail_displacement
from .rails import rail_frame as rail_frame
from .rails import rail_point as rail_point
from .rails import rail_under_wheel as rail_under_wheel
from .rails import track_irregularity as track_irregularity
from .rails import wheel_height as wheel_height
from .rails import wheel_origin as wheel_origin

__all__ = ["Arc", "FlexibleTrack", "cant_angle", "centreline_and_frame", "centreline_position",
           "CHANNELS", "curvature", "curve_layout", "from_track_coordinates",
           "HALF_TAPING_DISTANCE", "heading", "Irregularity", "project",
           "project_onto_centreline", "rail_displacement", "rail_frame", "rail_point",
           "rail_under_wheel", "RAIL_KEYS", "Rails", "STANDARD_GAUGE", "standard_rails",
           "Straight", "straight_track", "superelevation", "to_track_coordinates", "Track",
           "track_frame", "track_irregularity", "Transition", "wheel_height", "wheel_origin"]
