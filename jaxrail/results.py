"""The output side of a run: a JSON summary with a stable schema and a self-describing
HDF5 results file (docs/results.md describes both).

Both work on an unbatched :class:`jaxrail.simulation.SimulationResult` on the host
(plain NumPy; nothing here is traced). Axes of the per-wheel arrays: time (T),
wheelset (W, leading first: wheelset 1 of the summary is index 0), wheel (0 = left,
1 = right, seen in the direction of travel), patch slot (P). Output times after an
early stop (``valid`` False) are ignored by the summary and written as NaN (floats) or
0 / -1 (flags, indices) to the file.

Derailment ratio: ``Y`` here is the lateral force of the wheel **on the rail**,
positive towards the rail's field side (outward): the Nadal convention, in which a
flanging wheel has Y > 0. It is minus ``WheelOutputs.lateral_force`` (the force on the
wheel from the rail, positive towards the field side).
"""

import datetime
import json
import math
from pathlib import Path

import numpy as np

from ._files import write_atomically, write_text

SUMMARY_SCHEMA_VERSION = 1
FORMAT_VERSION = 1
SIDES = ("left", "right")
# Y/Q is only meaningful where the wheel carries load: below 1 kN it is noise over zero.
MIN_VERTICAL_FORCE_N = 1e3
AXES = "axes: time, wheelset (index 0 = wheelset 1 = leading), wheel (0 left, 1 right)"
PATCH_AXES = AXES + ", patch slot"

# WheelOutputs fields: (units, description).
CONTACT_FIELDS = {
    "active": ("1", "patch slot holds a contact patch (1) or not (0)"),
    "surface": ("1", ("index of the wheel surface of the patch (simplified profile: 0 "
                      "tread, 1 flange); -1 at times not reached")),
    "y_wheel": ("m", ("lateral position of the contact point on the wheel profile, from "
                      "the taping line, positive towards the field side")),
    "y_rail": ("m", ("lateral position of the contact point on the rail profile, from "
                     "the rail profile origin, positive towards the field side")),
    "penetration": ("m", "depth of the wheel into the rail at the contact point"),
    "contact_angle": ("rad", ("angle of the contact normal from the rail's up axis, "
                              "positive tilting towards the track centre (flange contact "
                              "~ +1.2 rad)")),
    "normal_force": ("N", "normal contact force"),
    "creep_force_x": ("N", "longitudinal creep force on the wheel, contact frame"),
    "creep_force_y": ("N", "lateral creep force on the wheel, contact frame"),
    "creepage_x": ("1", "longitudinal creepage"),
    "creepage_y": ("1", "lateral creepage"),
    "spin": ("1/m", "spin creepage"),
    "semi_axis_a": ("m", "Hertz ellipse semi-axis along the rolling direction"),
    "semi_axis_b": ("m", "Hertz ellipse semi-axis across the rolling direction, in the "
                         "contact plane"),
    "lateral_force": ("N", ("total lateral force on the wheel from the rail, track frame, "
                            "positive towards the wheel's field side (a flanging wheel has "
                            "lateral_force < 0; the Nadal Y on the rail is -lateral_force)")),
    "vertical_force": ("N", ("total vertical force Q on the wheel from the rail, track "
                             "frame, positive up")),
}


FLANGE_ANGLE = math.radians(70.0)  # S1002 flange, the usual Nadal reference


def nadal_limit(friction=0.4, flange_angle=FLANGE_ANGLE):
    """Nadal's limit of the derailment ratio Y/Q [-] for wheel flange climbing:
    ``(tan g - mu) / (1 + mu tan g)`` with ``friction`` mu [-] and ``flange_angle`` g
    [rad] (default 70 deg, the S1002 flange). Floats or NumPy arrays (broadcast)."""
    tan = np.tan(np.asarray(flange_angle, dtype=np.float64))
    mu = np.asarray(friction, dtype=np.float64)
    value = (tan - mu) / (1.0 + mu * tan)
    return float(value) if value.ndim == 0 else value


