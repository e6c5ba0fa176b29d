"""Signal processing for the EN 14363 assessment quantities: the standard's filters,
sliding windows over the distance travelled, percentiles and the instability frequency.

Plain NumPy float64 on the host; nothing here is traced. Channels are sampled in time
(axis 0, uniform sample rate) and the distance travelled is known at every sample.

**Filters.** EN 14363 defines each filter by its type, corner frequencies and order: a
Butterworth low-pass (20 Hz for the forces) or band-pass (0.4-10 Hz for carbody
accelerations, f0 +- 2 Hz for the instability criterion). Their defining transfer
function is the analogue Butterworth ``H(j 2 pi f)``, and that is what is applied here,
exactly, in the frequency domain: the record is extended at both ends by its mirror
image (long enough for the filter's impulse response to decay), transformed, multiplied
by ``H`` at each discrete frequency and transformed back. A sine that fills the record
comes out with the gain ``|H|`` and the phase ``arg H`` of the analogue filter, which
the tests check to 1 %. Two common alternatives are not the defining transfer
function: a bilinear-transformed digital filter warps the frequency axis, and a
zero-phase (forward-backward) filter squares the gain and removes the phase. Being
non-causal over the mirrored extension, the filter here also has start and end
transients unlike a measuring amplifier's; they last about the settling time passed to
:func:`apply_response` and are why the records must be longer than the windows.

**Windows.** A sliding mean over ``window`` metres of track is the integral of the
piecewise-linear interpolant of the samples over the distance, divided by ``window``;
windows are centred every ``step`` metres from ``window / 2`` after the first sample to
``window / 2`` before the last, so each lies wholly inside the record. A sliding rms is
the square root of the sliding mean of the square.
"""

import warnings

import numpy as np

# A relative spread of the sampling interval above this is not uniform sampling.
UNIFORM_SAMPLING_TOLERANCE = 1e-6
# Mirror extension of each end: this many periods of the filter's slowest corner or
# bandwidth, so that its impulse response has decayed before it reaches the record.
SETTLING_PERIODS = 10.0



def check_finite(name, x):
    """``x``, or ValueError naming ``name`` and how many samples are not finite."""
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: {np.count_nonzero(~np.isfinite(x))} samples are not "
                         "finite")
    return x

def _f64(x):
    return np.asarray(x, dtype=np.float64)


def sample_rate(time) -> float:
    """The sample rate [Hz] of the uniformly sampled times ``time`` [s] (T,); a
    ValueError if they are not finite, strictly increasing and uniform."""
    t = _f64(time)
    if t.ndim != 1 or len(t) < 2:
        raise ValueError(f"time: expected a 1-D array of at least 2 samples, got shape "
                         f"{t.shape}")
    check_finite("time", t)
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        k = int(np.argmax(dt <= 0.0))
        raise ValueError(f"time: not increasing at sample {k + 1} ({t[k]!r} s, then "
                         f"{t[k + 1]!r} s)")
    spacing = float(np.median(dt))
    spread = float(np.max(np.abs(dt - spacing))) / spacing
    if spread > UNIFORM_SAMPLING_TOLERANCE:
        raise ValueError(f"time: not uniformly sampled (the spacing varies by "
                         f"{spread:.2g} of {spacing:.6g} s); the filters need a uniform "
                         "sample rate, resample first")
    return 1.0 / spacing


def _butterworth_prototype(p, order):
    """The normalised analogue Butterworth low-pass prod_k (-p_k) / (p - p_k) at the
    complex points ``p`` (cut-off 1 rad/s; unit gain at p = 0)."""
    k = np.arange(1, order + 1)
    poles = np.exp(1j * np.pi * (2 * k + order - 1) / (2 * order))
    h = np.ones(np.shape(p), dtype=np.complex128)
    for pole in poles:
        h = h * (-pole / (p - pole))
    return h


def butterworth_lowpass(frequency, cutoff, order=4):
    """H(j 2 pi f) of the analogue Butterworth low-pass of ``order`` with the -3 dB
    ``cutoff`` [Hz], at ``frequency`` [Hz] (any shape)."""
    if not cutoff > 0.0:
        raise ValueError(f"cutoff: must be positive, got {cutoff!r} Hz")
    return _butterworth_prototype(1j * _f64(frequency) / cutoff, int(order))


