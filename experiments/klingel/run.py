"""A single coned wheelset rolling freely on straight track hunts with Klingel's
kinematic wavelength 2 pi sqrt(r0 e / tan(gamma)).

Prints JSON: the measured wavelengths (between upward zero crossings of the lateral
displacement), Klingel's, their ratio, the solver's steps and the wall time.

Usage: python experiments/klingel/run.py [--speed 5] [--distance 60] [--cone 0.05]
"""

import argparse
import json
import time

import numpy as np

import jaxrail


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--speed", type=float, default=5.0, help="forward speed [m/s]")
    parser.add_argument("--distance", type=float, default=60.0, help="distance run [m]")
    parser.add_argument("--cone", type=float, default=0.05, help="cone angle [rad]")
    parser.add_argument("--offset", type=float, default=2e-3, help="initial lateral offset [m]")
    args = parser.parse_args()
    jaxrail.enable_float64()
    from jaxrail.profiles.analytic import conical_wheel
    from jaxrail.track import straight_track
    from jaxrail.simulation import simulate_single_wheelset

    wheel = conical_wheel(args.cone)
    track = straight_track(args.distance + 30.0)  # UIC60 1:40 at 1.435 m
    t1 = args.distance / args.speed
    start = time.perf_counter()
    result, (_, patches) = simulate_single_wheelset(wheel, track, args.speed, args.offset, t1,
                                                    n_outputs=int(t1 * 200) + 1)
    wall = time.perf_counter() - start
    q = np.asarray(result.q)
    x, y = q[:, 0], q[:, 1]
    up = [x[k] - y[k] * (x[k + 1] - x[k]) / (y[k + 1] - y[k])
          for k in range(len(y) - 1) if y[k] < 0.0 <= y[k + 1]]
    wavelengths = np.diff(up)
    radius, e = float(patches.rolling_radius[0, 0]), float(patches.y_track[0, 0])
    klingel = 2 * np.pi * np.sqrt(radius * e / np.tan(args.cone))
    print(json.dumps({
        "speed_m_s": args.speed, "cone_rad": args.cone, "rolling_radius_m": radius,
        "half_contact_distance_m": e, "klingel_wavelength_m": klingel,
        "measured_wavelengths_m": [round(float(w), 4) for w in wavelengths],
        "ratio": float(np.mean(wavelengths)) / klingel if len(wavelengths) else None,
        "max_lateral_mm": 1e3 * float(np.max(np.abs(y))),
        "steps": int(result.accepted_steps),
        "rejected": int(result.rejected_steps),
        "status": result.status,
        "wall_s_including_compile": round(wall, 1),
    }, indent=1))


if __name__ == "__main__":
    main()