def _host(result):
    """The result's arrays as NumPy, checked to be one unbatched run."""
    t = np.asarray(result.t)
    if t.ndim != 1:
        raise ValueError(f"result: expected one run with t of shape (T,), got t.shape = "
                         f"{t.shape} (index a batched result first)")
    active = np.asarray(result.wheels.active)
    if active.ndim != 4 or active.shape[0] != t.shape[0] or active.shape[2] != 2:
        raise ValueError(f"result: wheels.active must have shape (T, W, 2, P) with "
                         f"T = {t.shape[0]}, got {active.shape}")
    return t, np.asarray(result.valid, dtype=bool)


def _optional(x):
    """A float, or None for NaN/inf (JSON has no NaN)."""
    x = float(x)
    return x if math.isfinite(x) else None


def masked_max(values, mask):
    """The largest finite entry of ``values`` where ``mask`` holds, as a float; None
    where there is none."""
    values = np.where(mask & np.isfinite(values), values, -np.inf)
    best = np.max(values) if values.size else -np.inf
    return float(best) if np.isfinite(best) else None


def nadal_forces(result):
    """``(Y, Q)`` (T, W, 2) [N] of every wheel in the Nadal convention (module
    docstring): the lateral force on the rail, positive outward, and the vertical one."""
    lateral = -np.asarray(result.wheels.lateral_force, dtype=np.float64)
    return lateral, np.asarray(result.wheels.vertical_force, dtype=np.float64)


def derailment_ratio(result):
    """Y/Q (T, W, 2) [-] of every wheel in the Nadal convention (module docstring):
    NaN where the wheel carries less than 1 kN or the time was not reached."""
    _, valid = _host(result)
    lateral, vertical = nadal_forces(result)
    loaded = valid[:, None, None] & (vertical > MIN_VERTICAL_FORCE_N)
    return np.where(loaded, lateral / np.where(loaded, vertical, 1.0), np.nan)


def _runs(t, flags):
    """[[t_start, t_end], ...] of the maximal runs of consecutive True ``flags``."""
    padded = np.concatenate([[False], flags, [False]]).astype(np.int8)
    edges = np.diff(padded)
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [[float(t[a]), float(t[b])] for a, b in zip(starts, ends)]


