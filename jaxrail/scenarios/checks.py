"""The allowed range of every number a user gives a scenario (file, command line, Monte
Carlo draws), checked before anything compiles, with errors that name where the value
came from, the key, what is allowed and what was given.

Ranges (inclusive): :data:`RANGES`. They bound physics (a speed of 160 m/s is above the
railway record, a misalignment of 35 mm is the derailment limit) and sizes (at most
:data:`MAX_OUTPUTS` output times and :data:`MAX_STEPS` fixed steps per run).
"""

import difflib

from .._ranges import within
from ..vehicles.parameters import PARAMETERS

RANGES = {
    "speed": (0.1, 160.0, "m/s"),
    "misalignment": (-0.035, 0.035, "m"),
    "duration": (1e-4, 3600.0, "s"),
    "friction": (*PARAMETERS["friction"].range, PARAMETERS["friction"].unit),
    "rtol": (1e-12, 0.1, "-"),
    "atol": (1e-15, 1e-2, "-"),
    "output_rate": (0.01, 1e5, "Hz"),
    "fixed_step": (1e-7, 1e-2, "s"),
    "length": (1e-3, 1e5, "m"),
    "radius": (10.0, 1e7, "m"),
    "cant": (-0.2, 0.2, "m"),
    "gauge": (*PARAMETERS["track_gauge"].range, PARAMETERS["track_gauge"].unit),
    "irregularity_scale": (0.0, 10.0, "-"),
    "irregularity_step": (0.01, 5.0, "m"),
    "defect_wavelength": (0.1, 1000.0, "m"),
    "defect_amplitude": (-0.05, 0.05, "m"),
    "defect_position": (-1e5, 1e5, "m"),
    "mass": (1.0, 1e4, "kg"),
    "stiffness": (1e5, 1e11, "N/m"),
    "damping": (0.0, 1e9, "N s/m"),
}
MAX_OUTPUTS = 200_001
MAX_STEPS = 2_000_000


def number(value, name: str, where: str, key: str | None = None) -> float:
    """``value`` as a float if it is a finite number within ``RANGES[name]``, else
    ValueError naming ``where`` and ``key`` (default ``name``)."""
    low, high, unit = RANGES[name]
    label = f"{where}: {key or name}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{label} must be a number [{unit}], got {value!r}")
    return within(value, low, high, unit, label)


def count(value, name: str, where: str, low: int, high: int) -> int:
    """``value`` if it is an integer within [low, high], else ValueError naming
    ``where`` and ``name``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"{where}: {name} must be an integer from {low} to {high}, got "
                         f"{value!r}")
    return value


def known_keys(table, allowed, where: str, label: str) -> dict:
    """``table`` if it is a TOML table whose keys are all in ``allowed``, else
    ValueError naming the unknown key and the closest allowed one."""
    if not isinstance(table, dict):
        raise ValueError(f"{where}: {label} must be a table, got {table!r}")
    for key in table:
        if key not in allowed:
            close = difflib.get_close_matches(key, allowed, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"{where}: unknown key {key!r} in {label}{hint}; allowed: "
                             f"{', '.join(sorted(allowed))}")
    return table


def text(table: dict, key: str, where: str, label: str, default=None, choices=None) -> str:
    """``table[key]`` (or ``default``) if it is a string (one of ``choices``)."""
    if key not in table:
        if default is None:
            raise ValueError(f"{where}: missing {key!r} in {label}")
        return default
    value = table[key]
    if not isinstance(value, str):
        raise ValueError(f"{where}: {label} {key} must be a string, got {value!r}")
    if choices is not None and value not in choices:
        raise ValueError(f"{where}: {label} {key} must be one of {tuple(choices)}, got "
                         f"{value!r}")
    return value


def run_size(duration: float, output_rate: float, fixed_step, where: str) -> None:
    """ValueError if a run of ``duration`` [s] would keep more than :data:`MAX_OUTPUTS`
    outputs at ``output_rate`` [Hz] or take more than :data:`MAX_STEPS` fixed steps."""
    outputs = int(round(duration * output_rate)) + 1
    if outputs > MAX_OUTPUTS:
        # the trailer's results: states 1.2 kB, contact details 2.5 kB per output time
        gigabytes = outputs * 3.8e3 / 1e9
        raise ValueError(f"{where}: {duration:g} s at output_rate {output_rate:g} Hz is "
                         f"{outputs} output times (the trailer's results alone "
                         f"{gigabytes:.3g} GB); at most {MAX_OUTPUTS}")
    if fixed_step is not None and duration / fixed_step > MAX_STEPS:
        raise ValueError(f"{where}: {duration:g} s in fixed steps of {fixed_step:g} s is "
                         f"{duration / fixed_step:.3g} steps; at most {MAX_STEPS}")
