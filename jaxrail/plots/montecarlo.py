"""Figures of a Monte Carlo table (:mod:`jaxrail.montecarlo`): maps of the summary
quantities over two inputs (default speed and misalignment) and their distributions.

Each quantity is the worst over the vehicle's wheelsets or wheels (the largest of the
columns ``<name>_1...``); Y/Q and Sum Y are shown against their limits (Nadal,
Prud'homme) as utilisations, where 1 is the limit. Samples that did not finish
successfully are drawn as crosses and left out of the contours.
"""

import re

import numpy as np

from ._figure import subplots
from .profiles import save_figure

# (title, unit, function of the table -> one value per sample)
QUANTITIES = {
    "max_lateral_displacement": ("max lateral displacement", "mm",
                                 lambda t: 1e3 * worst(t, "max_lateral_displacement_")),
    "Y_over_Q_utilisation": ("max Y/Q / Nadal limit", "-",
                             lambda t: worst(t, "max_Y_over_Q_") / t["nadal_limit"]),
    "Y_over_Q_mean_utilisation": ("max Y/Q (2 m) / Nadal limit", "-",
                                  lambda t: worst(t, "max_Y_over_Q_mean_") / t["nadal_limit"]),
    "sum_Y_utilisation": ("max Sum Y (2 m) / Prud'homme limit", "-",
                          lambda t: worst(t, "max_sum_Y_", "prudhomme_limit_")),
    "max_normal_force": ("max normal force", "kN", lambda t: 1e-3 * t["max_normal_force_N"]),
    "flange_contact_fraction": ("flange contact fraction (worst wheel)", "-",
                                lambda t: worst(t, "flange_contact_fraction_")),
    "wear_number": ("mean wear number T gamma (worst wheel)", "N",
                    lambda t: worst(t, "wear_number_")),
}
INPUT_UNITS = {"speed": ("m/s", 1.0), "misalignment": ("mm", 1e3)}


def worst(table, prefix, limit_prefix=None):
    """Per sample, the largest of the columns ``prefix<k>...`` (divided column by
    column by ``limit_prefix<k>...`` when given); NaN where all are NaN."""
    names = sorted(n for n in table if n.startswith(prefix) and re.match(r"\d", n[len(prefix):]))
    if not names:
        raise ValueError(f"table has no columns {prefix}<k>...")
    columns = []
    for name in names:
        values = np.asarray(table[name], dtype=np.float64)
        if limit_prefix is not None:
            values = values / np.asarray(table[limit_prefix + name[len(prefix):]], np.float64)
        columns.append(values)
    stacked = np.stack(columns)
    finite = np.isfinite(stacked)
    best = np.max(np.where(finite, stacked, -np.inf), axis=0)
    return np.where(np.any(finite, axis=0), best, np.nan)


def _axis(table, name):
    unit, scale = INPUT_UNITS.get(name, ("", 1.0))
    return np.asarray(table[name], np.float64) * scale, f"{name} [{unit}]" if unit else name


def _panels(height):
    """A figure with one panel per quantity, four to a row (unused panels hidden)."""
    rows = -(-len(QUANTITIES) // 4)
    fig, axes = subplots(rows, 4, figsize=(18.0, height * rows / 2), dpi=90)
    for ax in axes.flat[len(QUANTITIES):]:
        ax.set_visible(False)
    return fig, axes


def plot_maps(table, path, x="speed", y="misalignment"):
    """One panel per quantity over inputs ``x`` and ``y`` (PNG at ``path``)."""
    xs, xlabel = _axis(table, x)
    ys, ylabel = _axis(table, y)
    ok = np.asarray(table["status"]) == "successful"
    fig, axes = _panels(8.0)
    for ax, (key, (title, unit, value)) in zip(axes.flat, QUANTITIES.items()):
        z = value(table)
        good = ok & np.isfinite(z)
        if np.sum(good) >= 6 and np.ptp(xs[good]) > 0 and np.ptp(ys[good]) > 0:
            contour = ax.tricontourf(xs[good], ys[good], z[good], levels=12, cmap="viridis")
            fig.colorbar(contour, ax=ax, label=unit)
            if key.endswith("utilisation") and np.nanmax(z[good]) >= 1.0:
                ax.tricontour(xs[good], ys[good], z[good], levels=[1.0], colors="red")
        ax.scatter(xs[good], ys[good], s=4, c="k", alpha=0.4)
        ax.scatter(xs[~ok], ys[~ok], s=30, marker="x", c="red", label="not successful")
        if np.any(~ok):
            ax.legend(fontsize=7, loc="upper left")
        ax.set(xlabel=xlabel, ylabel=ylabel, title=title)
    fig.tight_layout()
    save_figure(fig, path)


def plot_distributions(table, path):
    """Histogram of each quantity over the successful samples (PNG at ``path``)."""
    ok = np.asarray(table["status"]) == "successful"
    fig, axes = _panels(7.0)
    for ax, (key, (title, unit, value)) in zip(axes.flat, QUANTITIES.items()):
        z = value(table)[ok]
        z = z[np.isfinite(z)]
        if z.size:
            ax.hist(z, bins=max(5, min(40, z.size // 5)), color="C0", alpha=0.8)
            ax.axvline(np.median(z), color="k", ls="--", label=f"median {np.median(z):.3g}")
            if key.endswith("utilisation"):
                ax.axvline(1.0, color="red", label="limit")
            ax.legend(fontsize=7)
        ax.set(xlabel=f"[{unit}]", ylabel="samples", title=title)
    fig.suptitle(f"{int(np.sum(ok))} successful of {ok.size} samples")
    fig.tight_layout()
    save_figure(fig, path)
