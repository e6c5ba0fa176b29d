"""EN 12299 ride comfort: frequency weightings, continuous comfort and mean comfort.

Host-side post-processing of carbody floor accelerations in plain NumPy (float64).
Nothing here is traced; JAX and SciPy are not used.

Frames: x longitudinal (direction of travel), y lateral, z vertical, all in the
carbody (floor) frame, as accelerometers fixed to the floor measure them. Accelerations
in m/s^2, frequencies in Hz, times in s. Signs do not matter: every index is an rms.

- Weightings ``Wb`` (vertical, EN 12299's own: not ISO 2631-4's Wb, see
  :data:`WEIGHTINGS`), ``Wc`` (seat back, x), ``Wd`` (horizontal, ISO 2631-1) and ``Wp``
  (roll, EN 12299; its constants are the least certain): :func:`weighting_response`,
  :func:`weighting_gain`, :func:`weight`.
- Continuous comfort Cc_x, Cc_y, Cc_z: :func:`continuous_comfort`.
- Mean comfort, standard (simplified) method N_MV: :func:`mean_comfort`,
  :func:`mean_comfort_points`, :func:`comfort_class`.

Source tags on the constants: [V-src: ...] checked against the named public source;
[R] recalled, not found in a public source.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

# Rms window of Cc and of the N_MV blocks [s]. [V-src: EN 12299:2009 contents (SAI
# Global listing: 6.6.2 "Rms-values of weighted accelerations"); "5-second sliding
# window" in the MoniRail Web Rider README; PyRidy comfort.py uses 5 s blocks]
WINDOW_S = 5.0
# N_MV evaluates a 5 min section, i.e. 60 blocks of 5 s. [V-src: railwaynews.net EN
# 12299 guide, "typically 5 minutes"; 60 blocks is 5 min / 5 s] [R] that the standard
# requires exactly one 5 min section per N_MV.
MEAN_COMFORT_BLOCKS = 60
PERCENTILE = 95.0     # [V-src: EN 12299:2009 contents 6.6.3 "95th ... percentiles"]
N_MV_FACTOR = 6.0     # N_MV = 6 sqrt(...) [V-src: PyRidy pyridy/processing/comfort.py]

# Verbal scale of N_MV: (lower bound inclusive, upper bound exclusive, class). [R] not
# found in a public source; recalled from EN 12299 (and ENV 12299).
COMFORT_SCALE = (
    (0.0, 1.0, "very comfortable"),
    (1.0, 2.0, "comfortable"),
    (2.0, 4.0, "medium"),
    (4.0, 5.0, "uncomfortable"),
    (5.0, math.inf, "very uncomfortable"),
)

# Second-order Butterworth band limits. [V-src: ISO 8041 Table via Larson Davis HVM200
# manual Table 3.1, Q1 = Q2 = 1/sqrt(2) "exact value" (ISO 2631-4 rounds it to 0.71)]
BUTTERWORTH_Q = 1.0 / math.sqrt(2.0)

# The output of weight() settles to this fraction of a start-up disturbance within the
# padding it puts before the record.
_SETTLED = 1e-10


@dataclass(frozen=True)
class Weighting:
    """Parameters of one frequency weighting [Hz; Q and gain dimensionless].

    H(s) = K Hh(s) Hl(s) Ht(s) Hs(s), with w_i = 2 pi f_i:

    - high-pass band limit  Hh = s^2 / (s^2 + w1 s / Q1 + w1^2)   (``f1 None``: Hh = 1)
    - low-pass band limit   Hl = w2^2 / (s^2 + w2 s / Q2 + w2^2)
    - a-v transition        Ht = (1 + s/w3) / (1 + s/(Q4 w4) + s^2/w4^2)
    - upward step           Hs = (1 + s/(Q5 w5) + s^2/w5^2) / (1 + s/(Q6 w6) + s^2/w6^2)
                                 * (w5/w6)^2                     (``f5 None``: Hs = 1)
    """

    name: str
    use: str
    f1: float | None
    f2: float
    f3: float
    f4: float
    q4: float
    f5: float | None
    q5: float | None
    f6: float | None
    q6: float | None
    gain: float
    q1: float = BUTTERWORTH_Q
    q2: float = BUTTERWORTH_Q


# Wc, Wd: [V-src: ISO 8041 Table "Parameters and transfer functions of the frequency
# weightings", as printed in the Larson Davis HVM200 Reference Manual, Table 3.1, every
# f, Q and K. Checked numerically: |W| at 100 rad/s is Wc 0.5145, Wd 0.1261, the ISO
# 8041 reference values listed by ZETLAB; Wd at 0.5 ... 16 Hz reproduces the ISO 2631-1
# Table 3 factors. High confidence.]
#
# Wb is EN 12299's, not ISO 2631-4's (ISO 8041's): the same corner frequencies, but
# Q4 = 0.63 (ISO: 0.55) and Q5 = Q6 = 0.8 (ISO: 0.9, 0.95); 8 % less gain at 4 Hz, 13 %
# more at 16 Hz. [V-src: the two public EN 12299 implementations found, PyRidy
# pyridy/processing/comfort.py ComfortProcessor.Wb and comfpy comfpy/filters.py Wb
# (github.com/ifs-rwth-aachen/PyRidy, github.com/tobias-bettinger/comfpy; both RWTH
# Aachen IFS, probably one transcription): f1 0.4, f2 100, f3 = f4 16, Q4 0.63, f5 2.5,
# Q5 0.8, f6 4, Q6 0.8, K 0.4, with the upward step written K (1 + s/(Q5 w5) +
# s^2/w5^2) / (1 + s/(Q6 w6) + s^2/w6^2), i.e. normalised to K at 0 Hz: here the step is
# normalised to (f5/f6)^2 at 0 Hz, so gain = 0.4 (4/2.5)^2 = 1.024, the same curve.
# NOT checked against the text of EN 12299 (not public): medium confidence.] [R, from
# review, not found in a public source] that EN 12299 keeps the Wb of ENV 12299 and
# BS 6841; a public BS 6841:1987 implementation (github.com/cseats/Footfall_app_data,
# bs6841freqweight.m) has ISO 2631-4's Q values, so that lineage is unconfirmed.
#
# Which axis takes which: Wd for x and y, Wb for z on the floor [V-src: PyRidy
# comfort.py, comfpy en12299.py]; Wc for the seat back (complete method, not implemented
# here) [R].
WEIGHTINGS: Mapping[str, Weighting] = MappingProxyType({
    "Wb": Weighting("Wb", "vertical z, floor and seat (EN 12299)",
                    f1=0.4, f2=100.0, f3=16.0, f4=16.0, q4=0.63,
                    f5=2.5, q5=0.8, f6=4.0, q6=0.8, gain=1.024),
    "Wc": Weighting("Wc", "longitudinal x, seat back (ISO 2631-1)",
                    f1=0.4, f2=100.0, f3=8.0, f4=8.0, q4=0.63,
                    f5=None, q5=None, f6=None, q6=None, gain=1.0),
    "Wd": Weighting("Wd", "horizontal x and y, floor and seat (ISO 2631-1)",
                    f1=0.4, f2=100.0, f3=2.0, f4=2.0, q4=0.63,
                    f5=None, q5=None, f6=None, q6=None, gain=1.0),
    # [V-src: PyRidy pyridy/processing/comfort.py and comfpy filters.py, Wp (both
    # RWTH Aachen IFS code, probably one author): Wd without its high-pass, f1 = 0.
    # NOT checked against the text of EN 12299: low confidence.]
    "Wp": Weighting("Wp", "roll velocity (EN 12299, comfort on curve transitions)",
                    f1=None, f2=100.0, f3=2.0, f4=2.0, q4=0.63,
                    f5=None, q5=None, f6=None, q6=None, gain=1.0),
})


@dataclass(frozen=True)
class MeanComfort:
    """Mean comfort (standard method) at one floor point.

    ``n_mv`` [1]; ``a_x_p95``, ``a_y_p95`` (Wd) and ``a_z_p95`` (Wb) [m/s^2], the 95th
    percentiles of the 5 s rms values; ``blocks``, the number of 5 s blocks used;
    ``comfort_class``, the verbal class of ``n_mv`` (:data:`COMFORT_SCALE`).
    """

    n_mv: float
    a_x_p95: float
    a_y_p95: float
    a_z_p95: float
    blocks: int
    comfort_class: str


# ---------------------------------------------------------------------------------
# Checks: all run before any computation; each message names the argument and value.


def _weighting(name) -> Weighting:
    if not isinstance(name, str) or name not in WEIGHTINGS:
        raise ValueError(f"unknown weighting {name!r}: the known weightings are "
                         f"{', '.join(WEIGHTINGS)}")
    return WEIGHTINGS[name]


def _positive(value, arg: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{arg} must be a finite number > 0, got {value!r}")
    return float(value)


def _samples(values, arg: str) -> np.ndarray:
    array = np.asarray(values)
    if array.dtype.kind not in "biuf":
        raise ValueError(f"{arg} must hold real numbers, got dtype {array.dtype}")
    if array.ndim != 1 or array.size == 0:
        raise ValueError(f"{arg} must be a non-empty 1-D array, got shape {array.shape}")
    array = array.astype(np.float64)
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f"{arg} has {bad.size} non-finite sample(s) (NaN or inf), the "
                         f"first at index {bad[0]}: {float(array[bad[0]])!r}")
    return array


def _window(window_s, sample_rate_hz: float) -> int:
    window_s = _positive(window_s, "window_s")
    n_window = round(window_s * sample_rate_hz)
    if n_window < 1:
        raise ValueError(f"window_s = {window_s!r} s at sample_rate_hz = {sample_rate_hz!r}"
                         " holds no sample")
    return n_window


def _long_enough(n: int, n_window: int, sample_rate_hz: float, window_s: float,
                 arg: str, extra: str = "") -> None:
    if n < n_window:
        raise ValueError(f"{arg}: the record has {n} samples ({n / sample_rate_hz:g} s), "
                         f"shorter than the {window_s:g} s window ({n_window} samples)"
                         f"{extra}")


def _record(accel_x, accel_y, accel_z, sample_rate_hz, min_blocks: int | None,
            where: str = "") -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The three checked channels of one floor point and the window in samples;
    `min_blocks` None: no block count needed (Cc), only one whole window."""
    channels = tuple(_samples(a, f"{where}{arg}") for a, arg in
                     ((accel_x, "accel_x"), (accel_y, "accel_y"), (accel_z, "accel_z")))
    lengths = [c.size for c in channels]
    if len(set(lengths)) > 1:
        raise ValueError(f"{where}accel_x, accel_y, accel_z must have the same length, "
                         f"got {lengths[0]}, {lengths[1]}, {lengths[2]} samples")
    n_window = _window(WINDOW_S, sample_rate_hz)
    blocks = lengths[0] // n_window
    need = "" if min_blocks is None else (
        f"; mean comfort N_MV needs {min_blocks} blocks of {WINDOW_S:g} s "
        f"({min_blocks * WINDOW_S:g} s), {blocks} available")
    _long_enough(lengths[0], n_window, sample_rate_hz, WINDOW_S,
                 f"{where}accel_x, accel_y, accel_z", need)
    if min_blocks is not None and blocks < min_blocks:
        raise ValueError(f"{where}accel_x, accel_y, accel_z: the record of "
                         f"{lengths[0] / sample_rate_hz:g} s holds {blocks} block(s) of "
                         f"{WINDOW_S:g} s, mean comfort N_MV needs min_blocks = "
                         f"{min_blocks} ({min_blocks * WINDOW_S:g} s); pass "
                         f"min_blocks={blocks} for an indicative value")
    return (*channels, n_window)


