"""EN 12299 mean comfort of a run: the carbody floor accelerometers' readings
(:mod:`jaxrail.standards.floor`) at floor points over the bogies and at the centre,
from a results file's ``bodies/q``, ``bodies/qdot`` and ``bodies/qddot`` or from the
same arrays in memory (:func:`comfort_of_states`), through
:func:`jaxrail.standards.en12299.mean_comfort`."""

import dataclasses

import numpy as np

from ..vehicles.trailer import trailer_values
from .en12299 import MEAN_COMFORT_BLOCKS, WINDOW_S, continuous_comfort, mean_comfort
from .en14363 import valid_rows
from .floor import floor_accelerations

FLOOR_HEIGHT_M = 1.2
"""[m] of the carbody floor above the rail tops [A]: a typical main-line coach (the
trailer's data hold no floor height)."""


def trailer_floor_points(values=None) -> dict:
    """``{name: point (3,) [m, carbody frame]}`` over the leading bogie, at the centre
    and over the trailing bogie, on the floor (:data:`FLOOR_HEIGHT_M`), from trailer
    data (``carbody.bogie_half_distance``, ``carbody.height``; default the built-in
    Manchester file, whatever data file the run used)."""
    v = trailer_values() if values is None else values
    a, z = v["carbody.bogie_half_distance"], FLOOR_HEIGHT_M - v["carbody.height"]
    return {"over leading bogie": (a, 0.0, z), "centre": (0.0, 0.0, z),
            "over trailing bogie": (-a, 0.0, z)}


def record_blocks(time) -> tuple[float, int]:
    """(sample rate [Hz], whole 5 s blocks) of the output times ``time`` (T,) [s], the
    blocks counted as :mod:`.en12299` counts them; (0, 0) for fewer than 2 times."""
    time = np.asarray(time, dtype=np.float64)
    rate = (len(time) - 1) / (time[-1] - time[0]) if len(time) > 1 else 0.0
    window = round(WINDOW_S * rate)  # samples of one block
    return rate, (len(time) // window if window >= 1 else 0)


def body_index(names, body: str, where: str) -> int:
    """Index of ``body`` in the bodies' ``names``; ValueError naming ``where`` (the
    names' source) and the bodies there are."""
    names = [str(n) for n in names]
    if body not in names:
        raise ValueError(f"{where}: no body named {body!r} (bodies: "
                         f"{names or 'unnamed'})")
    return names.index(body)


def comfort_of_states(time, q, qdot, qddot, body: int, points=None,
                      body_name: str = "carbody") -> dict:
    """Mean comfort N_MV and the largest continuous comfort Cc per axis at each floor
    ``points`` (``{name: (3,) [m, body frame]}``, default
    :func:`trailer_floor_points`) of body index ``body`` (named ``body_name`` in the
    result), from the uniformly sampled ``time`` (T,) [s] and the bodies' ``q``,
    ``qdot``, ``qddot`` (T, 7 n) or (T, n, 7) (jaxrail.multibody conventions, all
    finite). Fewer blocks than the standard's 60 give an indicative N_MV
    (``"indicative": true``); ValueError for a record shorter than one 5 s block."""
    rate, blocks = record_blocks(time)
    out = {"body": body_name, "sample_rate_hz": rate, "blocks_of_5_s": blocks,
           "indicative": blocks < MEAN_COMFORT_BLOCKS, "points": {}}
    for name, point in (trailer_floor_points() if points is None else points).items():
        reading = floor_accelerations(q, qdot, qddot, body, point)
        comfort = mean_comfort(*reading.T, rate, min_blocks=max(1, min(
            blocks, MEAN_COMFORT_BLOCKS)))
        cc = continuous_comfort(*reading.T, rate)
        out["points"][name] = {
            "point_m": [float(x) for x in point], **dataclasses.asdict(comfort),
            **{f"max_{k}_m_s2": float(np.nanmax(cc[k])) for k in ("cc_x", "cc_y", "cc_z")}}
    return out


def comfort_of_file(path, body="carbody", points=None) -> dict:
    """:func:`comfort_of_states` of ``body`` in the results file ``path``, over the rows
    before the first ``valid = 0``. ValueError names a missing dataset or body, or a
    record shorter than one 5 s block.
    :func:`jaxrail.standards.from_result.comfort_of_result` does the same for a
    :class:`jaxrail.simulation.SimulationResult` in memory. A ValueError names ``path``
    when it is missing or not an HDF5 file (:func:`jaxrail.results.open_results`)."""
    from ..results import open_results

    with open_results(path) as f:
        missing = [n for n in ("time", "valid", "bodies/q", "bodies/qdot", "bodies/qddot")
                   if n not in f]
        if missing:
            raise ValueError(f"{path}: no EN 12299 comfort without {', '.join(missing)} "
                             "(results files of jaxrail 0.1 after the accelerations were "
                             "added to the outputs have them)")
        names = [n.decode() if isinstance(n, bytes) else str(n)
                 for n in f["bodies/q"].attrs.get("body_names", [])]
        index = body_index(names, body, f"{path}: bodies/q")
        rows = valid_rows(f["valid"][()])
        time = f["time"][:rows]
        states = [f[n][:rows] for n in ("bodies/q", "bodies/qdot", "bodies/qddot")]
    return comfort_of_states(time, *states, index, points, body)


def format_comfort(comfort: dict) -> str:
    """:func:`comfort_of_file`'s result as lines for the terminal."""
    lines = [f"EN 12299 mean comfort N_MV ({comfort['blocks_of_5_s']} blocks of 5 s"
             + (", fewer than the standard's 60: indicative" if comfort["indicative"]
                else "") + f", {comfort['body']} floor)"]
    for name, point in comfort["points"].items():
        lines.append(f"  {name:<20} N_MV {point['n_mv']:.2f} ({point['comfort_class']}), "
                     f"max Cc y {point['max_cc_y_m_s2']:.3f} m/s^2")
    return "\n".join(lines)
