"""Statistics of a Monte Carlo study: the run's facts and the min, median and max of
every quantity of the table over the samples that ran through (what ``jaxrail
montecarlo`` prints as JSON)."""

import numpy as np

SUCCESSFUL = "successful"
"""The ``status`` of a sample that ran through to its end."""


def successful(table: dict) -> np.ndarray:
    """Boolean mask (N,) of the samples of ``table`` whose ``status`` is ``successful``."""
    return np.asarray(table["status"]) == SUCCESSFUL


def column_statistics(table: dict) -> dict:
    """``{column: {"min", "median", "max"}}`` of every float column of ``table``
    ``{column: array (N,)}`` over the successful samples, NaN and infinite values left
    out; a column with no such value is left out. Integer and string columns, and the
    ``sample`` index (a float column in a table read back from CSV), have none. Values
    in the column's unit, as Python floats."""
    ok = successful(table)
    out = {}
    for name, values in table.items():
        values = np.asarray(values)
        if values.dtype.kind != "f" or name == "sample":
            continue
        good = values[ok & np.isfinite(values)]
        if good.size:
            out[name] = {"min": float(good.min()), "median": float(np.median(good)),
                         "max": float(good.max())}
    return out


def study_statistics(result, scenario: str, duration_s: float) -> dict:
    """The statistics of a study as a JSON-ready dict.

    **Arguments:**

    - ``result``: the study's :class:`jaxrail.montecarlo.MonteCarlo`.
    - ``scenario``: the scenario's name.
    - ``duration_s``: the simulated time of each sample [s].

    **Returns** ``scenario``, ``samples`` (rows of the table), ``seed``, ``duration_s``,
    ``statuses`` ({status: count}), ``compile_time_s``, ``run_time_s``, ``devices``,
    ``chunk``, then ``successful_samples``: :func:`column_statistics` of the table, left
    out when no successful sample has a finite value.
    """
    table = result.table
    stats = {"scenario": scenario, "samples": len(table["status"]), "seed": result.seed,
             "duration_s": duration_s, "statuses": result.statuses,
             "compile_time_s": result.compile_time_s, "run_time_s": result.run_time_s,
             "devices": result.devices, "chunk": result.chunk}
    columns = column_statistics(table)
    if columns:
        stats["successful_samples"] = columns
    return stats
