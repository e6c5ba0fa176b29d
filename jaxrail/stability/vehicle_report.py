"""What ``jaxrail vehicle list`` and ``jaxrail vehicle show`` report: the built-in
vehicles, and a vehicle's bodies, masses, wheel loads at rest and modes standing on the
track with its wheelsets clamped (:mod:`jaxrail.stability.standing`, which says how the
wheelsets are held and how the modes are named). It sits in ``stability``, above
``vehicles``, because the modes are a stability computation."""

import math

import numpy as np

from ..vehicles.from_file import (read_toml, vehicle_file_path, vehicle_from_file,
                                  vehicle_names)
from .standing import vehicle_modes

HELD = ("each wheelset clamped to the track at its rest pose: at rest the creep forces "
        "vanish, so the contact holds the wheelsets neither longitudinally nor in yaw; "
        "the suspension's modes are taken with the wheelsets fixed, as VAMPIRE and "
        "SIMPACK take them")


def vehicle_list() -> list[tuple[str, str]]:
    """``(name, description)`` of each built-in vehicle file
    (:func:`jaxrail.vehicles.vehicle_names`)."""
    return [(name, str(read_toml(vehicle_file_path(name))["vehicle"].get("description", "")))
            for name in vehicle_names()]


def _finite(x):
    """``x`` as a float, or None where it is not finite (JSON has no infinity)."""
    return float(x) if x is not None and math.isfinite(x) else None


def vehicle_report(name_or_path, model=None) -> dict:
    """The report of a vehicle file (a built-in name or a path) as JSON-ready data.

    Keys: ``vehicle``, ``file``, ``description``; ``bodies`` (name, ``mass_kg``,
    ``inertia_kg_m2`` (roll, pitch, yaw), ``position_m`` (vehicle frame));
    ``total_mass_kg``, ``weight_N``; ``static_wheel_loads_N`` (each wheel's vertical
    load at rest, leading wheelset first, left then right), ``wheelsets``;
    ``wheelsets_held``; ``modes`` (``frequency_hz``, ``damping_ratio``, ``body``,
    ``motion``, ``time_constant_s`` (real modes; else null), ``eigenvalue_1_s``
    [re, im], ``energy_share``); ``equilibrium_residual_m_s2``. ``model``: the contact
    model of the rest pose (default the paper's search)."""
    path = vehicle_file_path(name_or_path)
    table = read_toml(path)["vehicle"]
    vehicle, params = vehicle_from_file(path)
    standing = vehicle_modes(vehicle, params, model)
    bodies = params.system.bodies
    layout = np.asarray(params.layout)
    names = vehicle.system.body_names
    return {
        "vehicle": vehicle.name,
        "file": str(path),
        "description": str(table.get("description", "")),
        "bodies": [{"name": name, "mass_kg": float(bodies.mass[i]),
                    "inertia_kg_m2": np.diagonal(np.asarray(bodies.inertia[i])).tolist(),
                    "position_m": layout[i].tolist()} for i, name in enumerate(names)],
        "total_mass_kg": standing.total_mass_kg,
        "weight_N": standing.weight_n,
        "static_wheel_loads_N": standing.wheel_loads_n.reshape(-1).tolist(),
        "wheelsets": [names[i] for i in vehicle.wheelsets],
        "wheelsets_held": HELD,
        "modes": [{"frequency_hz": m.frequency_hz, "damping_ratio": m.damping_ratio,
                   "body": m.body, "motion": m.motion,
                   "time_constant_s": _finite(m.time_constant_s),
                   "eigenvalue_1_s": [m.eigenvalue.real, m.eigenvalue.imag],
                   "energy_share": m.energy_share} for m in standing.modes],
        "equilibrium_residual_m_s2": standing.residual,
    }


def format_report(report: dict) -> str:
    """The report as text tables: bodies, wheel loads at rest, modes."""
    lines = [f"{report['vehicle']}: {report['description']}", f"file: {report['file']}", "",
             f"{'body':<16}{'mass [kg]':>12}  {'inertia roll, pitch, yaw [kg m^2]':<36}"
             f"{'position x, y, z [m]'}"]
    for b in report["bodies"]:
        inertia = ", ".join(f"{x:.4g}" for x in b["inertia_kg_m2"])
        position = ", ".join(f"{x:.3f}" for x in b["position_m"])
        lines.append(f"{b['name']:<16}{b['mass_kg']:>12.1f}  {inertia:<36}{position}")
    lines += [f"{'total':<16}{report['total_mass_kg']:>12.1f}", "",
              "wheel loads at rest [kN] (leading wheelset first):",
              f"{'wheelset':<16}{'left':>10}{'right':>10}"]
    loads = np.reshape(report["static_wheel_loads_N"], (-1, 2))
    for name, (left, right) in zip(report["wheelsets"], loads):
        lines.append(f"{name:<16}{1e-3 * left:>10.3f}{1e-3 * right:>10.3f}")
    lines += [f"{'sum':<16}{1e-3 * float(np.sum(loads)):>20.3f}  (weight "
              f"{1e-3 * report['weight_N']:.3f})", "",
              f"modes standing on the track ({report['wheelsets_held']}):",
              f"{'f [Hz]':>8}{'damping':>9}{'tau [s]':>10}  {'body':<40}motion"]
    for m in report["modes"]:
        tau = "" if m["time_constant_s"] is None else f"{m['time_constant_s']:.4g}"
        lines.append(f"{m['frequency_hz']:>8.3f}{m['damping_ratio']:>9.3f}{tau:>10}  "
                     f"{m['body']:<40}{m['motion']}")
    return "\n".join(lines)
