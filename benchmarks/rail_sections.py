"""The rail sections under the trailer's 8 wheels: the projection of each wheel's profile
origin onto the track and the rail's frame there (:func:`jaxrail.track.rail_under_wheel`,
vmapped over wheelsets and sides), at the paper curve's start, timed as
``benchmarks/rhs_profile.py`` times its parts (a compiled loop of 50, median of
``--calls`` loops). Prints JSON: us per evaluation of all 8, the operations and element
operations of the optimised program, the load.
Usage: ``python benchmarks/rail_sections.py [--calls 30]``.
"""

import argparse
import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import rhs_profile as profile  # noqa: E402  (float64 and the timing helpers)

import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.track.rails import rail_under_wheel, wheel_origin  # noqa: E402
from jaxrail.vehicles import initial_state  # noqa: E402
from jaxrail.vehicles.vehicle import wheelset_states  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--calls", type=int, default=30)
    args = parser.parse_args()
    scenario = load_scenario("paper-curve")
    vehicle, params, track = scenario.build()
    state = jax.jit(lambda p, t: initial_state(vehicle, p, t, scenario.speed,
                                               scenario.misalignment))(params, track)
    data, structure = eqx.partition((vehicle, params, track), eqx.is_array)

    def sections(q, qdot, data):
        vehicle, params, track = eqx.combine(data, structure)
        position, rotation, _, _ = wheelset_states(vehicle, q, qdot)

        def wheelset(r, a):
            return jax.vmap(lambda side: rail_under_wheel(
                track, wheel_origin(r, a, side), side))(jnp.array([1.0, -1.0]))
        return jax.vmap(wheelset)(position, rotation)

    us, operations, elements, _ = profile.timed_in_loop(sections, (state.q, state.qdot, data),
                                                        args.calls)
    print(json.dumps({"benchmark": "rail_sections", "us_per_evaluation": round(us, 2),
                      "operations": operations["operations"],
                      "element_operations": {k: elements[k] for k in ("arithmetic",
                                                                      "data_movement")},
                      "load": os.getloadavg()}, indent=1))


if __name__ == "__main__":
    main()
