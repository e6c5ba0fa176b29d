"""Figures of a wear evolution (:func:`jaxrail.wear.evolution.evolve`'s arrays, mm and
km): the worn profiles over distance, the profile measures against distance, and the
wear's distribution over the profile."""

import numpy as np

from ._figure import subplots
from .profiles import save_figure


def plot_worn_profiles(evolution, path, title=None):
    """The wheel profile at every step (colour: distance), and the height each lost,
    against the lateral coordinate [mm]; written whole to ``path`` (PNG)."""
    import matplotlib

    y = 1e3 * np.asarray(evolution["profile_y"])
    heights = 1e3 * np.asarray(evolution["profile_height"])
    distance = np.asarray(evolution["distance_km"])
    colours = matplotlib.colormaps["viridis"](np.linspace(0.0, 1.0, len(heights)))
    fig, (top, bottom) = subplots(2, 1, figsize=(7.0, 7.0), dpi=90, sharex=True,
                                  gridspec_kw={"height_ratios": [1.6, 1.0]})
    for h, d, c in zip(heights, distance, colours):
        top.plot(y, h, color=c, lw=1.0, label=f"{d:,.0f} km")
        bottom.plot(y, heights[0] - h, color=c, lw=1.0)
    top.set_ylabel("profile height [mm]")
    top.legend(fontsize=7, ncol=2, loc="upper right")
    bottom.set_ylabel("height lost [mm]")
    bottom.set_xlabel("lateral coordinate from the taping line [mm] (flange to the left)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.set_title(title or "worn wheel profiles")
    save_figure(fig, path)


def plot_measures(evolution, path, title=None):
    """Equivalent conicity (3 mm), flange thickness Sd, flange height Sh and qR against
    distance [km]; written whole to ``path`` (PNG)."""
    distance = np.asarray(evolution["distance_km"])
    m = evolution["measures"]
    fig, axes = subplots(2, 2, figsize=(8.0, 6.0), dpi=90, sharex=True)
    panels = (("equivalent_conicity", "equivalent conicity (3 mm) [-]", 1.0),
              ("flange_thickness", "flange thickness Sd [mm]", 1e3),
              ("flange_height", "flange height Sh [mm]", 1e3), ("qr", "qR [mm]", 1e3))
    for ax, (name, label, scale) in zip(axes.ravel(), panels):
        ax.plot(distance, scale * np.asarray(m[name]), "o-", color="C0", ms=3)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("distance [km]")
    fig.suptitle(title or "profile measures against distance")
    fig.tight_layout()  # the right column's labels clear the left column's ticks
    save_figure(fig, path)


def plot_wear_distribution(evolution, path, step=0, title=None):
    """Each wheel's height loss per 1000 km against the wheel profile's lateral
    coordinate [mm] in step ``step`` (default the first, on the new profile); written
    whole to ``path`` (PNG)."""
    y = 1e3 * np.asarray(evolution["profile_y"])
    depth = 1e6 * np.asarray(evolution["wear/depth_per_km"])[step]  # m/km -> mm per 1000 km
    fig, ax = subplots(figsize=(7.0, 4.0), dpi=90)
    sides = ("left", "right")
    for w in range(depth.shape[0]):
        for j in range(2):
            ax.plot(y, depth[w, j], lw=1.0, ls="-" if j == 0 else "--",
                    color=f"C{w}", label=f"wheelset {w + 1} {sides[j]}")
    ax.set_xlabel("lateral coordinate from the taping line [mm] (flange to the left)")
    ax.set_ylabel("height lost per 1000 km [mm]")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    ax.set_title(title or "wear distribution over the wheel profile")
    save_figure(fig, path)
