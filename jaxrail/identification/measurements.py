"""Measured time histories: the channels a simulation can be compared with, and the
CSV file that holds them.

Channels (k counts wheelsets from 1, leading first; side is ``left`` or ``right``):

- ``wheelset_lateral_k`` [m], ``wheelset_vertical_k`` [m], ``wheelset_yaw_k`` [rad]:
  the wheelset relative to the track (:class:`jaxrail.simulation.SimulationResult`);
- ``wheel_lateral_force_k_side``, ``wheel_vertical_force_k_side`` [N]: the rail's
  force on the wheel in the track frame (Y, Q of an instrumented wheelset; lateral
  positive towards the wheel's own field side);
- ``lateral_acceleration_BODY`` [m/s^2]: an accelerometer on body BODY (a name of
  the vehicle's multibody system, e.g. ``frame``) along the track's canted lateral
  axis: (a - g) . n, what a lateral accelerometer on a level-mounted body reads.

File format (CSV, lines starting with ``#`` are comments)::

    time,wheelset_lateral_1,wheel_lateral_force_1_right
    noise,1e-4,500
    0.00,0.002,-1234.5
    ...

The ``noise`` row gives each channel's standard deviation (same unit), which weights
it in the fit. Times [s] increase strictly.
"""

import dataclasses
import math
import re
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .._files import write_text
from ..track import to_track_coordinates, track_frame

_PATTERNS = [
    (re.compile(r"wheelset_(lateral|vertical|yaw)_([1-9]\d*)$"), "wheelset"),
    (re.compile(r"wheel_(lateral|vertical)_force_([1-9]\d*)_(left|right)$"), "wheel"),
    (re.compile(r"lateral_acceleration_(\w+)$"), "acceleration"),
]
UNITS = {"wheelset_lateral": "m", "wheelset_vertical": "m", "wheelset_yaw": "rad",
         "wheel_lateral_force": "N", "wheel_vertical_force": "N",
         "lateral_acceleration": "m/s^2"}


def _parse(name, vehicle):
    """(kind, details) of a channel name; ValueError names what is wrong."""
    for pattern, kind in _PATTERNS:
        match = pattern.match(name)
        if not match:
            continue
        if kind == "acceleration":
            body = match.group(1)
            if body not in vehicle.system.body_names:
                raise ValueError(f"channel {name!r}: no body {body!r}; bodies: "
                                 f"{', '.join(vehicle.system.body_names)}")
            return kind, (vehicle.system.body_names.index(body),)
        k = int(match.group(2))
        if k > vehicle.n_wheelsets:
            raise ValueError(f"channel {name!r}: the vehicle has {vehicle.n_wheelsets} "
                             "wheelsets")
        side = () if kind == "wheelset" else (0 if match.group(3) == "left" else 1,)
        return kind, (match.group(1), k - 1, *side)
    raise ValueError(f"unknown channel {name!r}: expected wheelset_(lateral|vertical|yaw)_K, "
                     "wheel_(lateral|vertical)_force_K_(left|right) or lateral_acceleration_BODY")


def check_channels(names, vehicle) -> None:
    """ValueError if any channel name is unknown or does not exist on ``vehicle``."""
    for name in names:
        _parse(name, vehicle)


def _lateral_acceleration(track, q, qddot, gravity, body):
    """Lateral accelerometer reading [m/s^2] of ``body``'s centre at one output: its
    acceleration less gravity along the track frame's lateral axis."""
    position, acceleration = q[7 * body: 7 * body + 3], qddot[7 * body: 7 * body + 3]
    lateral = track_frame(track, to_track_coordinates(track, position)[0])[:, 1]
    return (acceleration - gravity) @ lateral


def _acceleration_column(params, track, result, body):
    """Lateral accelerometer reading (T,) of ``body`` at the output times, from the
    result's accelerations (NaN after an early stop)."""
    safe = lambda x: jnp.where(result.valid[:, None], x, 0.0)  # noqa: E731
    values = jax.lax.map(lambda x: _lateral_acceleration(track, *x, params.system.gravity,
                                                         body),
                         (safe(result.q), safe(result.qddot)))
    return jnp.where(result.valid, values, jnp.nan)


def channel_values(names, vehicle, params, track, result):
    """Values (T, C) of the channels ``names`` at the result's output times (traceable;
    NaN after an early stop); accelerations from the result's ``qddot`` (the run's own
    contact model and loads)."""
    columns = []
    for name in names:
        kind, detail = _parse(name, vehicle)
        if kind == "wheelset":
            columns.append(getattr(result, f"wheelset_{detail[0]}")[:, detail[1]])
        elif kind == "wheel":
            field = getattr(result.wheels, f"{detail[0]}_force")
            columns.append(field[:, detail[1], detail[2]])
        else:
            columns.append(_acceleration_column(params, track, result, detail[0]))
    return jnp.stack(columns, axis=1)