def _min_blocks(min_blocks) -> int:
    if isinstance(min_blocks, (bool, np.bool_)) or not isinstance(min_blocks, numbers.Integral) \
            or min_blocks < 1:
        raise ValueError(f"min_blocks must be an integer >= 1, got {min_blocks!r}")
    return int(min_blocks)


# ---------------------------------------------------------------------------------
# Weightings


def _response(w: Weighting, frequency_hz: np.ndarray) -> np.ndarray:
    s = 2j * np.pi * frequency_hz
    h = np.full(s.shape, w.gain, dtype=np.complex128)
    if w.f1 is not None:
        w1 = 2 * np.pi * w.f1
        h *= s**2 / (s**2 + w1 / w.q1 * s + w1**2)
    w2 = 2 * np.pi * w.f2
    h *= w2**2 / (s**2 + w2 / w.q2 * s + w2**2)
    w3, w4 = 2 * np.pi * w.f3, 2 * np.pi * w.f4
    h *= (1 + s / w3) / (1 + s / (w.q4 * w4) + (s / w4) ** 2)
    if w.f5 is not None:
        w5, w6 = 2 * np.pi * w.f5, 2 * np.pi * w.f6
        h *= ((1 + s / (w.q5 * w5) + (s / w5) ** 2) / (1 + s / (w.q6 * w6) + (s / w6) ** 2)
              * (w5 / w6) ** 2)
    return h


