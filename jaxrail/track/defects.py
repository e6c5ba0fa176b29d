"""Isolated track defects: a single cosine dip, the classic test input.

``cosine_defect("lateral", wavelength=10.0, amplitude=0.005, position=60.0)`` moves the
track centre by

    d(s) = -amplitude (1 - cos(2 pi (s - position) / wavelength)) / 2

for ``position <= s <= position + wavelength`` and leaves it at zero elsewhere: a dip
of depth ``amplitude`` [m] (the rails move right for "lateral", down for "vertical";
a negative amplitude moves them left or up). Both rails move together (the alignment
or vertical-level channel). The dip is sampled at a fortieth of its wavelength by
default (at most 0.25 m), with a sample at both of its ends; the interpolation
follows the cosine within 0.05 % of its depth.
"""

import math

import numpy as np

from .irregularity import CHANNELS, sampled

DEFECT_KINDS = {"lateral": "alignment", "vertical": "vertical"}
"""Defect kinds and the channel each moves."""


def cosine_defect(kind: str, wavelength: float, amplitude: float, position: float,
                  step: float | None = None):
    """:class:`~jaxrail.track.irregularity.Irregularity` of one cosine dip (module
    docstring): ``kind`` "lateral" or "vertical", ``wavelength`` [m] > 0, ``amplitude``
    [m], ``position`` [m] the arc length where it starts; ``step`` [m] the sample
    spacing (default a fortieth of the wavelength, at most 0.25 m)."""
    if kind not in DEFECT_KINDS:
        raise ValueError(f"unknown defect kind {kind!r}: use one of {', '.join(DEFECT_KINDS)}")
    for name, value in (("wavelength", wavelength), ("amplitude", amplitude),
                        ("position", position)):
        if not math.isfinite(float(value)):
            raise ValueError(f"defect {name} must be a finite number, got {value!r}")
    if not wavelength > 0.0:
        raise ValueError(f"defect wavelength must be > 0 m, got {wavelength}")
    step = min(wavelength / 40.0, 0.25) if step is None else float(step)
    if not 0.0 < step <= wavelength / 20.0:
        raise ValueError(f"defect step must be in (0, wavelength / 20 = {wavelength / 20} m], "
                         f"got {step}")
    intervals = int(math.ceil(wavelength / step - 1e-9))
    step = wavelength / intervals  # a sample at both ends of the dip
    count = intervals + 1
    # two zero samples before and after, so that the interpolation's slopes at the ends
    # are zero too
    s = position + step * np.arange(-2, count + 2)
    phase = np.clip((s - position) / wavelength, 0.0, 1.0)
    dip = -0.5 * amplitude * (1.0 - np.cos(2.0 * math.pi * phase))
    values = np.zeros((len(s), len(CHANNELS)))
    values[:, CHANNELS.index(DEFECT_KINDS[kind])] = dip
    return sampled(values, s[0], step)
