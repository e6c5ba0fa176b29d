"""Figures of curving runs, one panel per labelled result (e.g. simplified against real
profiles, as the paper's Fig. 4): contact positions on the wheel, wheelset lateral
displacements, contact forces and the derailment ratio Y/Q.

Every function takes ``results``: a dict ``{label: SimulationResult}`` (unbatched
runs; output times not reached are left out) and writes a PNG to ``path`` whole or not
at all. Wheelset indices count from 0 = leading (labelled 1 in the figures); wheel 0 =
left, 1 = right (the outer wheel of a left curve).
"""

import numpy as np

from ._figure import subplots
from ..results import derailment_ratio, nadal_limit
from .profiles import save_figure

SIDES = ("left", "right")
DPI = 90


def _check(results, wheelset=0, wheel=None):
    if not isinstance(results, dict) or not results:
        raise ValueError("results: expected a non-empty dict {label: SimulationResult}")
    for label, r in results.items():
        shape = np.shape(r.wheels.active)
        if len(shape) != 4:
            raise ValueError(f"results[{label!r}]: wheels.active must be (T, W, 2, P), got "
                             f"{shape} (index a batched result first)")
        if not 0 <= wheelset < shape[1]:
            raise ValueError(f"wheelset: {wheelset} is not in 0..{shape[1] - 1} "
                             f"(results[{label!r}] has {shape[1]} wheelsets)")
    if wheel is not None and wheel not in (0, 1):
        raise ValueError(f"wheel: expected 0 (left) or 1 (right), got {wheel!r}")


def _panels(n, rows=1, width=4.6, height=3.4, sharey=True):
    fig, axes = subplots(rows, n, figsize=(width * n, height * rows), dpi=DPI,
                             sharey=sharey, squeeze=False)
    return fig, axes