def butterworth_bandpass(frequency, low, high, order=4):
    """H(j 2 pi f) of the analogue Butterworth band-pass from ``low`` to ``high`` [Hz]
    (-3 dB edges): the low-pass prototype of ``order`` with s -> (s^2 + w0^2) / (s B),
    w0 = 2 pi sqrt(low high), B = 2 pi (high - low) (the transform of
    ``scipy.signal.butter(order, ..., "bandpass", analog=True)``; order 2 ``order``
    overall, unit gain at sqrt(low high), zero at 0 Hz)."""
    if not 0.0 < low < high:
        raise ValueError(f"band-pass edges: need 0 < low < high, got {low!r} and "
                         f"{high!r} Hz")
    f = _f64(frequency)
    safe = np.where(f == 0.0, 1.0, f)
    p = 1j * (safe ** 2 - low * high) / (safe * (high - low))
    return np.where(f == 0.0, 0.0, _butterworth_prototype(p, int(order)))


def apply_response(values, rate, response, settling_time):
    """``values`` (T, ...) sampled at ``rate`` [Hz] along axis 0 through the transfer
    function ``response(frequency [Hz]) -> H`` (see the module docstring): mirror
    extension of ``settling_time`` [s] at each end, FFT, product with H, inverse FFT."""
    if not (np.isfinite(rate) and rate > 0.0):
        raise ValueError(f"sample rate: must be positive and finite, got {rate!r} Hz")
    x = _f64(values)
    if x.ndim == 0 or x.shape[0] < 2:
        raise ValueError(f"filter: need at least 2 samples along axis 0, got shape "
                         f"{x.shape}")
    n = x.shape[0]
    pad = int(np.ceil(settling_time * rate))
    widths = [(pad, pad)] + [(0, 0)] * (x.ndim - 1)
    padded = np.pad(x, widths, mode="reflect")
    spectrum = np.fft.rfft(padded, axis=0)
    h = response(np.fft.rfftfreq(padded.shape[0], d=1.0 / rate))
    h = h.reshape((-1,) + (1,) * (x.ndim - 1))
    out = np.fft.irfft(spectrum * h, n=padded.shape[0], axis=0)
    return out[pad:pad + n]


def lowpass(values, rate, cutoff, order=4):
    """``values`` (T, ...) through the analogue Butterworth low-pass (axis 0)."""
    return apply_response(values, rate, lambda f: butterworth_lowpass(f, cutoff, order),
                          SETTLING_PERIODS / cutoff)


def bandpass(values, rate, low, high, order=4):
    """``values`` (T, ...) through the analogue Butterworth band-pass (axis 0)."""
    return apply_response(values, rate,
                          lambda f: butterworth_bandpass(f, low, high, order),
                          SETTLING_PERIODS / min(low, high - low))


def check_distance(distance, n_samples, needed=None, what=""):
    """The distance travelled [m] (T,) as float64, after checking that it is finite,
    non-decreasing, has ``n_samples`` samples and, given ``needed`` [m], covers it."""
    s = _f64(distance)
    if s.shape != (n_samples,):
        raise ValueError(f"distance: expected shape ({n_samples},) like time, got "
                         f"{s.shape}")
    check_finite("distance", s)
    if np.any(np.diff(s) < 0.0):
        k = int(np.argmax(np.diff(s) < 0.0))
        raise ValueError(f"distance: decreases at sample {k + 1} ({s[k]!r} m, then "
                         f"{s[k + 1]!r} m); it is the distance travelled")
    if needed is not None and s[-1] - s[0] < needed:
        raise ValueError(f"distance: the record covers {s[-1] - s[0]:.4g} m of track; "
                         f"{what or 'the window'} needs at least {needed:.4g} m")
    return s


def window_centres(distance, window, step):
    """Centres [m] of the sliding windows of ``window`` metres every ``step`` metres
    that lie wholly inside the record ``distance`` (T,)."""
    if not (window > 0.0 and step > 0.0):
        raise ValueError(f"sliding window: window and step must be positive, got "
                         f"{window!r} m and {step!r} m")
    s = check_distance(distance, len(np.atleast_1d(distance)), window,
                       f"a sliding window of {window:g} m")
    count = int(np.floor((s[-1] - s[0] - window) / step + 1e-9)) + 1
    return s[0] + 0.5 * window + step * np.arange(count)


