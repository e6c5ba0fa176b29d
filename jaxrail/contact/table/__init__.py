"""Contact tables: the paper's search tabulated over a wheel's pose relative to its rail.

A wheel's contact with a locally straight rail depends only on the wheel's pose in the
rail's frame ``[t n b]`` (:func:`jaxrail.track.rail_frame`). Write ``T`` for the wheel's
taping point (the wheel origin less the nominal radius along the wheel frame's up
axis, eq. 7). The pose is

- ``lateral = n . (T - rail origin)`` [m] (global left positive, for both wheels),
- ``vertical = b . (T - rail origin)`` [m],
- ``roll = arcsin(axle . b)`` [rad] and ``yaw = atan2(-axle . t, axle . n)`` [rad].

A :class:`ContactTable` holds, for each rail (left, right) and each node of a grid in
(lateral, yaw, roll), what the paper's search (:func:`jaxrail.contact.search_wheel`)
finds with the wheel lowered until its deepest patch penetrates each depth of the
approach axis: the wheel's vertical position there and, per patch slot, the signed
depth, the parts the search places the contact point from (the patch's deepest point,
the centre and breadth of its interpenetration), the rail point's offset from it on the
profiles and the Hertz curvature of the patch, each with its derivative in
``vertical`` (forward-mode, through the search). Patches are tracked along the lateral
axis at build time (in order along the wheel: two patches of one surface cannot pass
each other), so that a slot holds the same patch from node to node and interpolation
does not mix two patches.

Lookups interpolate every field with a quadratic B-spline through the nodes along
lateral, yaw and roll (C1, one block of 3 x 3 x 3 coefficients), first the wheel's
vertical position at the levels, then the slots at the two levels around the wheel's
actual position, and between them by cubic Hermite interpolation in the vertical
position from each field's values and derivatives there. They place the contact point
from its parts as the search does (:func:`jaxrail.contact.patches.wide_point`): on the
conformal UIC60 1:20 tread the point moves 15-35 um per um of depth and its rate jumps
where the blend starts and ends, which the parts do not. They derive the rest of
:class:`jaxrail.contact.ContactPatches` as the search does, from the wheel's actual
pose and the profiles at the interpolated points: the wheel point on the wheel's strip
(eq. 12; the creepages are taken between it and the rail point, so its height matters
to 1e-5 of the rolling radius), its longitudinal offset, the contact frame, angle,
rolling radius and profile curvatures.
"""

from .build import build_contact_table as build_contact_table
from .grid import FIELDS as FIELDS
from .grid import GEOMETRY as GEOMETRY
from .grid import Axis as Axis
from .grid import ContactTable as ContactTable
from .grid import TableGrid as TableGrid
from .lookup import relative_pose as relative_pose
from .lookup import table_patches as table_patches

__all__ = ["Axis", "build_contact_table", "ContactTable", "FIELDS", "GEOMETRY",
           "relative_pose", "TableGrid", "table_patches"]
