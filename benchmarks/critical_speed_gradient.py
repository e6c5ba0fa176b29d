"""The suspended wheelset's linear critical speed and its gradient with respect to four
parameters (implicit differentiation, jaxrail.stability), against central differences
of the critical speed itself; prints JSON.

    python benchmarks/critical_speed_gradient.py [--step 1e-3] [--wheel cone]

``--wheel cone``: 1:40 coned wheels instead of S1002, with the cone angle (the
conicity) among the parameters.
"""

import argparse
import json
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from jaxrail.profiles.analytic import conical_wheel  # noqa: E402
from jaxrail.stability import LinearStability  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.vehicles import get_values, set_values  # noqa: E402
from jaxrail.vehicles.suspended_wheelset import suspended_wheelset  # noqa: E402

NAMES = ("primary_longitudinal_stiffness", "primary_lateral_stiffness", "friction",
         "wheelset_mass")
RANGE = (60.0, 140.0)  # [m/s]
CONE_RANGE = (200.0, 300.0)  # [m/s]: the coned wheelset's crossing is near 238 m/s


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=1e-3,
                        help="relative step of the central differences")
    parser.add_argument("--wheel", choices=("s1002", "cone"), default="s1002")
    args = parser.parse_args()
    names, speeds = NAMES, RANGE
    if args.wheel == "cone":
        vehicle, params = suspended_wheelset(conical_wheel(0.025, nominal_radius=0.46))
        names, speeds = NAMES + ("wheel_cone_angle",), CONE_RANGE
    else:
        vehicle, params = suspended_wheelset()
    stability = LinearStability(vehicle, params, straight_track(200.0))
    start = time.perf_counter()
    critical = stability.critical_speed(*speeds)
    solve_s = time.perf_counter() - start
    start = time.perf_counter()
    gradient = stability.critical_speed_gradient(critical, names)
    gradient_s = time.perf_counter() - start
    values = np.asarray(get_values(vehicle, params, names))
    rows = []
    for k, name in enumerate(names):
        step = args.step * values[k]
        found = []
        for sign in (1.0, -1.0):
            moved = set_values(vehicle, params, [name], jnp.array([values[k] + sign * step]))
            near = [stability.hunting(critical.speed + dv, moved) for dv in (-1.0, 1.0)]
            found.append(stability.critical_speed(*speeds, params=moved, points=near).speed)
        central = (found[0] - found[1]) / (2 * step)
        rows.append({"parameter": name, "value": float(values[k]),
                     "implicit_derivative": gradient[name], "central_difference": central,
                     "relative_difference": gradient[name] / central - 1.0})
    print(json.dumps({
        "vehicle": f"suspended-wheelset ({args.wheel} wheels), primary longitudinal "
                   f"stiffness 1 MN/m per side",
        "critical_speed_m_s": critical.speed, "hunting_frequency_hz": critical.frequency_hz,
        "critical_speed_solve_s": solve_s, "gradient_s_first_call": gradient_s,
        "relative_step": args.step, "gradient": rows,
        "load_average": os.getloadavg()[0]}, indent=2))


if __name__ == "__main__":
    main()
