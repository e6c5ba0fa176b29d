"""Plot a wheel on its rail, as they sit on straight track (mm, track frame)."""

import numpy as np

from ._figure import subplots
from .._files import write_atomically
from ..track.rails import HALF_TAPING_DISTANCE
from ..profiles import sample_profile
from ..profiles.measures import rail_offset


def plot_wheel_on_rail(wheel, rail, path, gauge=1.435, title=None):
    """Left wheel and rail in the track cross-section [mm], wheel centred, written
    whole to ``path`` (PNG). Lateral from the track centre, height from the rail
    profile origin; the wheel is drawn at its taping line 750 mm from the centre and
    lowered onto the rail top."""
    offset_mm = 1e3 * float(rail_offset(rail, gauge))
    fig, ax = subplots(figsize=(7.0, 4.0), dpi=90)
    y_rail, z_rail = sample_profile(rail, n=801)
    ax.plot(offset_mm + y_rail, z_rail, color="0.3", lw=1.5, label=rail_name(rail))
    ax.fill_between(offset_mm + y_rail, z_rail, z_rail.min() - 5.0, color="0.85")
    lowest_wheel = None
    for k, surface in enumerate(wheel.surfaces):
        y_wheel, f_wheel = sample_profile(wheel, n=801, surface=k)
        lateral = 1e3 * HALF_TAPING_DISTANCE + y_wheel
        top_of_rail = np.interp(lateral - offset_mm, y_rail, z_rail, left=np.nan, right=np.nan)
        gap = -f_wheel - top_of_rail
        lowest_wheel = np.nanmin(gap) if lowest_wheel is None else min(lowest_wheel, np.nanmin(gap))
        ax.plot(lateral, -f_wheel, lw=1.5, color=f"C{k}",
                label=f"{wheel.name}" + (f" surface {k}" if len(wheel.surfaces) > 1 else ""))
    for line in ax.get_lines()[1:]:
        line.set_ydata(line.get_ydata() - lowest_wheel)
    ax.set_xlabel("lateral position from track centre [mm]")
    ax.set_ylabel("height [mm]")
    ax.set_aspect("equal")
    ax.set_title(title or f"{wheel.name} on {rail_name(rail)}, gauge {1e3 * gauge:.0f} mm")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    save_figure(fig, path)


def rail_name(rail):
    """A rail's label."""
    return getattr(rail, "name", type(rail).__name__)


def save_figure(fig, path):
    """Save ``fig`` as PNG to ``path`` whole or not at all."""
    write_atomically(path, lambda temporary: fig.savefig(temporary, format="png",
                                                         bbox_inches="tight"))