def summarize(result, friction=0.4, flange_angle_threshold=0.6) -> dict:
    """The run's summary as plain Python types (JSON-serializable, None for missing
    values, never NaN). The schema is stable; docs/results.md lists every key.

    Arguments:
        result: an unbatched :class:`jaxrail.simulation.SimulationResult`.
        friction: mu [-] for the Nadal limit (use the run's contact friction).
        flange_angle_threshold: contact angle [rad] above which (in magnitude) a patch
            counts as flange contact (0.6 rad ~ 34 deg: between the tread's few degrees
            and the flange's ~70).

    Keys: ``schema_version``, ``status``, ``simulated_time_s``, ``wall_time_s``,
    ``compile_time_s``, ``real_time_factor`` (simulated / wall time), ``steps``,
    ``rhs_evaluations`` and ``jacobian_evaluations`` (the right-hand sides and load
    Jacobians the integration evaluated, :func:`jaxrail.simulation.evaluations_per_step`;
    None for a solver it does not know), ``friction``, ``nadal_limit``,
    ``flange_angle_threshold_rad``, ``wheels`` (W * 2 objects: wheelset 1 left, 1 right,
    2 left, ...) and ``wheelsets`` (W objects).
    """
    t, valid = _host(result)
    w = result.wheels
    active = np.asarray(w.active, dtype=bool) & valid[:, None, None, None]
    normal = np.asarray(w.normal_force, dtype=np.float64)
    angle = np.abs(np.asarray(w.contact_angle, dtype=np.float64))
    flange = np.any(active & (angle > flange_angle_threshold), axis=3)  # (T, W, 2)
    tread_and_flange = flange & np.any(active & (angle <= flange_angle_threshold), axis=3)
    multi = np.sum(active, axis=3) >= 2
    ratio = derailment_ratio(result)
    n_valid = int(np.sum(valid))
    any_valid = n_valid > 0
    deflection = np.abs(np.asarray(result.rail_deflection, dtype=np.float64))  # (T, W, 2, 2)
    wheels = []
    for ws in range(active.shape[1]):
        for side in range(2):
            peak = masked_max(normal[:, ws, side], active[:, ws, side])
            wheels.append({
                "wheelset": ws + 1,
                "side": SIDES[side],
                "max_normal_force_N": peak if peak is not None or not any_valid else 0.0,
                "max_Y_over_Q": masked_max(ratio[:, ws, side], np.isfinite(ratio[:, ws, side])),
                "multi_patch_intervals_s": _runs(t, multi[:, ws, side]),
                "tread_and_flange_intervals_s": _runs(t, tread_and_flange[:, ws, side]),
                "flange_contact_fraction": (float(np.sum(flange[:, ws, side])) / n_valid
                                            if any_valid else None),
                "max_rail_deflection_lateral_m": masked_max(deflection[:, ws, side, 0], valid),
                "max_rail_deflection_vertical_m": masked_max(deflection[:, ws, side, 1],
                                                             valid),
            })
    lateral = np.abs(np.asarray(result.wheelset_lateral, dtype=np.float64))
    wheelsets = [{"wheelset": ws + 1,
                  "max_lateral_displacement_m": masked_max(lateral[:, ws], valid)}
                 for ws in range(lateral.shape[1])]
    simulated = float(np.max(t[valid])) if any_valid else 0.0
    wall = _optional(result.wall_time_s)
    steps = int(result.steps)
    return {
        "schema_version": SUMMARY_SCHEMA_VERSION,
        "status": str(result.status),
        "simulated_time_s": simulated,
        "wall_time_s": wall,
        "compile_time_s": _optional(result.compile_time_s),
        "real_time_factor": simulated / wall if wall else None,
        "steps": steps,
        "rhs_evaluations": _count(result.rhs_evaluations),
        "jacobian_evaluations": _count(result.jacobian_evaluations),
        "friction": float(friction),
        "nadal_limit": nadal_limit(friction),
        "flange_angle_threshold_rad": float(flange_angle_threshold),
        "wheels": wheels,
        "wheelsets": wheelsets,
    }


def write_summary(path, summary: dict) -> None:
    """Write ``summary`` (from :func:`summarize`) as indented JSON, whole or not at all."""
    write_text(path, json.dumps(summary, indent=2, allow_nan=False) + "\n")


# --- HDF5 results file -------------------------------------------------------------

_COMPONENTS = ["x", "y", "z", "e0", "e1", "e2", "e3"]
_BODY_CONVENTION = (
    "7 numbers per body: centre of mass position r = (x, y, z) in the global frame, then "
    "Euler parameters p = (e0, e1, e2, e3) (unit quaternion, scalar first) of the "
    "body-to-global rotation (Nikravesh; jaxrail.multibody conventions)")


def _root_attrs(result, metadata):
    import jaxrail
    attrs = {
        "format": "jaxrail-results",
        "format_version": FORMAT_VERSION,
        "jaxrail_version": jaxrail.__version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "description": "jaxrail simulation results",
        "conventions": (
            "SI units (units attribute on every dataset). Track frame: x along the track, "
            "y to the left, z up; left/right seen in the direction of travel. Wheelset "
            "index 0 = wheelset 1 = leading; wheel 0 = left, 1 = right. Rows with "
            "valid = 0 were not reached (early stop): floats NaN, flags 0, indices -1."),
    }
    for key, value in metadata.items():
        if not isinstance(key, str):
            raise TypeError(f"metadata: keys must be strings, got {key!r}")
        if key == "body_names" or value is None:
            continue
        if isinstance(value, (bool, np.bool_)):
            value = np.uint8(value)
        elif isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
            value = list(value)
        elif not isinstance(value, (str, int, float, np.integer, np.floating)):
            value = json.dumps(value, default=str)
        attrs[key] = value
    # What the result itself says wins over the metadata.
    attrs.update({
        "status": str(result.status),
        "simulated_time_s": float(result.simulated_time_s),
        "derailed": np.uint8(bool(result.derailed)),
        "steps": int(result.steps),
        "accepted_steps": int(result.accepted_steps),
        "rejected_steps": int(result.rejected_steps),
        "rhs_evaluations": int(result.rhs_evaluations),
        "jacobian_evaluations": int(result.jacobian_evaluations),
        "wall_time_s": float(result.wall_time_s),
        "compile_time_s": float(result.compile_time_s),
    })
    return attrs


