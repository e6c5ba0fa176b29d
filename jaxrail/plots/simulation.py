"""Figures of a simulation result: wheelset lateral displacements and wheel loads."""

import numpy as np

from ._figure import subplots
from .profiles import save_figure

SIDES = ("left", "right")


def plot_wheelsets(result, path, title=""):
    """Two panels against time: each wheelset's lateral displacement from the track
    centreline [mm], and each wheel's vertical load Q [kN]. Saved as PNG to ``path``."""
    valid = np.asarray(result.valid)
    t = np.asarray(result.t)[valid]
    lateral = 1e3 * np.asarray(result.wheelset_lateral)[valid]
    load = 1e-3 * np.asarray(result.wheels.vertical_force)[valid]
    fig, (top, bottom) = subplots(2, 1, figsize=(8, 6), sharex=True)
    for w in range(lateral.shape[1]):
        top.plot(t, lateral[:, w], label=f"wheelset {w + 1}")
        for s, style in zip(range(2), ("-", "--")):
            bottom.plot(t, load[:, w, s], style, color=f"C{w}", lw=1,
                        label=f"{w + 1} {SIDES[s]}")
    top.set_ylabel("lateral displacement [mm]")
    top.legend(fontsize=8, ncol=4)
    top.grid(alpha=0.3)
    bottom.set_ylabel("wheel load Q [kN]")
    bottom.set_xlabel("time [s]")
    bottom.legend(fontsize=7, ncol=4)
    bottom.grid(alpha=0.3)
    if title:
        top.set_title(title)
    save_figure(fig, path)
