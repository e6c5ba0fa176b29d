"""Benchmark of the contact search: one jitted call of ``search_vehicle`` for the
8 wheels of a vehicle (4 wheelsets), S1002 on UIC60 1:40, straight track, 1435 mm.

Poses: wheelsets shifted -1, 0, +1.5, +3 mm and yawed 0, 1, -1, 2 mrad, their height and
roll set (Newton on the refined deepest depth, outside the timed call) so that each
wheel penetrates its rail by 0.05 mm, about the elastic approach under a 10 t wheel load.

Prints JSON: compile time and median call time at the default strip spacing (1 mm),
strips per wheel, and the same for spacings 4, 2, 1, 0.5 mm; the load average before
and after. Usage: ``python benchmarks/contact_search.py [--calls 50]``.
"""

import argparse
import json
import os
import platform
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.contact import SearchConfig, deepest_depth, search_vehicle, wheelset_pose  # noqa: E402
from jaxrail.profiles import s1002, uic60  # noqa: E402
from jaxrail.track import Rails, straight_track  # noqa: E402

SHIFTS = (-1.0e-3, 0.0, 1.5e-3, 3.0e-3)  # [m]
YAWS = (0.0, 1.0e-3, -1.0e-3, 2.0e-3)  # [rad]
STATIONS = (10.0, 12.5, 27.5, 30.0)  # [m] two bogies, 2.5 m wheelbase, 17.5 m apart
PENETRATION = 5.0e-5  # [m]
SPACINGS = (4.0e-3, 2.0e-3, 1.0e-3, 0.5e-3)  # [m]


def _poses(wheel, track):
    """Height and roll of each wheelset so that both wheels penetrate by PENETRATION."""

    @jax.jit
    def depths(unknowns, shift, yaw, station):
        position, rotation = wheelset_pose(track, station, shift, unknowns[0], unknowns[1], yaw)
        return jnp.stack([deepest_depth(wheel, track, position, rotation, side, SearchConfig(),
                                        station) for side in (1.0, -1.0)])

    positions, rotations = [], []
    for shift, yaw, station in zip(SHIFTS, YAWS, STATIONS):
        x = np.array([float(wheel.nominal_radius), 0.0])
        args = (jnp.asarray(shift), jnp.asarray(yaw), jnp.asarray(station))
        for _ in range(15):
            r = np.asarray(depths(jnp.asarray(x), *args)) - PENETRATION
            jac = np.stack([(np.asarray(depths(jnp.asarray(x + 1e-7 * e), *args)) - PENETRATION - r)
                            / 1e-7 for e in np.eye(2)], axis=1)
            x = x - np.linalg.solve(jac, r)
        position, rotation = wheelset_pose(track, station, shift, x[0], x[1], yaw)
        positions.append(position)
        rotations.append(rotation)
    return jnp.stack(positions), jnp.stack(rotations)


def _time(config, wheel, track, positions, rotations, calls):
    search = jax.jit(lambda w, t, p, q: search_vehicle(w, t, p, q, config))
    start = time.perf_counter()
    result = search(wheel, track, positions, rotations)
    jax.block_until_ready(result)
    compile_s = time.perf_counter() - start
    for _ in range(5):  # warm-up
        jax.block_until_ready(search(wheel, track, positions, rotations))
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        jax.block_until_ready(search(wheel, track, positions, rotations))
        times.append(time.perf_counter() - start)
    strips = int(config.strip_grid(wheel.surfaces[0]).shape[0])
    active = np.asarray(result.active)
    return {
        "strip_spacing_mm": 1e3 * config.strip_spacing,
        "strips_per_wheel": strips,
        "compile_s": round(compile_s, 3),
        "median_us": round(1e6 * statistics.median(times), 1),
        "min_us": round(1e6 * min(times), 1),
        "active_patches": int(active.sum()),
        "max_penetration_mm": round(1e3 * float(np.max(np.asarray(result.penetration))), 5),
    }, result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=50, help="timed calls per setting")
    args = parser.parse_args()
    load_before = os.getloadavg()
    wheel = s1002()
    track = straight_track(40.0, rails=Rails.at_gauge(uic60("1:40"), 1.435))
    positions, rotations = _poses(wheel, track)

    default, reference = _time(SearchConfig(), wheel, track, positions, rotations, args.calls)
    scaling = []
    for spacing in SPACINGS:
        entry, result = _time(SearchConfig(strip_spacing=spacing), wheel, track, positions,
                              rotations, args.calls)
        # contact position against the finest default-independent run: spacing effect
        entry["max_y_wheel_change_vs_1mm_um"] = round(1e6 * float(np.max(np.where(
            np.asarray(reference.active) & np.asarray(result.active),
            np.abs(np.asarray(result.y_wheel) - np.asarray(reference.y_wheel)), 0.0))), 3)
        scaling.append(entry)
    print(json.dumps({
        "benchmark": "search_vehicle, 4 wheelsets = 8 wheels, S1002 / UIC60 1:40, straight track",
        "default": default,
        "scaling": scaling,
        "calls_per_setting": args.calls,
        "load_average_before": [round(x, 2) for x in load_before],
        "load_average_after": [round(x, 2) for x in os.getloadavg()],
        "cpu_count": os.cpu_count(),
        "machine": platform.processor() or platform.machine(),
        "jax": jax.__version__,
        "backend": jax.default_backend(),
    }, indent=1))


if __name__ == "__main__":
    main()