def weighting_response(name: str, frequency_hz):
    """Complex frequency response H(j 2 pi f) of weighting `name` ("Wb", "Wc", "Wd",
    "Wp") at `frequency_hz` [Hz] (a float or an array; the result has its shape,
    complex128). Phase convention: a cosine cos(2 pi f t) comes out as
    |H| cos(2 pi f t + angle(H))."""
    w = _weighting(name)
    f = np.asarray(frequency_hz, dtype=np.float64)
    if not np.all(np.isfinite(f)):
        raise ValueError(f"frequency_hz must be finite, got {frequency_hz!r}")
    h = _response(w, f)
    return complex(h) if h.ndim == 0 else h


def weighting_gain(name: str, frequency_hz):
    """Gain |W(f)| = |H(j 2 pi f)| of weighting `name` at `frequency_hz` [Hz] (a float
    or an array; float64, dimensionless)."""
    gain = np.abs(weighting_response(name, frequency_hz))
    return float(gain) if np.ndim(gain) == 0 else gain


def _settling_s(w: Weighting) -> float:
    """Time [s] in which the slowest pole of `w` decays to :data:`_SETTLED`."""
    sections = [(w.f1, w.q1), (w.f2, w.q2), (w.f4, w.q4), (w.f6, w.q6)]
    rates = [np.min(-np.roots([1.0, 2 * np.pi * f / q, (2 * np.pi * f) ** 2]).real)
             for f, q in sections if f is not None]
    return math.log(1 / _SETTLED) / min(rates)


