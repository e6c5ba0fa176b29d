"""A run's record as the channels of an EN 14363 assessment
(:func:`jaxrail.standards.en14363.assess_channels`): the leading wheelset's body by name,
the valid rows before an early stop, the distance travelled and Y, Q from the contact
outputs (docs/results.md)."""

import numpy as np

REQUIRED_DATASETS = ("time", "valid", "contact/lateral_force", "contact/vertical_force",
                     "bodies/q")


def leading_wheelset_body(names):
    """Index in ``names`` (the bodies' names, in order) of the leading wheelset's body:
    the one named ``wheelset`` or ``wheelset_<k>`` with the smallest k; None if none."""
    candidates = []
    for i, name in enumerate(names):
        head, _, tail = str(name).lower().partition("_")
        if head == "wheelset" and (tail == "" or tail.isdigit()):
            candidates.append((int(tail) if tail else 0, i))
    return min(candidates)[1] if candidates else None


def find_wheelset_body(names, wheelset_body, where):
    """(index of the leading wheelset's body, how it was found) from the bodies'
    ``names`` (None if unnamed), unless ``wheelset_body`` gives it; ``where`` names
    the names' source in the error."""
    if wheelset_body is not None:
        return int(wheelset_body), "argument wheelset_body"
    i = None if names is None else leading_wheelset_body(names)
    if i is None:
        raise ValueError(f"wheelset_body: no body named 'wheelset' or 'wheelset_<k>' "
                         f"in {where} ({'none given' if names is None else list(names)}); "
                         "pass the leading wheelset's body index")
    return i, f"{where}: {names[i]!r}"


def valid_rows(valid) -> int:
    """How many rows come before the first False of ``valid`` (T,) (all when none is):
    an early stop ends the record."""
    valid = np.asarray(valid, dtype=bool)
    return len(valid) if np.all(valid) else int(np.argmin(valid))


def travelled_distance(centre):
    """Distance travelled [m] (T,) from 0: the cumulative horizontal path of a point
    whose global (x, y) [m] at each sample is ``centre`` (T, 2)."""
    steps = np.hypot(*np.diff(np.asarray(centre, dtype=np.float64), axis=0).T)
    return np.concatenate([[0.0], np.cumsum(steps)])


def record_channels(time, valid, lateral_force, vertical_force, centre):
    """``{"time", "distance", "y", "q", "rows", "total_rows"}``: the channels of
    :func:`jaxrail.standards.en14363.assess_channels` from a run's outputs, over the
    rows before the first ``valid`` False. ``lateral_force``, ``vertical_force`` (T, W,
    2) [N] are the contact outputs (on the wheel from the rail, track frame:
    docs/results.md), so Y = -lateral_force and Q = vertical_force; ``centre`` (T, 2)
    [m] is the leading wheelset centre's global (x, y), whose path is the distance
    travelled. A ValueError when fewer than 2 rows are valid."""
    rows = valid_rows(valid)
    if rows < 2:
        raise ValueError(f"fewer than 2 valid rows ({rows})")
    return {"time": np.asarray(time, dtype=np.float64)[:rows],
            "distance": travelled_distance(np.asarray(centre)[:rows]),
            "y": -np.asarray(lateral_force, dtype=np.float64)[:rows],
            "q": np.asarray(vertical_force, dtype=np.float64)[:rows],
            "rows": rows, "total_rows": len(np.asarray(valid))}