def _integral_at(values, distance, points):
    """The integral of the piecewise-linear interpolant of ``values`` (T, ...) over the
    distance from its first sample to each of ``points`` (P,): shape (P, ...)."""
    x, s = values, distance
    ds = np.diff(s)
    shape = (-1,) + (1,) * (x.ndim - 1)
    nodes = np.concatenate([np.zeros((1,) + x.shape[1:]),
                            np.cumsum(0.5 * (x[1:] + x[:-1]) * ds.reshape(shape), axis=0)])
    k = np.clip(np.searchsorted(s, points, side="right") - 1, 0, len(s) - 2)
    d = (points - s[k]).reshape(shape)
    width = ds[k].reshape(shape)
    slope = np.where(width > 0.0, (x[k + 1] - x[k]) / np.where(width > 0.0, width, 1.0),
                     0.0)
    return nodes[k] + x[k] * d + 0.5 * slope * d * d


def sliding_mean(values, distance, window, step):
    """(centres [m] (P,), means (P, ...)): the mean of ``values`` (T, ...) over each
    window of ``window`` metres of track, every ``step`` metres (module docstring). A
    window that holds a NaN sample is NaN."""
    x = _f64(values)
    s = check_distance(distance, x.shape[0] if x.ndim else 0)
    centres = window_centres(s, window, step)
    bad = ~np.isfinite(x)
    clean = np.where(bad, 0.0, x)
    lo, hi = centres - 0.5 * window, centres + 0.5 * window
    means = (_integral_at(clean, s, hi) - _integral_at(clean, s, lo)) / window
    if np.any(bad):
        # A NaN sample taints every window that reaches into either of its segments.
        flagged = bad.astype(np.float64)
        reach = _integral_at(flagged, s, hi) - _integral_at(flagged, s, lo)
        means = np.where(reach > 0.0, np.nan, means)
    return centres, means


def sliding_rms(values, distance, window, step):
    """(centres [m] (P,), rms (P, ...)): the root mean square of ``values`` (T, ...)
    over each window of ``window`` metres every ``step`` metres."""
    centres, mean_square = sliding_mean(np.square(_f64(values)), distance, window, step)
    return centres, np.sqrt(mean_square)


def percentile(values, p):
    """The ``p`` % value (0..100) of the finite ``values`` along axis 0 (linear
    interpolation between order statistics, NumPy's default); NaN where none is
    finite."""
    x = _f64(values)
    finite = np.isfinite(x)
    if np.all(finite):
        return np.percentile(x, p, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns give NaN
        return np.nanpercentile(np.where(finite, x, np.nan), p, axis=0)


def two_sided_extreme(values, low=0.15, high=99.85):
    """max(|F(low)|, |F(high)|) along axis 0: the largest magnitude a two-sided
    quantity reaches, from its ``low`` and ``high`` percentiles."""
    return np.maximum(np.abs(percentile(values, low)), np.abs(percentile(values, high)))


def dominant_frequency(values, rate, band):
    """The frequency [Hz] of the largest peak of the spectrum of ``values`` (T,) inside
    ``band`` = (low, high) [Hz]: Hann-windowed periodogram of the record with its mean
    and linear trend removed, refined by a parabola through the logarithms of the peak
    bin and its neighbours. NaN where the band holds no frequency bin."""
    x = _f64(values)
    n = len(x)
    t = np.arange(n)
    x = x - np.polyval(np.polyfit(t, x, 1), t) if n > 2 else x - np.mean(x)
    spectrum = np.abs(np.fft.rfft(x * np.hanning(n))) ** 2
    f = np.fft.rfftfreq(n, d=1.0 / rate)
    inside = np.flatnonzero((f >= band[0]) & (f <= band[1]))
    if len(inside) == 0:
        return float("nan")
    k = int(inside[np.argmax(spectrum[inside])])
    if 0 < k < len(f) - 1 and np.all(spectrum[k - 1:k + 2] > 0.0):
        a, b, c = np.log(spectrum[k - 1:k + 2])
        denominator = a - 2.0 * b + c
        shift = 0.5 * (a - c) / denominator if denominator < 0.0 else 0.0
        return float(f[k] + shift * (f[1] - f[0]))
    return float(f[k])
