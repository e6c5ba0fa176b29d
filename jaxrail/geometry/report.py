"""Wheel-rail geometry report: the ``jaxrail geometry`` tables (JSON, CSV) and plot.

Runs :func:`jaxrail.geometry.wheelset_geometry` for a range of shifts given in mm and
turns the :class:`WheelsetGeometry` result into plain Python rows in millimetres: one
row per shift with the active patches of each wheel, plus the equivalent conicity for
amplitudes of 1 to 6 mm. Files are written whole or not at all.
"""

import csv
import io
import json
import math

import jax.numpy as jnp
import numpy as np

from .._files import write_text as write_text
from ..track import Rails
from .conicity import equivalent_conicity
from .quasistatic import VIRTUAL_PENETRATION, wheelset_geometry

CONICITY_AMPLITUDES_MM = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
HALF_CONTACT_DISTANCE = 0.75  # [m] e of the conicity formula (EN 15302, standard gauge)
CSV_COLUMNS = ("shift_mm", "side", "patch", "y_track_mm", "y_wheel_mm", "rolling_radius_mm",
               "contact_angle_rad", "penetration_mm", "roll_rad", "delta_r_mm", "converged")
# A row is converged when the solve's depth error is below RESIDUAL_TOLERANCE and the
# deepest patch the search then finds on each wheel is the virtual penetration to within
# DEPTH_TOLERANCE (S1002 on UIC60 1:40 and 1:20 over +-10 mm in 0.5 mm steps: within 1e-14 m).
RESIDUAL_TOLERANCE = 1e-9  # [m]
DEPTH_TOLERANCE = 1e-7  # [m]
_PATCH_FIELDS = (("y_track_mm", "y_track"), ("y_wheel_mm", "y_wheel"),
                 ("rolling_radius_mm", "rolling_radius"), ("contact_angle_rad", "contact_angle"),
                 ("penetration_mm", "penetration"))



MAX_SHIFT_MM = 25.0  # [mm] lateral shifts of the wheelset a report may ask for
MAX_SHIFTS = 10_001  # shifts per report


def shift_grid_mm(shift_from, shift_to, shift_step):
    """Shifts [mm] from ``shift_from`` to ``shift_to`` (included when on the grid) in steps
    of ``shift_step``; ``ValueError`` naming the CLI option on bad input."""
    for name, value in (("--shift-from", shift_from), ("--shift-to", shift_to),
                        ("--shift-step", shift_step)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value}")
    for name, value in (("--shift-from", shift_from), ("--shift-to", shift_to)):
        if abs(value) > MAX_SHIFT_MM:
            raise ValueError(f"{name} must be within [-{MAX_SHIFT_MM:g}, {MAX_SHIFT_MM:g}] mm "
                             f"(beyond, the flange is past the rail), got {value}")
    if shift_step <= 0.0:
        raise ValueError(f"--shift-step must be > 0, got {shift_step}")
    if shift_from >= shift_to:
        raise ValueError(f"--shift-from ({shift_from}) must be less than --shift-to ({shift_to})")
    count = int(math.floor((shift_to - shift_from) / shift_step + 1e-9)) + 1
    if count > MAX_SHIFTS:
        raise ValueError(f"--shift-step {shift_step} gives {count} shifts in [{shift_from}, "
                         f"{shift_to}] mm; at most {MAX_SHIFTS}")
    if count < 2:
        raise ValueError(f"--shift-step {shift_step} leaves a single shift in "
                         f"[{shift_from}, {shift_to}]")
    return np.round(shift_from + shift_step * np.arange(count), 9)


def _covered(shifts_m, delta_r_m, amplitude_m):
    """The shift range holds both turning points of the oscillation of this amplitude:
    ``0 < A <= max shift`` and the potential ``int_0^y dr`` at the lowest shift reaches
    its level at ``A`` (so the negative turning point is inside the range)."""
    if not (shifts_m[0] < 0.0 < amplitude_m <= shifts_m[-1] + 1e-12):
        return False
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (delta_r_m[1:] + delta_r_m[:-1])
                                                   * np.diff(shifts_m))])
    potential = cumulative - np.interp(0.0, shifts_m, cumulative)
    return bool(potential[0] >= np.interp(amplitude_m, shifts_m, potential))


