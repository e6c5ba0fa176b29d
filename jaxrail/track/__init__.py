"""Design track geometry: layout, evaluation at arc length, rails and projection.

Conventions: global X, Y horizontal, Z up; the track is planar. Track frame
``[t n b]``: t along the direction of travel, n to the left, b up, rolled about t by
the cant (banked toward the inside of the curve). Curvature and cant are signed:
positive for a left curve. See docs/track.md.
"""

from .geometry import cant_angle as cant_angle
from .geometry import centreline_position as centreline_position
from .geometry import curvature as curvature
from .geometry import heading as heading
from .geometry import rail_frame as rail_frame
from .geometry import rail_point as rail_point
from .geometry import superelevation as superelevation
from .geometry import track_frame as track_frame
from .layout import Arc as Arc
from .layout import Straight as Straight
from .layout import Track as Track
from .layout import Transition as Transition
from .layout import curve_layout as curve_layout
from .layout import straight_track as straight_track
from .projection import from_track_coordinates as from_track_coordinates
from .projection import project as project
from .projection import to_track_coordinates as to_track_coordinates

__all__ = ["Arc", "cant_angle", "centreline_position", "curvature", "curve_layout",
           "from_track_coordinates", "heading", "project", "rail_frame", "rail_point",
           "Straight", "straight_track", "superelevation", "to_track_coordinates",
           "Track", "track_frame", "Transition"]
