"""Welch estimate of an irregularity's PSD and its confidence band (NumPy, host side):
how a realisation or a measured file is checked against its spectrum.

Units: samples ``x`` [m] at spacing ``step`` [m]; frequencies ``W`` [rad/m]; the
one-sided PSD [m^2/(rad/m)], whose integral over ``W`` is the variance (the convention
of :mod:`jaxrail.track.spectra`).
"""

import math

import numpy as np

# Welch with a Hann window and half-overlapping segments: the estimate at one frequency
# has about 2 K / (1 + 2 c^2) degrees of freedom for K segments, c = 1/6 the window's
# correlation at half a segment (Welch 1967; Percival & Walden, Spectral Analysis, 1993)
_HANN_HALF_OVERLAP = 1.0 / 6.0


def welch_psd(x, step: float, segment: int = 4096):
    """``(W (segment // 2 + 1,) [rad/m], S (..., segment // 2 + 1) [m^2/(rad/m)],
    degrees of freedom)`` of ``x`` (..., N) [m] sampled at ``step`` [m]: Hann-windowed,
    mean-removed segments of ``segment`` samples overlapping by half (``segment`` is
    cut to N when longer)."""
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[-1]
    segment = min(int(segment), n)
    hop = segment // 2
    starts = range(0, n - segment + 1, hop)
    window = 0.5 - 0.5 * np.cos(2.0 * math.pi * np.arange(segment) / segment)  # periodic Hann
    scale = 1.0 / (np.sum(window ** 2) / step)  # one-sided density per (cycle/m) below
    total = 0.0
    for k, s in enumerate(starts, start=1):
        piece = x[..., s:s + segment]
        piece = piece - piece.mean(axis=-1, keepdims=True)
        total = total + np.abs(np.fft.rfft(window * piece, axis=-1)) ** 2
    count = k
    density = total / count * scale  # two-sided per cycle/m
    density[..., 1:] *= 2.0  # one-sided
    if segment % 2 == 0:
        density[..., -1] /= 2.0
    freq = 2.0 * math.pi * np.fft.rfftfreq(segment, d=step)  # rad/m
    dof = 2.0 * count / (1.0 + 2.0 * _HANN_HALF_OVERLAP ** 2)
    return freq, density / (2.0 * math.pi), dof


def chi2_quantile(p: float, dof: float) -> float:
    """Quantile of the chi-squared distribution (Wilson-Hilferty: within 1 % for 10 or more
    degrees of freedom)."""
    z = _normal_quantile(p)
    c = 2.0 / (9.0 * dof)
    return dof * (1.0 - c + z * math.sqrt(c)) ** 3


def _normal_quantile(p: float) -> float:
    """Standard normal quantile by bisection on erf (host, once per figure)."""
    lo, hi = -10.0, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def confidence_band(dof: float, level: float = 0.95) -> tuple[float, float]:
    """Factors ``(low, high)`` on the true PSD between which a Welch estimate with
    ``dof`` degrees of freedom lies with probability ``level``."""
    tail = 0.5 * (1.0 - level)
    return chi2_quantile(tail, dof) / dof, chi2_quantile(1.0 - tail, dof) / dof
