"""Track irregularity spectra and realisations drawn from them.

Spatial angular frequency ``W`` [rad/m] = 2 pi / wavelength; one-sided power spectral
densities ``S(W)`` in m^2/(rad/m) per channel of :data:`.irregularity.CHANNELS` (the
cross-level channel as the height difference of the rails, in m^2/(rad/m)). The
variance of a channel over a band of wavelengths is the integral of ``S`` over that
band of ``W`` (:func:`band_variance`). Constants and their sources: docs/track.md.

- **ORE B176 / ERRI "German"**, low and high level (``german-low``, ``german-high``):
  ``S_v = A_v Wc^2 / ((W^2 + Wr^2)(W^2 + Wc^2))``, alignment the same with ``A_a``;
  cross level as an angle ``S = (A_v / b^2) Wc^2 W^2 / ((W^2 + Wr^2)(W^2 + Wc^2)(W^2 +
  Ws^2))`` with ``b = 0.75`` m, here times ``(2 b)^2`` for the height difference; gauge
  ``S_g = A_g Wc^2 W^2 / ((W^2 + Wr^2)(W^2 + Wc^2)(W^2 + Ws^2))``.
- **FRA classes 1-6** (``fra-1`` ... ``fra-6``), vertical and alignment:
  ``S = k A Wc^2 / (W^2 (W^2 + Wc^2))`` with ``k = 0.25``, ``A`` in cm^2 rad/m; the
  cross-level and gauge channels of an FRA realisation are zero.

A realisation is a sum of cosines ``z(x) = sum_k sqrt(2 S(W_k) dW) cos(W_k x +
phi_k)`` over the frequencies ``W_k = k dW`` of the band, ``dW = 2 pi / L`` for a
generation length ``L`` of at least four times the longest wavelength, phases
``phi_k`` uniform from ``jax.random`` with the seed (one independent set per channel),
evaluated at the samples by an inverse real FFT. It is reproducible from the seed,
traceable in the seed and the scale (Monte Carlo draws both inside a vmapped program),
and its band variances equal the spectrum's sums over the same frequencies.
"""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from .irregularity import Irregularity

HALF_RAIL_DISTANCE = 0.75  # [m] b of the German cross-level spectrum
DEFAULT_BAND = (3.0, 150.0)  # [m] wavelengths: EN 13848's D1-D3 (3-25, 25-70, 70-150 m)
MAX_SAMPLES = 4_000_000  # samples of one realisation (128 MB of float64 channels)


def _stack(channels):
    """The channels stacked as NumPy for NumPy input (host: realisations are built from
    NumPy amplitudes, also inside jit), as JAX otherwise."""
    if any(isinstance(x, jax.Array) for x in channels):
        return jnp.stack(channels)
    return np.stack(channels)


@dataclasses.dataclass(frozen=True)
class GermanSpectrum:
    """ORE B176 "German" spectrum: ``level`` coefficients ``a_v``, ``a_a``, ``a_g`` [m rad]
    and the corner frequencies ``wc``, ``wr``, ``ws`` [rad/m]."""

    name: str
    a_v: float
    a_a: float
    a_g: float
    wc: float = 0.8246
    wr: float = 0.0206
    ws: float = 0.4380

    def psd(self, w):
        """One-sided PSDs (4, ...) [m^2/(rad/m)] of :data:`CHANNELS` at ``w`` [rad/m]."""
        w2 = w * w
        base = self.wc ** 2 / ((w2 + self.wr ** 2) * (w2 + self.wc ** 2))
        high = w2 / (w2 + self.ws ** 2)
        # the angle spectrum (A_v / b^2) ... times (2 b)^2, the rails' height difference
        cross = (2.0 * HALF_RAIL_DISTANCE) ** 2 / HALF_RAIL_DISTANCE ** 2 * self.a_v * base * high
        return _stack([self.a_a * base, self.a_v * base, cross, self.a_g * base * high])


@dataclasses.dataclass(frozen=True)
class FraSpectrum:
    """FRA track class spectrum: ``a_v``, ``a_a`` [cm^2 rad/m], ``wc`` [rad/m], ``k``."""

    name: str
    a_v: float
    a_a: float
    wc: float = 0.8245
    k: float = 0.25

    def psd(self, w):
        """One-sided PSDs (4, ...) [m^2/(rad/m)] of :data:`CHANNELS` at ``w`` [rad/m]."""
        w2 = w * w
        base = 1e-4 * self.k * self.wc ** 2 / (w2 * (w2 + self.wc ** 2))  # cm^2 -> m^2
        zero = 0.0 * base
        return _stack([self.a_a * base, self.a_v * base, zero, zero])


_FRA = ((1.2107, 3.3634), (1.0181, 1.2107), (0.6816, 0.4128), (0.5376, 0.3027),
        (0.2095, 0.0762), (0.0339, 0.0339))
SPECTRA = {
    "german-low": GermanSpectrum("german-low", a_v=4.032e-7, a_a=2.119e-7, a_g=5.32e-8),
    "german-high": GermanSpectrum("german-high", a_v=1.080e-6, a_a=6.125e-7, a_g=1.032e-7),
    **{f"fra-{k + 1}": FraSpectrum(f"fra-{k + 1}", a_v=v, a_a=a) for k, (v, a) in enumerate(_FRA)},
}
"""The spectra by name."""


