"""EN 14363 and EN 12299 of a run in memory: the same channels and the same
assessment as :func:`jaxrail.standards.en14363.assess_file` and
:func:`jaxrail.standards.comfort.comfort_of_file` build from a results file, taken
from an unbatched :class:`jaxrail.simulation.SimulationResult` (host NumPy) and the
names of its vehicle's bodies (``vehicle.system.body_names``), with no file written.

As from a file, only the rows before the first ``valid`` False are used: Y is
``-wheels.lateral_force`` and Q ``wheels.vertical_force`` (the values
:func:`jaxrail.results.write_results` writes as ``contact/lateral_force`` and
``contact/vertical_force``), the distance travelled the horizontal path of the
leading wheelset's centre in ``q``.
"""

import numpy as np

from . import comfort, en14363


def _bodies(result, body_names):
    """``(q, qdot, qddot)`` (T, n, 7) of ``result``, checked against ``body_names`` (n)."""
    states = [np.asarray(x, dtype=np.float64)
              for x in (result.q, result.qdot, result.qddot)]
    n = len(body_names)
    if states[0].ndim != 2 or states[0].shape[1] != 7 * n:
        raise ValueError(f"result.q: expected shape (T, {7 * n}) for the {n} bodies "
                         f"{list(body_names)}, got {states[0].shape} (index a batched "
                         "result first)")
    return [x.reshape(len(x), n, 7) for x in states]


def result_channels(result, body_names, wheelset_body=None) -> dict:
    """:func:`jaxrail.standards.en14363.record_channels` of ``result``, plus
    ``"wheelset_body"`` and ``"wheelset_body_from"``: the leading wheelset's body index,
    ``wheelset_body`` or found by name in ``body_names``."""
    body, found = en14363.find_wheelset_body(list(body_names), wheelset_body, "body_names")
    q = _bodies(result, body_names)[0]
    if not 0 <= body < q.shape[1]:
        raise ValueError(f"wheelset_body: {body} is not one of the {q.shape[1]} bodies")
    channels = en14363.record_channels(result.t, result.valid, result.wheels.lateral_force,
                                       result.wheels.vertical_force, q[:, body, :2])
    return {**channels, "wheelset_body": body, "wheelset_body_from": found}


def assess_result(result, body_names, *, wheelset_body=None, **options) -> dict:
    """EN 14363 assessment of ``result`` (module docstring): ``options`` are those of
    :func:`jaxrail.standards.en14363.assess_channels` (acceleration channels with the
    result's T rows). The result adds ``"run": {"status", "rows_used",
    "wheelset_body", "wheelset_body_from"}``."""
    channels = result_channels(result, body_names, wheelset_body)
    status = str(result.status)
    out = en14363.assess_record(channels, status, **options)
    out["run"] = {"status": status, "rows_used": channels["rows"],
                  "wheelset_body": channels["wheelset_body"],
                  "wheelset_body_from": channels["wheelset_body_from"]}
    return out


def comfort_states(result, body_names, body="carbody"):
    """``(time (R,) [s], q, qdot, qddot (R, n, 7), index of body)``: the rows of
    ``result`` before the first ``valid`` False; ValueError if no body is named
    ``body``."""
    index = comfort.body_index(body_names, body, "body_names")
    rows = en14363.valid_rows(result.valid)
    time = np.asarray(result.t, dtype=np.float64)[:rows]
    return (time, *(x[:rows] for x in _bodies(result, body_names)), index)


def comfort_of_result(result, body_names, body="carbody", points=None) -> dict:
    """:func:`jaxrail.standards.comfort.comfort_of_states` of ``body`` in ``result``
    over its valid rows (the result of :func:`jaxrail.standards.comfort.comfort_of_file`
    on the same run's file). ValueError names a missing body or a record shorter than
    one 5 s block."""
    return comfort.comfort_of_states(*comfort_states(result, body_names, body), points,
                                     body)
