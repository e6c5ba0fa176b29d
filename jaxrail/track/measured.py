"""Measured track geometry files: the four irregularity channels on an equidistant grid.

Format (CSV, UTF-8; lines starting with ``#`` are comments; one header line, then one
row per sample, distances increasing by a constant step)::

    # jaxrail track irregularities: german-low, seed 7, band 3-150 m
    distance [m],alignment [mm],vertical level [mm],cross level [mm],gauge deviation [mm]
    0.0,0.4183,-1.0472,0.2521,0.0630
    0.25,0.4211,-1.0314,0.2494,0.0618
    ...

- distance: arc length along the design track [m];
- alignment: lateral displacement of the track centre, positive left [mm];
- vertical level: vertical displacement of the track centre, positive up [mm];
- cross level: height of the left rail over the right rail, over 1.5 m [mm];
- gauge deviation: gauge minus its nominal value, positive wider [mm].

Conventions and signs: docs/track.md. The spacing must be equal within 1e-6 of the
step (GENSYS's TRAX files use 0.25 m). Values in millimetres: a file whose largest
value is below 0.05 mm looks like metres and is refused, as is one above 500 mm.
"""

import csv
import io
import math

import numpy as np

from .._files import write_text
from .irregularity import sampled

COLUMNS = ("distance [m]", "alignment [mm]", "vertical level [mm]", "cross level [mm]",
           "gauge deviation [mm]")
"""The header's columns; the last four are :data:`.irregularity.CHANNELS` in mm."""
SPACING_TOLERANCE = 1e-6  # relative to the step
SMALLEST_LARGEST_MM = 0.05  # a file whose largest |value| is below this looks like metres
LARGEST_MM = 500.0


def _normal(name: str) -> str:
    return " ".join(name.strip().lower().split())


def read_irregularity(path):
    """:class:`~jaxrail.track.irregularity.Irregularity` [m] of a measured file (module
    docstring); ValueError names the file, the line and what is wrong."""
    try:
        with open(path, encoding="utf-8") as stream:
            text = stream.read()
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text (UTF-8) file") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the irregularity file ({error.strerror})") from None
    return parse_irregularity(text, str(path))


def parse_irregularity(text: str, where: str = "<irregularity>"):
    """As :func:`read_irregularity`, from the file's text."""
    rows = [(k + 1, line) for k, line in enumerate(text.splitlines())
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise ValueError(f"{where}: empty irregularity file; the header must be "
                         f"{','.join(COLUMNS)}")
    number, header = rows[0]
    names = [_normal(x) for x in next(csv.reader([header]))]
    expected = [_normal(x) for x in COLUMNS]
    missing = [c for c, n in zip(COLUMNS, expected) if n not in names]
    if missing:
        raise ValueError(f"{where}: line {number}: missing column(s) {', '.join(missing)}; the "
                         f"header must name {','.join(COLUMNS)}")
    unknown = [n for n in names if n not in expected]
    if unknown:
        raise ValueError(f"{where}: line {number}: unknown column(s) {', '.join(unknown)}; the "
                         f"header must name {','.join(COLUMNS)}")
    order = [names.index(n) for n in expected]
    data = []
    for number, line in rows[1:]:
        cells = next(csv.reader([line]))
        if len(cells) != len(names):
            raise ValueError(f"{where}: line {number}: {len(cells)} cells, the header has "
                             f"{len(names)}")
        row = []
        for k in order:
            try:
                value = float(cells[k])
            except ValueError:
                raise ValueError(f"{where}: line {number}: column {COLUMNS[order.index(k)]!r}: "
                                 f"{cells[k].strip()!r} is not a number") from None
            if not math.isfinite(value):
                raise ValueError(f"{where}: line {number}: column {COLUMNS[order.index(k)]!r}: "
                                 f"{cells[k].strip()!r} is not finite")
            row.append(value)
        data.append(row)
    if len(data) < 4:
        raise ValueError(f"{where}: {len(data)} samples; an irregularity needs at least 4")
    data = np.asarray(data)
    distance, millimetres = data[:, 0], data[:, 1:]
    steps = np.diff(distance)
    step = (distance[-1] - distance[0]) / (len(distance) - 1)
    if not step > 0.0:
        raise ValueError(f"{where}: distances must increase, got {distance[0]} to {distance[-1]} m")
    off = np.abs(steps - step) > SPACING_TOLERANCE * step
    if off.any():
        k = int(np.argmax(off))
        raise ValueError(f"{where}: unequal spacing: {steps[k]:.9g} m between {distance[k]:.9g} "
                         f"and {distance[k + 1]:.9g} m, the mean step is {step:.9g} m; resample "
                         "the file to an equidistant grid")
    largest = float(np.max(np.abs(millimetres)))
    if 0.0 < largest < SMALLEST_LARGEST_MM:
        raise ValueError(f"{where}: the largest value is {largest:.3g} mm: these look like metres; "
                         "the channels must be in millimetres")
    if largest > LARGEST_MM:
        raise ValueError(f"{where}: a value of {largest:.4g} mm: more than {LARGEST_MM:g} mm is not "
                         "a track irregularity; the channels must be in millimetres")
    return sampled(1e-3 * millimetres, distance[0], step)


def irregularity_table(irregularity) -> tuple[np.ndarray, np.ndarray]:
    """``(distance (N,) [m], channels (N, 4) [mm])`` of an irregularity's samples, times
    its scale."""
    values = np.asarray(irregularity.values) * float(irregularity.scale)
    distance = float(irregularity.start) + float(irregularity.step) * np.arange(len(values))
    return distance, 1e3 * values


def write_irregularity(path, irregularity, comment: str = "") -> None:
    """Write ``irregularity``'s samples as a measured file (module docstring), whole or
    not at all, with 17 significant digits (read back, it is the same within the
rounding of the millimetre conversion, 1e-16 relative)."""
    distance, millimetres = irregularity_table(irregularity)
    out = io.StringIO()
    for line in comment.splitlines():
        out.write(f"# {line}\n")
    out.write(",".join(COLUMNS) + "\n")
    for x, row in zip(distance, millimetres):
        out.write(",".join(repr(float(v)) for v in (x, *row)) + "\n")
    write_text(path, out.getvalue())