def _fft_length(n: int) -> int:
    """The smallest 2^a 3^b 5^c >= n (NumPy's FFT is slow on large prime lengths)."""
    best = 1 << max(n - 1, 0).bit_length()
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


def _weight(x: np.ndarray, fs: float, w: Weighting) -> np.ndarray:
    # Constant extension with the edge values: the filter starts in the steady state of
    # the first value (a gravity offset on z starts no transient) and the wrap-around of
    # the circular convolution dies out inside the padding before the record begins.
    n_pad = math.ceil(_settling_s(w) * fs) + 1
    n_fft = _fft_length(x.size + 2 * n_pad)
    padded = np.concatenate([np.full(n_pad, x[0]), x, np.full(n_fft - n_pad - x.size, x[-1])])
    f = np.fft.rfftfreq(n_fft, d=1.0 / fs)
    y = np.fft.irfft(np.fft.rfft(padded) * _response(w, f), n=n_fft)
    return y[n_pad:n_pad + x.size]


def weight(signal, sample_rate_hz: float, name: str) -> np.ndarray:
    """The `signal` (1-D, uniformly sampled at `sample_rate_hz` [Hz]) filtered with
    weighting `name`; same length and unit (m/s^2, or rad/s for roll), float64.

    Frequency-domain filtering with the exact analogue response: the record, extended at
    both ends with its first and last value over the settling time of the weighting
    (about 13 s for Wb, Wc, Wd: their 0.4 Hz high-pass), is multiplied by
    H(j 2 pi f_k) on its FFT bins. So a sine's steady state has the gain and phase of
    H exactly at the bins and to well under 1 % between them; the output equals a
    causal analogue filter's that had seen the first value for ever. Limits: the
    weighting is applied only up to the Nyquist frequency sample_rate_hz / 2 (the
    band limit f2 = 100 Hz needs sample_rate_hz >= 200 Hz to act; comfort content is
    below 80 Hz); the first seconds carry the filter's response to the record's start
    (a slope or a change of level at t = 0), as a real instrument's would; no
    detrending is done.
    """
    w = _weighting(name)
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    return _weight(_samples(signal, "signal"), fs, w)