def _finish_panel(ax, label):
    """Title, time axis, grid and legend of one panel against time."""
    ax.set_title(label, fontsize=9)
    ax.set_xlabel("time [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _valid(r):
    valid = np.asarray(r.valid, dtype=bool)
    return valid, np.asarray(r.t)[valid]


def plot_contact_positions(results, path, wheelset=0, wheel=1, colour_by="slot"):
    """The paper's Fig. 4: lateral position y_wheel [mm] of every active contact patch
    on the wheel profile (from the taping line, positive towards the field side, so the
    flange is below zero) against time [s], one panel per result, for wheel ``wheel``
    of wheelset ``wheelset`` (default the right = outer wheel of a left curve, leading
    wheelset). ``colour_by``: "slot" (patch slot) or "surface" (wheel surface, e.g.
    tread and flange of the simplified profile)."""
    _check(results, wheelset, wheel)
    if colour_by not in ("slot", "surface"):
        raise ValueError(f"colour_by: expected 'slot' or 'surface', got {colour_by!r}")
    fig, axes = _panels(len(results))
    for ax, (label, r) in zip(axes[0], results.items()):
        valid, t = _valid(r)
        active = np.asarray(r.wheels.active, dtype=bool)[valid, wheelset, wheel]
        y = 1e3 * np.asarray(r.wheels.y_wheel)[valid, wheelset, wheel]
        key = (np.arange(active.shape[1])[None, :].repeat(len(t), 0) if colour_by == "slot"
               else np.asarray(r.wheels.surface)[valid, wheelset, wheel])
        times = np.broadcast_to(t[:, None], active.shape)
        for k in np.unique(key[active]):
            pick = active & (key == k)
            ax.scatter(times[pick], y[pick], s=4, color=f"C{int(k)}", label=f"{colour_by} {k}")
        counts = active.sum(axis=1)
        ax.set_title(f"{label}: {int(np.sum(counts >= 2))}/{len(t)} samples with 2+ patches",
                     fontsize=9)
        ax.set_xlabel("time [s]")
        ax.grid(alpha=0.3)
        if np.any(active):
            ax.legend(fontsize=7, markerscale=2, loc="best")
    axes[0, 0].set_ylabel(f"contact position on wheel {wheelset + 1} {SIDES[wheel]}, "
                          "y_wheel [mm]")
    save_figure(fig, path)


def plot_lateral_displacements(results, path):
    """Lateral displacement [mm] of every wheelset's centre from the track centreline
    (positive left) against time [s], one panel per result."""
    _check(results)
    fig, axes = _panels(len(results))
    for ax, (label, r) in zip(axes[0], results.items()):
        valid, t = _valid(r)
        lateral = 1e3 * np.asarray(r.wheelset_lateral)[valid]
        for w in range(lateral.shape[1]):
            ax.plot(t, lateral[:, w], lw=1, label=f"wheelset {w + 1}")
        _finish_panel(ax, label)
    axes[0, 0].set_ylabel("lateral displacement [mm]")
    save_figure(fig, path)


def plot_forces(results, path, wheelset=0):
    """Normal force, longitudinal and lateral creep force [kN] of every active patch of
    both wheels of wheelset ``wheelset`` against time [s]: three rows, one column per
    result. Colour: wheel (left, right); line style: patch slot."""
    _check(results, wheelset)
    rows = (("normal_force", "normal force [kN]"),
            ("creep_force_x", "longitudinal creep force [kN]"),
            ("creep_force_y", "lateral creep force [kN]"))
    fig, axes = subplots(3, len(results), figsize=(4.6 * len(results), 7.5), dpi=DPI,
                             sharex="col", sharey="row", squeeze=False)
    styles = ("-", "--", ":", "-.")
    for c, (label, r) in enumerate(results.items()):
        valid, t = _valid(r)
        active = np.asarray(r.wheels.active, dtype=bool)[valid, wheelset]
        for row, (field, name) in enumerate(rows):
            ax = axes[row, c]
            value = 1e-3 * np.asarray(getattr(r.wheels, field))[valid, wheelset]
            for side in range(2):
                for slot in range(active.shape[2]):
                    on = active[:, side, slot]
                    if np.any(on):
                        ax.plot(t, np.where(on, value[:, side, slot], np.nan), lw=0.9,
                                color=f"C{side}", ls=styles[slot % len(styles)],
                                marker=".", ms=2,  # isolated samples show too
                                label=f"{SIDES[side]} slot {slot}")
            ax.grid(alpha=0.3)
            if c == 0:
                ax.set_ylabel(name)
        axes[0, c].set_title(f"{label}: wheelset {wheelset + 1}", fontsize=9)
        axes[0, c].legend(fontsize=6, ncol=2)
        axes[-1, c].set_xlabel("time [s]")
    save_figure(fig, path)


def plot_derailment_ratio(results, path, friction=0.4, wheelset=0):
    """Derailment ratio Y/Q [-] of both wheels of wheelset ``wheelset`` (default the
    leading one) against time [s], one panel per result, with Nadal's limit for
    ``friction`` and a 70 deg flange as a horizontal line. Y is the force of the wheel
    on the rail towards the field side (the Nadal convention, see jaxrail.results)."""
    _check(results, wheelset)
    limit = nadal_limit(friction)
    fig, axes = _panels(len(results))
    for ax, (label, r) in zip(axes[0], results.items()):
        valid, t = _valid(r)
        ratio = derailment_ratio(r)[valid, wheelset]
        for side in range(2):
            ax.plot(t, ratio[:, side], lw=1, color=f"C{side}",
                    label=f"wheelset {wheelset + 1} {SIDES[side]}")
        ax.axhline(limit, color="k", ls="--", lw=1, label=f"Nadal limit {limit:.2f} "
                   f"(mu = {friction:g})")
        _finish_panel(ax, label)
    axes[0, 0].set_ylabel("derailment ratio Y/Q [-]")
    save_figure(fig, path)