def _count(value):
    """An evaluation count as an int, None where the solver's is unknown (-1)."""
    value = int(value)
    return None if value < 0 else value


def _datasets(result, body_names):
    """{path: (array, units, description, axes)} of everything the file holds."""
    t, valid = _host(result)

    def rows(x):
        return valid.reshape((-1,) + (1,) * (x.ndim - 1))

    def floats(x):
        x = np.asarray(x, dtype=np.float64)
        return np.where(rows(x), x, np.nan)

    q, qdot, qddot = floats(result.q), floats(result.qdot), floats(result.qddot)
    n = q.shape[1] // 7
    if q.shape[1] != 7 * n:
        raise ValueError(f"result: q must have 7 numbers per body, got shape {q.shape}")
    if body_names is not None and len(body_names) != n:
        raise ValueError(f"metadata['body_names']: {len(body_names)} names for {n} bodies")
    wheelset_axes, wheelset_text = "axes: time, wheelset (index 0 = leading)", "time, wheelset"
    out = {
        "time": (floats(t), "s", "output time", "time"),
        "valid": (valid.astype(np.uint8), "1",
                  "1 where the run reached this output time, 0 after an early stop", "time"),
        "wheelset/lateral": (floats(result.wheelset_lateral), "m",
                             ("wheelset centre lateral offset from the track centreline, "
                              f"positive left; {wheelset_axes}"), wheelset_text),
        "wheelset/vertical": (floats(result.wheelset_vertical), "m",
                              ("wheelset centre vertical displacement from the initial "
                               f"state, positive up; {wheelset_axes}"), wheelset_text),
        "wheelset/yaw": (floats(result.wheelset_yaw), "rad",
                         ("wheelset yaw relative to the track, positive anticlockwise "
                          f"seen from above; {wheelset_axes}"), wheelset_text),
        "track/irregularity": (
            floats(result.irregularity), "m",
            ("the track's irregularity at each wheelset: alignment (positive left), vertical "
             "level (positive up), cross level (left rail over right) and gauge deviation "
             "(positive wider), zeros on an ideal track (docs/track.md); axes: time, "
             "wheelset (index 0 = leading), channel"), "time, wheelset, channel"),
        "track/rail_deflection": (
            floats(result.rail_deflection), "m",
            ("the deflection of the rails under each wheelset on a flexible track: lateral "
             "along the canted track frame's n (positive left), vertical along its b "
             "(positive up), from the unloaded rail; zeros on rigid rails (docs/track.md); "
             "axes: time, wheelset (index 0 = leading), rail (left, right), direction "
             "(lateral, vertical)"), "time, wheelset, rail, direction"),
        "bodies/q": (q.reshape(len(t), n, 7), "m (x, y, z); 1 (e0, e1, e2, e3)",
                     "body coordinates; axes: time, body, component. " + _BODY_CONVENTION,
                     "time, body, component"),
        "bodies/qdot": (qdot.reshape(len(t), n, 7), "m/s (x, y, z); 1/s (e0, e1, e2, e3)",
                        ("time derivatives of bodies/q (not angular velocities); axes: "
                         "time, body, component"), "time, body, component"),
        "bodies/qddot": (qddot.reshape(len(t), n, 7),
                         "m/s^2 (x, y, z); 1/s^2 (e0, e1, e2, e3)",
                         ("time derivatives of bodies/qdot: the accelerations of eq. (19) "
                          "with the loads of the outputs; axes: time, body, component"),
                         "time, body, component"),
        "constraint_violation": (floats(result.constraint_violation), "m",
                                 "largest |Phi| over the joint constraint equations",
                                 "time"),
    }
    wheels = result.wheels
    for field, (units, description) in CONTACT_FIELDS.items():
        x = np.asarray(getattr(wheels, field))
        axes, text = (PATCH_AXES, "time, wheelset, wheel, patch") if x.ndim == 4 else (
            AXES, "time, wheelset, wheel")
        if field == "active":
            x = (x.astype(bool) & rows(x)).astype(np.uint8)
        elif field == "surface":
            x = np.where(rows(x), x, -1).astype(np.int32)
        else:
            x = floats(x)
        out[f"contact/{field}"] = (x, units, f"{description}; {axes}", text)
    return out