# ---------------------------------------------------------------------------------
# Rms values and comfort indices


def rms_blocks(signal, sample_rate_hz: float, window_s: float = WINDOW_S) -> np.ndarray:
    """Rms of `signal` over consecutive, non-overlapping blocks of `window_s` [s]
    (round(window_s * sample_rate_hz) samples each); samples after the last whole block
    are left out. Same unit as `signal`, float64, one value per block."""
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    n_window = _window(window_s, fs)
    x = _samples(signal, "signal")
    _long_enough(x.size, n_window, fs, float(window_s), "signal")
    blocks = x.size // n_window
    return np.sqrt(np.mean(x[:blocks * n_window].reshape(blocks, n_window) ** 2, axis=1))


def running_rms(signal, sample_rate_hz: float, window_s: float = WINDOW_S) -> np.ndarray:
    """Rms of `signal` over the `window_s` [s] preceding each sample: value i is the rms
    of samples i - n + 1 ... i, n = round(window_s * sample_rate_hz); NaN for the first
    n - 1 samples (no whole window yet). Same length and unit as `signal`, float64."""
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    n_window = _window(window_s, fs)
    x = _samples(signal, "signal")
    _long_enough(x.size, n_window, fs, float(window_s), "signal")
    return _running_rms(x, n_window)


def _running_rms(x: np.ndarray, n_window: int) -> np.ndarray:
    sums = np.concatenate([[0.0], np.cumsum(x**2)])
    mean_square = (sums[n_window:] - sums[:-n_window]) / n_window
    out = np.full(x.size, np.nan)
    # The difference of two cumulative sums can come out a rounding error below zero.
    out[n_window - 1:] = np.sqrt(np.maximum(mean_square, 0.0))
    return out


def continuous_comfort(accel_x, accel_y, accel_z, sample_rate_hz: float) -> dict:
    """Continuous comfort Cc_x(t), Cc_y(t) (Wd) and Cc_z(t) (Wb) at one floor point:
    the rms of the weighted floor accelerations [m/s^2] over the preceding 5 s.

    `accel_x`, `accel_y`, `accel_z`: floor accelerations [m/s^2], carbody frame, x
    longitudinal, y lateral, z vertical, sampled at `sample_rate_hz` [Hz], at least
    5 s long. Returns ``{"time_s", "cc_x", "cc_y", "cc_z"}``: arrays of the records'
    length, time from the first sample [s], Cc NaN before the first whole 5 s window.
    """
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    x, y, z, n_window = _record(accel_x, accel_y, accel_z, fs, min_blocks=None)
    return {
        "time_s": np.arange(x.size) / fs,
        "cc_x": _running_rms(_weight(x, fs, WEIGHTINGS["Wd"]), n_window),
        "cc_y": _running_rms(_weight(y, fs, WEIGHTINGS["Wd"]), n_window),
        "cc_z": _running_rms(_weight(z, fs, WEIGHTINGS["Wb"]), n_window),
    }


