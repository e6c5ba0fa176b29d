"""Figures of track irregularities: a realisation's PSD against its spectrum."""

import math

import numpy as np

from ..track.irregularity import CHANNELS
from ..track.psd import confidence_band, welch_psd
from ._figure import subplots

_TITLES = {"alignment": "alignment", "vertical": "vertical level",
           "cross_level": "cross level (left over right rail)", "gauge": "gauge deviation"}


def plot_irregularity_psd(irregularity, spectrum, band, path, title=None, segment=None):
    """Welch PSD of each channel of ``irregularity`` [m^2/(rad/m)] against ``spectrum``
    (:mod:`jaxrail.track.spectra`) over ``band`` (shortest, longest wavelength [m]), with
    the 95 % band in which a Welch estimate of that spectrum lies (segments of ``segment``
    samples: by default the largest power of two up to 4096 that fits eight times);
    PNG at ``path``."""
    values = np.asarray(irregularity.values).T * float(irregularity.scale)
    if segment is None:
        segment = max(256, min(4096, 2 ** int(math.log2(max(values.shape[-1] // 8, 1)))))
    step = float(irregularity.step)
    freq, psd, dof = welch_psd(values, step, segment)
    low, high = confidence_band(dof)
    inside = (freq >= 2 * math.pi / band[1]) & (freq <= 2 * math.pi / band[0])
    reference = np.asarray(spectrum.psd(np.where(freq > 0, freq, 1.0)))
    fig, axes = subplots(2, 2, figsize=(10, 7), dpi=110)
    for ax, name, estimate, expected in zip(axes.flat, CHANNELS, psd, reference):
        if not np.any(expected[inside] > 0):
            ax.text(0.5, 0.5, "not in this spectrum", ha="center", transform=ax.transAxes)
            ax.set_title(_TITLES[name])
            continue
        ax.loglog(freq[1:], estimate[1:], color="0.55", lw=0.8, label="Welch PSD")
        ax.loglog(freq[inside], expected[inside], color="C0", lw=1.6, label="spectrum")
        ax.fill_between(freq[inside], low * expected[inside], high * expected[inside],
                        color="C0", alpha=0.2, lw=0, label=f"95 % band ({dof:.0f} dof)")
        ax.set_title(_TITLES[name])
        ax.set_xlabel("W [rad/m]")
        ax.set_ylabel("PSD [m$^2$/(rad/m)]")
        ax.set_xlim(0.5 * 2 * math.pi / band[1], 2.0 * 2 * math.pi / band[0])
        ax.set_ylim(0.1 * low * expected[inside].min(), 10.0 * high * expected[inside].max())
        ax.grid(True, which="both", alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle(title or f"{getattr(spectrum, 'name', 'spectrum')}: one realisation")
    fig.tight_layout()
    fig.savefig(path)
