"""Which axis of a contact table sets its geometry error (issue 19).

Builds tables of S1002 on UIC60 at the given inclination on grids that refine one axis
at a time (lateral, roll, approach) and compares each table's main contact point and
rolling radius with the quasi-static search (``jaxrail.geometry.wheelset_geometry``,
each wheel pressed 0.06 mm into its rail) over shifts of +-8 mm, where the search's
point moves less than 0.5 mm per 0.25 mm of shift and each wheel has one patch (the
region ``tests/contact/test_table.py`` checks). Prints one JSON line per grid.

Usage: ``python experiments/table_grid/run.py 1:20 base lateral roll approach approach4
approach5``.
"""

import json
import sys
import time

import numpy as np

from jaxrail import enable_float64

enable_float64()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxrail.contact.pose import wheelset_pose  # noqa: E402
from jaxrail.contact.table import Axis, TableGrid, build_contact_table, table_patches  # noqa: E402
from jaxrail.geometry import wheelset_geometry  # noqa: E402
from jaxrail.profiles import s1002, uic60  # noqa: E402
from jaxrail.track import Rails, straight_track  # noqa: E402

DEPTH = 6.0e-5  # [m]
STATION, LENGTH = 10.0, 20.0
LATERAL, YAW, ROLL = (Axis.span(-0.016, 0.016, 1.0e-4), Axis.span(0.0, 0.0, 1.0),
                      Axis.span(-0.015, 0.015, 0.005))
APPROACH = TableGrid().approach
DEEPEST = float(APPROACH.nodes[-1])
GRIDS = {
    "base": TableGrid(LATERAL, YAW, ROLL, APPROACH),
    "lateral": TableGrid(Axis.span(-0.016, 0.016, 0.5e-4), YAW, ROLL, APPROACH),
    "roll": TableGrid(LATERAL, YAW, Axis.span(-0.015, 0.015, 0.0025), APPROACH),
    "approach": TableGrid(LATERAL, YAW, ROLL,
                          Axis.span(APPROACH.start, DEEPEST, APPROACH.step / 2)),
    "approach4": TableGrid(LATERAL, YAW, ROLL,
                           Axis.span(APPROACH.start, DEEPEST, APPROACH.step / 4)),
    "approach5": TableGrid(LATERAL, YAW, ROLL,
                           Axis.span(APPROACH.start, DEEPEST, APPROACH.step / 5)),
    "approach_coarse": TableGrid(LATERAL, YAW, ROLL,
                                 Axis.span(APPROACH.start, DEEPEST, APPROACH.step * 2)),
}


def main_field(patches, field):
    deepest = np.argmax(np.asarray(patches.penetration), axis=-1)
    return np.take_along_axis(np.asarray(getattr(patches, field)), deepest[..., None], -1)[..., 0]


def main(inclination, names):
    wheel, rails = s1002(), Rails.at_gauge(uic60(inclination), 1.435)
    shifts = np.arange(-0.008, 0.00801, 2.5e-4)
    online = wheelset_geometry(wheel, rails, shifts, virtual_penetration=DEPTH)
    y_online = np.asarray(online.main_patch("y_wheel"))
    step = np.abs(np.diff(y_online, axis=0))
    inner = (step[1:] < 5e-4) & (step[:-1] < 5e-4)
    single = np.asarray(online.patches.active).sum(axis=2) == 1
    smooth = np.concatenate([np.zeros((1, 2), bool), inner, np.zeros((1, 2), bool)]) & single
    track = straight_track(LENGTH, rails=rails)
    for name in names:
        start = time.perf_counter()
        table, _ = build_contact_table(wheel, rails, grid=GRIDS[name])
        build = time.perf_counter() - start

        def one(shift, height, roll):
            position, rotation = wheelset_pose(track, STATION, shift, height, roll)
            return jax.vmap(lambda side: table_patches(table, wheel, track, position,
                                                       rotation, side))(
                jnp.array([1.0, -1.0]))

        tabled = jax.jit(jax.vmap(one))(jnp.asarray(shifts), online.height, online.roll)
        out = {"inclination": inclination, "grid": name,
               "approach_levels": GRIDS[name].approach.count, "build_s": round(build, 1)}
        for field in ("y_wheel", "rolling_radius"):
            difference = np.abs(main_field(tabled, field)
                                - np.asarray(online.main_patch(field)))[smooth]
            out[field] = {"within_0.02mm": round(float(np.mean(difference < 2e-5)), 3),
                          "max_mm": round(1e3 * float(difference.max()), 4)}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:] or list(GRIDS))