def comfort_class(n_mv: float) -> str:
    """Verbal class of a mean comfort value `n_mv` (:data:`COMFORT_SCALE`)."""
    if isinstance(n_mv, (bool, np.bool_)) or not isinstance(n_mv, numbers.Real) \
            or not math.isfinite(n_mv) or n_mv < 0:
        raise ValueError(f"n_mv must be a finite number >= 0, got {n_mv!r}")
    return next(label for low, high, label in COMFORT_SCALE if low <= n_mv < high)


def _mean_comfort(x: np.ndarray, y: np.ndarray, z: np.ndarray, fs: float,
                  n_window: int) -> MeanComfort:
    blocks = x.size // n_window

    def p95(a: np.ndarray, w: str) -> float:
        weighted = _weight(a, fs, WEIGHTINGS[w])[:blocks * n_window]
        rms = np.sqrt(np.mean(weighted.reshape(blocks, n_window) ** 2, axis=1))
        return float(np.percentile(rms, PERCENTILE))  # linear interpolation

    ax, ay, az = p95(x, "Wd"), p95(y, "Wd"), p95(z, "Wb")
    n_mv = N_MV_FACTOR * math.sqrt(ax**2 + ay**2 + az**2)
    return MeanComfort(n_mv, ax, ay, az, blocks, comfort_class(n_mv))


def mean_comfort(accel_x, accel_y, accel_z, sample_rate_hz: float, *,
                 min_blocks: int = MEAN_COMFORT_BLOCKS) -> MeanComfort:
    """Mean comfort N_MV, standard (simplified) method, at one floor point:

        N_MV = 6 sqrt((a_XP95^Wd)^2 + (a_YP95^Wd)^2 + (a_ZP95^Wb)^2)

    a_P95: 95th percentile (linear interpolation between ranks) of the rms values of
    the weighted acceleration over consecutive 5 s blocks. `accel_x`, `accel_y`,
    `accel_z`: floor accelerations [m/s^2], carbody frame (x longitudinal, y lateral,
    z vertical), sampled at `sample_rate_hz` [Hz]. The standard evaluates a 5 min
    section (`min_blocks` = 60 blocks); pass a smaller `min_blocks` for an indicative
    value from a shorter record, or call once per 5 min section of a longer one.
    """
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    x, y, z, n_window = _record(accel_x, accel_y, accel_z, fs, _min_blocks(min_blocks))
    return _mean_comfort(x, y, z, fs, n_window)


def mean_comfort_points(points: Mapping[str, Sequence], sample_rate_hz: float, *,
                        min_blocks: int = MEAN_COMFORT_BLOCKS) -> dict[str, MeanComfort]:
    """:func:`mean_comfort` at several named floor points, e.g. ``{"over leading
    bogie": (ax, ay, az), "centre": (...), "over trailing bogie": (...)}`` (or a
    (3, n) array per point); returns a dict with the same names. Every point is
    checked before any is computed."""
    fs = _positive(sample_rate_hz, "sample_rate_hz")
    min_blocks = _min_blocks(min_blocks)
    if not isinstance(points, Mapping) or not points:
        raise ValueError(f"points must be a non-empty mapping of name -> (accel_x, "
                         f"accel_y, accel_z), got {type(points).__name__}")
    checked = {}
    for name, channels in points.items():
        if isinstance(channels, (str, bytes)) \
                or not isinstance(channels, (Sequence, np.ndarray)) or len(channels) != 3:
            raise ValueError(f"floor point {name!r}: needs (accel_x, accel_y, accel_z), "
                             f"got {type(channels).__name__}")
        checked[name] = _record(*channels, fs, min_blocks, where=f"floor point {name!r}: ")
    return {name: _mean_comfort(x, y, z, fs, n_window)
            for name, (x, y, z, n_window) in checked.items()}
