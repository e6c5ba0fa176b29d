"""The Monte Carlo table as files: CSV (plain text, one header line) and Parquet
(typed columns, via pyarrow), each written whole or not at all.

A table is ``{column: 1-D array}`` with equal lengths; string columns (``status``)
stay strings, numbers are float64 or int64, NaN where a value is missing (an empty
field in CSV, a null in Parquet).
"""

import csv
import math
from pathlib import Path

import numpy as np

from .._files import write_atomically

FORMATS = (".csv", ".parquet")


def check_table(table: dict) -> int:
    """Number of rows; ValueError if the columns differ in length."""
    lengths = {name: len(values) for name, values in table.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"table columns differ in length: {lengths}")
    return next(iter(lengths.values()), 0)


def _cell(value):
    if isinstance(value, (str, np.str_)):
        return str(value)
    value = value.item() if hasattr(value, "item") else value
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(value)
    return str(value)


def write_csv(path, table: dict) -> None:
    n = check_table(table)
    names = list(table)

    def write(temporary):
        with open(temporary, "w", newline="", encoding="utf-8") as stream:
            writer = csv.writer(stream)
            writer.writerow(names)
            for i in range(n):
                writer.writerow([_cell(table[name][i]) for name in names])

    write_atomically(path, write)


def write_parquet(path, table: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    check_table(table)
    columns = {}
    for name, values in table.items():
        values = np.asarray(values)
        if values.dtype.kind in "USO":
            columns[name] = pa.array([str(v) for v in values], type=pa.string())
        elif values.dtype.kind == "f":
            columns[name] = pa.array(values, mask=~np.isfinite(values), type=pa.float64())
        else:
            columns[name] = pa.array(values)
    write_atomically(path, lambda temporary: pq.write_table(pa.table(columns), temporary))


def write_table(path, table: dict) -> None:
    """Write ``table`` as CSV or Parquet, chosen by the file's suffix."""
    suffix = Path(path).suffix.lower()
    if suffix == ".csv":
        write_csv(path, table)
    elif suffix == ".parquet":
        write_parquet(path, table)
    else:
        raise ValueError(f"table file {path}: suffix must be one of {FORMATS}")


def read_table(path) -> dict:
    """``{column: array}`` from a CSV or Parquet file written by :func:`write_table`."""
    suffix = Path(path).suffix.lower()
    if suffix == ".parquet":
        import pyarrow.parquet as pq

        data = pq.read_table(path)
        return {name: np.array([np.nan if v is None else v
                                for v in data.column(name).to_pylist()])
                for name in data.column_names}
    if suffix != ".csv":
        raise ValueError(f"table file {path}: suffix must be one of {FORMATS}")
    with open(path, newline="", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    if not rows:
        raise ValueError(f"{path}: empty table file")
    header, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(header):
        cells = [row[j] for row in body]
        try:
            out[name] = np.array([float(c) if c else np.nan for c in cells])
        except ValueError:
            out[name] = np.array(cells)
    return out