def conicity_entries(shifts_m, delta_r_m, nominal_radius_m, amplitudes_mm=CONICITY_AMPLITUDES_MM):
    """``[{"amplitude_mm", "tan_gamma_e"}]``; ``tan_gamma_e`` is ``None`` where the shift
    range does not cover the amplitude (see :func:`_covered`)."""
    shifts_m, delta_r_m = np.asarray(shifts_m), np.asarray(delta_r_m)
    amplitudes_m = 1e-3 * np.asarray(amplitudes_mm, dtype=np.float64)
    values = np.asarray(equivalent_conicity(jnp.asarray(shifts_m), jnp.asarray(delta_r_m),
                                  jnp.asarray(amplitudes_m), HALF_CONTACT_DISTANCE,
                                  jnp.asarray(nominal_radius_m, dtype=jnp.float64)))
    return [{"amplitude_mm": float(a),
             "tan_gamma_e": float(v) if _covered(shifts_m, delta_r_m, 1e-3 * a) else None}
            for a, v in zip(amplitudes_mm, values)]


def geometry_rows(result, virtual_penetration=VIRTUAL_PENETRATION):
    """One dict per shift [mm, rad] from a :class:`WheelsetGeometry` solved at
    ``virtual_penetration`` [m]: ``shift_mm``, ``roll_rad``, ``delta_r_mm``,
    ``converged`` (module constants; a row that did not converge holds the contact at
    the wrong depth) and the active patches of the ``left`` and ``right``
    wheel in lateral slot order (``y_track_mm`` from the track centre, positive left;
    ``y_wheel_mm`` from the taping line, positive toward the field side)."""
    patches = result.patches
    active = np.asarray(patches.active)
    fields = {key: np.asarray(getattr(patches, name)) for key, name in _PATCH_FIELDS}
    shifts, roll, delta_r = (np.asarray(x) for x in (result.shift, result.roll, result.delta_r))
    deepest = np.where(active, fields["penetration_mm"], -np.inf).max(axis=2)  # (n, 2) [m]
    converged = ((np.asarray(result.residual) <= RESIDUAL_TOLERANCE)
                 & np.all(np.abs(deepest - virtual_penetration) <= DEPTH_TOLERANCE, axis=1))
    rows = []
    for k in range(shifts.shape[0]):
        row = {"shift_mm": float(np.round(1e3 * shifts[k], 9)), "roll_rad": float(roll[k]),
               "delta_r_mm": float(1e3 * delta_r[k]), "converged": bool(converged[k])}
        for side_index, side in enumerate(("left", "right")):
            row[side] = [
                {key: float(values[k, side_index, slot] * (1.0 if key.endswith("_rad") else 1e3))
                 for key, values in fields.items()}
                for slot in np.flatnonzero(active[k, side_index])]
        rows.append(row)
    return rows


def geometry_report(wheel, rail, shifts_mm, gauge_mm=1435.0, yaw_per_shift=0.0, settings=None):
    """Run the quasi-static analysis and build the report.

    Arguments:
        wheel, rail: wheel and rail profiles (built outside jit).
        shifts_mm: increasing lateral shifts [mm], positive left.
        gauge_mm: track gauge [mm].
        yaw_per_shift: yaw per shift [mrad/mm] (= rad/m).
        settings: dict echoed as ``"settings"`` (the inputs as the user gave them).

    Returns ``(report, result)``: the JSON-ready dict ``{"settings", "rows",
    "conicity"}`` and the :class:`WheelsetGeometry`.
    """
    shifts_m = 1e-3 * np.asarray(shifts_mm, dtype=np.float64)
    rails = Rails.at_gauge(rail, jnp.asarray(1e-3 * gauge_mm, dtype=jnp.float64))
    result = wheelset_geometry(wheel, rails, jnp.asarray(shifts_m),
                               jnp.asarray(yaw_per_shift, dtype=jnp.float64))
    report = {
        "settings": dict(settings or {}),
        "rows": geometry_rows(result),
        "conicity": conicity_entries(shifts_m, np.asarray(result.delta_r),
                                     float(wheel.nominal_radius)),
        "max_residual_mm": float(1e3 * np.max(np.asarray(result.residual))),
    }
    return report, result


def report_json(report) -> str:
    """The report as indented JSON text."""
    return json.dumps(report, indent=1) + "\n"


def report_csv(report) -> str:
    """The report as CSV text: one line per shift and active patch (columns
    :data:`CSV_COLUMNS`; ``patch`` numbers a wheel's active patches in lateral order)."""
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for row in report["rows"]:
        for side in ("left", "right"):
            for number, patch in enumerate(row[side]):
                writer.writerow([repr(row["shift_mm"]), side, number]
                                + [repr(patch[key]) for key, _ in _PATCH_FIELDS]
                                + [repr(row["roll_rad"]), repr(row["delta_r_mm"]),
                                   str(row["converged"]).lower()])
    return stream.getvalue()