@dataclasses.dataclass(frozen=True)
class Measurements:
    """Measured channels: ``time`` (M,) [s], ``channels`` (C names), ``values`` (M, C),
    ``noise`` (C,) standard deviations (channel units)."""

    time: np.ndarray
    channels: tuple[str, ...]
    values: np.ndarray
    noise: np.ndarray

    def __post_init__(self):
        time, values, noise = (np.asarray(x, dtype=np.float64)
                               for x in (self.time, self.values, self.noise))
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "noise", noise)
        object.__setattr__(self, "channels", tuple(self.channels))
        m, c = len(time), len(self.channels)
        if c == 0 or m < 2:
            raise ValueError("measurements need at least one channel and two samples")
        if values.shape != (m, c) or noise.shape != (c,):
            raise ValueError(f"measurements: values must be ({m}, {c}) and noise ({c},), "
                             f"got {values.shape} and {noise.shape}")
        if not np.all(np.diff(time) > 0.0) or time[0] < 0.0:
            raise ValueError("measurement times must be >= 0 and strictly increasing")
        if not np.all(np.isfinite(values)):
            raise ValueError("measurement values must be finite")
        if not np.all(noise > 0.0):
            raise ValueError("every channel's noise must be > 0")


def read_measurements(path) -> Measurements:
    """:class:`Measurements` from a CSV file (format in the module docstring);
    ValueError names the file and line."""
    rows = []
    if not Path(path).is_file():
        raise ValueError(f"{path}: no such measurement file")
    with open(path, encoding="utf-8") as stream:
        for number, line in enumerate(stream, 1):
            if line.strip() and not line.lstrip().startswith("#"):
                rows.append((number, [cell.strip() for cell in line.split(",")]))
    if len(rows) < 4:
        raise ValueError(f"{path}: needs a header, a noise row and at least two samples")
    (_, header), (noise_line, noise) = rows[0], rows[1]
    if header[0] != "time" or len(header) < 2:
        raise ValueError(f"{path}: the header must be time,<channel>,...; got {header}")
    if noise[0] != "noise":
        raise ValueError(f"{path}:{noise_line}: the second row must be noise,<std>,...")

    def numbers(number, cells):
        if len(cells) != len(header):
            raise ValueError(f"{path}:{number}: {len(cells)} values, header has {len(header)}")
        try:
            return [float(c) for c in cells]
        except ValueError as error:
            raise ValueError(f"{path}:{number}: {error}") from None

    data = np.array([numbers(n, cells) for n, cells in rows[2:]])
    try:
        return Measurements(data[:, 0], header[1:], data[:, 1:],
                            numbers(noise_line, ["0"] + noise[1:])[1:])
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def write_measurements(path, measurements: Measurements, comment: str = "") -> None:
    """Write ``measurements`` as CSV, whole or not at all."""
    lines = [f"# {line}" for line in comment.splitlines()]
    lines.append(",".join(("time",) + measurements.channels))
    lines.append(",".join(["noise"] + [repr(float(x)) for x in measurements.noise]))
    for t, row in zip(measurements.time, measurements.values):
        lines.append(",".join([repr(float(t))] + [repr(float(x)) for x in row]))
    write_text(path, "\n".join(lines) + "\n")


def triangular_window(width):
    """Weights ``max(0, 1 - |dt| / width)`` of time offsets dt [s]: with ``width`` the
    output spacing, :func:`sample` interpolates linearly."""
    return lambda dt: jnp.maximum(0.0, 1.0 - jnp.abs(dt) / width)


def gaussian_window(cutoff):
    """Weights of a Gaussian low-pass filter of time offsets dt [s], its amplitude
    response ``exp(-ln 2 (f / cutoff)^2)`` one half at ``cutoff`` [Hz]: standard
    deviation ``sqrt(ln 2 / 2) / (pi cutoff)`` in time, cut at 5 of them. No overshoot,
    zero phase; at 5 x cutoff it passes 3e-8."""
    if not cutoff > 0.0:
        raise ValueError(f"the low-pass cutoff must be > 0 Hz, got {cutoff}")
    sigma = math.sqrt(math.log(2.0) / 2.0) / (math.pi * cutoff)
    return lambda dt: jnp.where(jnp.abs(dt) <= 5.0 * sigma,
                                jnp.exp(-0.5 * (dt / sigma) ** 2), 0.0)


def sample(result_t, values, times, window=None):
    """``values`` (T, C) at output times ``result_t`` (T,) seen at ``times`` (M,)
    through ``window`` (weights of the offsets t - t_m [s], e.g. :func:`gaussian_window`):
    each sample is the weighted mean of the outputs, renormalised where the window
    passes the ends. ``window`` None interpolates linearly between outputs. (M, C),
    traceable; a sample is NaN if a NaN value has weight in it.

    With a low-pass window this is the acquisition's anti-aliasing filter: slow signals
    pass, and wheel-rail contact ringing (a hundred Hz and more, above the Nyquist
    frequency of usual sample rates) is removed instead of folded into the samples with
    a phase that moves with the contact stiffness (docs/identification.md).
    """
    result_t = jnp.asarray(result_t)
    times = jnp.asarray(times)
    if window is None:
        window = triangular_window(result_t[1] - result_t[0])
    weights = window(result_t[None, :] - times[:, None])
    weights = weights / jnp.sum(weights, axis=1, keepdims=True)
    finite = jnp.isfinite(values)
    mean = weights @ jnp.where(finite, values, 0.0)
    reached = weights @ jnp.where(finite, 0.0, 1.0)
    return jnp.where(reached > 0.0, jnp.nan, mean)
