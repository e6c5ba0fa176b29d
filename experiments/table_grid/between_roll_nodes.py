"""Contact tables between their roll nodes (issue 19).

The geometry test (``tests/contact/test_table.py``) evaluates a table at the wheels of
a wheelset shifted across straight track, whose roll relative to the rail happens to
lie near the table's roll nodes. This script moves each of those wheels off its roll by
a quarter and half of the roll step, lowers it with the paper's search until it is
0.06 mm deep (``_node`` at that one level), and compares the table's main contact point
on the wheel with the search's there, for a roll step of 5 and of 2.5 mrad. Only wheels
with one patch, away from the jumps (the search's point moves less than 0.5 mm between
neighbouring shifts), count. Prints one JSON line per grid and roll offset.

Usage: ``python experiments/table_grid/between_roll_nodes.py 1:20``.
"""

import json
import sys

import numpy as np

from jaxrail import enable_float64

enable_float64()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxrail.contact import SearchConfig  # noqa: E402
from jaxrail.contact.pose import wheelset_pose  # noqa: E402
from jaxrail.contact.table import (Axis, TableGrid, build_contact_table,  # noqa: E402
                                   relative_pose, table_patches)
from jaxrail.contact.table.build import _node, _pose_on_straight  # noqa: E402
from jaxrail.geometry import wheelset_geometry  # noqa: E402
from jaxrail.profiles import s1002, uic60  # noqa: E402
from jaxrail.track import Rails, straight_track  # noqa: E402

DEPTH = 6.0e-5  # [m]
LATERAL, YAW = Axis.span(-0.016, 0.016, 1.0e-4), Axis.span(0.0, 0.0, 1.0)


def sweep_poses(wheel, rails):
    """(lateral, yaw, roll, side) of each wheel of the quasi-static sweep, (2 n, 4)."""
    shifts = np.arange(-0.008, 0.00801, 2.5e-4)
    online = wheelset_geometry(wheel, rails, shifts, virtual_penetration=DEPTH)
    track, poses = straight_track(20.0, rails=rails), []
    for n, shift in enumerate(shifts):
        position, rotation = wheelset_pose(track, 10.0, shift, online.height[n], online.roll[n])
        for side in (1.0, -1.0):
            lateral, _, yaw, roll, *_ = relative_pose(track, float(wheel.nominal_radius),
                                                      position, rotation, side)
            poses.append((float(lateral), float(yaw), float(roll), side))
    return np.array(poses)


def main(inclination):
    wheel, rails = s1002(), Rails.at_gauge(uic60(inclination), 1.435)
    offset, config = float(rails.offset), SearchConfig()
    radius = float(wheel.nominal_radius)
    poses = sweep_poses(wheel, rails)
    track = straight_track(100.0, rails=rails)
    search = jax.jit(jax.vmap(lambda lat, yaw, roll, side: _node(
        wheel, rails.profile, offset, lat, yaw, roll, side, config, radius, (DEPTH,))))
    for step in (0.005, 0.0025):
        grid = TableGrid(LATERAL, YAW, Axis.span(-0.015, 0.015, step))
        table, _ = build_contact_table(wheel, rails, grid=grid)

        def look(lateral, yaw, roll, side, vertical, table=table):
            position, rotation = _pose_on_straight(track, radius, lateral, vertical, yaw, roll,
                                                   side)
            return table_patches(table, wheel, track, position, rotation, side)

        for shift in (0.0, step / 4, step / 2):
            lateral, yaw, roll, side = (jnp.asarray(poses[:, k]) for k in range(4))
            found, values, depth, heights, _ = search(lateral, yaw, roll + shift, side)
            found, depth = np.asarray(found)[:, 0], np.asarray(depth)[:, 0]
            main_slot = np.argmax(np.where(found, depth, -1.0), axis=-1)
            y_search = np.asarray(values)[np.arange(len(main_slot)), 0, main_slot, -1]
            patches = jax.jit(jax.vmap(look))(lateral, yaw, roll + shift, side,
                                              jnp.asarray(heights)[:, 0])
            deepest = np.argmax(np.asarray(patches.penetration), axis=-1)
            y_table = np.take_along_axis(np.asarray(patches.y_wheel), deepest[:, None], -1)[:, 0]
            moves = np.abs(np.diff(y_search.reshape(-1, 2), axis=0))
            inner = (moves[1:] < 5e-4) & (moves[:-1] < 5e-4)
            smooth = np.concatenate([np.zeros((1, 2), bool), inner, np.zeros((1, 2), bool)])
            smooth = smooth.reshape(-1) & (found.sum(axis=-1) == 1)
            difference = np.abs(y_table - y_search)[smooth]
            print(json.dumps({"inclination": inclination, "roll_step_mrad": 1e3 * step,
                              "off_node_mrad": 1e3 * shift, "wheels": int(smooth.sum()),
                              "within_0.02mm": round(float(np.mean(difference < 2e-5)), 3),
                              "max_mm": round(1e3 * float(difference.max()), 4)}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