def spectrum(name: str):
    """The spectrum called ``name`` (:data:`SPECTRA`); ValueError lists the names."""
    if name not in SPECTRA:
        raise ValueError(f"unknown irregularity spectrum {name!r}: use one of "
                         f"{', '.join(SPECTRA)}")
    return SPECTRA[name]


def check_band(band) -> tuple[float, float]:
    """``band`` (shortest, longest wavelength) [m] as floats, or ValueError."""
    try:
        lo, hi = (float(x) for x in band)
    except (TypeError, ValueError):
        raise ValueError(f"irregularity band must be two wavelengths [m] (shortest, "
                         f"longest), got {band!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo):
        raise ValueError(f"irregularity band must be two positive wavelengths [m], got {band!r}")
    if not lo < hi:
        raise ValueError(f"irregularity band ({lo}, {hi}) m has its ends swapped or equal: give "
                         "the shortest wavelength first, e.g. (3, 150)")
    return lo, hi


def band_variance(spectrum_, band) -> np.ndarray:
    """Variance (4,) [m^2] of each channel over ``band`` (shortest, longest wavelength
    [m]): the integral of the PSD over the band's frequencies, by 400-point
    Gauss-Legendre quadrature in log W (the reference the realisations are checked
    against)."""
    lo, hi = check_band(band)
    x, w = np.polynomial.legendre.leggauss(400)
    a, b = math.log(2 * math.pi / hi), math.log(2 * math.pi / lo)
    log_w = 0.5 * (b - a) * x + 0.5 * (b + a)
    freq = np.exp(log_w)
    values = spectrum_.psd(freq)
    return 0.5 * (b - a) * np.sum(w * freq * values, axis=-1)


def _generation_size(samples: int, step: float, band) -> int:
    """FFT length: at least the samples and four times the longest wavelength, even."""
    longest = 4.0 * band[1] / step
    n = max(samples, int(math.ceil(longest)))
    return n + n % 2


def realisation(spectrum_, length: float, step: float = 0.25, seed=0, band=DEFAULT_BAND,
                scale=1.0, start: float = 0.0) -> Irregularity:
    """One realisation of ``spectrum_`` (a name of :data:`SPECTRA` or a spectrum) over
    ``[start, start + length]`` [m] at spacing ``step`` [m], the wavelengths of ``band``
    [m] (module docstring). ``seed`` (int, may be traced) picks the phases; ``scale``
    (may be traced) multiplies every channel."""
    spec = spectrum(spectrum_) if isinstance(spectrum_, str) else spectrum_
    band = check_band(band)
    length, step = float(length), float(step)
    if not (math.isfinite(step) and step > 0.0):
        raise ValueError(f"irregularity step must be > 0 m, got {step}")
    if not (math.isfinite(length) and length > 0.0):
        raise ValueError(f"irregularity length must be > 0 m, got {length}")
    if 2.0 * step > band[0]:
        raise ValueError(f"irregularity step {step} m cannot carry the band's shortest "
                         f"wavelength {band[0]} m: use a step of at most {band[0] / 2} m")
    samples = int(math.ceil(length / step - 1e-9)) + 1
    if samples > MAX_SAMPLES:
        raise ValueError(f"irregularity of {length} m at {step} m: {samples} samples, at most "
                         f"{MAX_SAMPLES}")
    if isinstance(scale, (int, float)) and not scale >= 0.0:
        raise ValueError(f"irregularity amplitude scale must be >= 0, got {scale}")
    return Irregularity(_draw(spec, samples, step, band, seed), start, step, scale)


def component_amplitudes(spectrum_, size: int, step: float, band) -> np.ndarray:
    """Amplitudes (4, size // 2 + 1) [m] of the cosines at ``W_k = 2 pi k / (size
    step)``: ``sqrt(2 S(W_k) dW)`` inside ``band``, zero outside (and at ``k = 0`` and
    the Nyquist frequency)."""
    dw = 2.0 * math.pi / (size * step)
    w = dw * np.arange(size // 2 + 1)
    inside = (w >= 2.0 * math.pi / band[1]) & (w <= 2.0 * math.pi / band[0])
    inside[0] = inside[-1] = False
    psd = spectrum_.psd(np.where(inside, w, 1.0))
    return np.where(inside, np.sqrt(2.0 * psd * dw), 0.0)


def _draw(spec, samples, step, band, seed):
    """The channels (samples, 4) [m] of the realisation with ``seed``."""
    size = _generation_size(samples, step, band)
    amplitude = jnp.asarray(component_amplitudes(spec, size, step, band))
    key = jax.random.key(jnp.asarray(seed, dtype=jnp.uint32))
    phase = jax.random.uniform(key, amplitude.shape, dtype=jnp.float64, maxval=2.0 * math.pi)
    # irfft: x_n = (1/N) sum_k C_k e^{i 2 pi k n / N} over the full spectrum; a cosine of
    # amplitude A needs C_k = (N / 2) A e^{i phi}
    coefficients = 0.5 * size * amplitude * jnp.exp(1j * phase)
    return jnp.fft.irfft(coefficients, n=size, axis=-1)[:, :samples].T