def write_results(path, result, *, metadata: dict | None = None) -> None:
    """Write ``result`` to the HDF5 file ``path``, whole or not at all (an existing file
    is replaced only when the new one is complete).

    The layout (docs/results.md): root attributes (``metadata`` entries, e.g. scenario
    name and description, plus format, jaxrail version, creation time, status and
    integrator statistics from the result); datasets ``time``, ``valid``,
    ``wheelset/{lateral,vertical,yaw}``, ``bodies/{q,qdot,qddot}`` (T, n, 7),
    ``contact/<WheelOutputs field>`` and ``constraint_violation``, each with attributes
    ``units`` (SI, "1" for dimensionless), ``description`` and ``axes``.
    ``metadata["body_names"]`` (n names), if given, labels the bodies.
    """
    import h5py

    metadata = {} if metadata is None else metadata
    if not isinstance(metadata, dict):
        raise TypeError(f"metadata: expected a dict, got {type(metadata).__name__}")
    body_names = metadata.get("body_names")
    datasets = _datasets(result, body_names)
    attrs = _root_attrs(result, metadata)

    def write(temporary):
        with h5py.File(temporary, "w") as f:
            f.attrs.update(attrs)
            for name, (data, units, description, axes) in datasets.items():
                big = data.size >= 4096  # compress what is worth it; MATLAB reads gzip
                d = f.create_dataset(name, data=data, compression="gzip" if big else None,
                                     shuffle=big)
                d.attrs.update({"units": units, "description": description, "axes": axes})
                if name.startswith("bodies/"):
                    d.attrs["components"] = _COMPONENTS
                    if body_names is not None:
                        d.attrs["body_names"] = [str(b) for b in body_names]

    write_atomically(path, write)


def _plain(value):
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()] if value.dtype.kind in "OSU" else value
    return value.item() if isinstance(value, np.generic) else value


RESULTS_FILE = "an HDF5 results file written by `jaxrail simulate --out` (docs/results.md)"


def open_results(path):
    """``h5py.File(path, "r")``, open, of a results file. Checked first: a ValueError names
    ``path`` and what was expected when it is missing, a folder or not HDF5 (h5py's own
    message names neither)."""
    import h5py

    where = Path(path)
    if not where.exists():
        raise ValueError(f"{path}: no such file; expected {RESULTS_FILE}")
    if where.is_dir():
        raise ValueError(f"{path}: is a folder; expected {RESULTS_FILE}")
    if not h5py.is_hdf5(where):
        raise ValueError(f"{path}: not an HDF5 file; expected {RESULTS_FILE}")
    return h5py.File(where, "r")


def read_results(path) -> dict:
    """A results file as plain NumPy: ``{dataset path: array, "attrs": root attributes,
    "units": {dataset path: units}}``; ``valid`` and ``contact/active`` as bool.
    ValueError (:func:`open_results`) when ``path`` is not an HDF5 file."""
    import h5py

    out, units = {}, {}

    def visit(name, node):
        if isinstance(node, h5py.Dataset):
            data = node[()]
            out[name] = data.astype(bool) if name in ("valid", "contact/active") else data
            units[name] = _plain(node.attrs["units"])

    with open_results(path) as f:
        f.visititems(visit)
        out["attrs"] = {k: _plain(v) for k, v in f.attrs.items()}
    out["units"] = units
    return out
