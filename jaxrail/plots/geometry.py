"""Plot of the quasi-static wheel-rail geometry: dr(y), contact angles and the contact
point map (mm, track frame)."""

import matplotlib
import numpy as np

from ._figure import subplots
from ..track.rails import HALF_TAPING_DISTANCE
from ..profiles import sample_profile
from .profiles import rail_name, save_figure

_MAP_LIFT = 6.0  # [mm] clearance drawn between the flange tip and the rail top


def _main_patch(patches):
    """The deepest of a wheel's patches (the one ``delta_r`` uses), or None."""
    return max(patches, key=lambda p: p["penetration_mm"]) if patches else None


def plot_geometry(report, wheel, rail, rail_offset_mm, path, title=None):
    """Three panels written whole to ``path`` (PNG): rolling radius difference against
    shift, contact angles of the main patches of both wheels, and the contact point map
    of the left wheel (wheel profile drawn lifted above the rail, every active patch's
    wheel point joined to its rail point, coloured by shift).

    Arguments:
        report: dict of :func:`jaxrail.geometry.report.geometry_report`.
        wheel, rail: the profiles of the report.
        rail_offset_mm: track centre to rail profile origin [mm].
    """
    rows = report["rows"]
    shift = np.array([r["shift_mm"] for r in rows])
    fig, (ax_dr, ax_angle, ax_map) = subplots(
        3, 1, figsize=(6.5, 8.6), dpi=90, gridspec_kw={"height_ratios": [1.0, 1.0, 1.5]})

    ax_dr.plot(shift, [r["delta_r_mm"] for r in rows], color="C0", lw=1.4)
    ax_dr.set_ylabel(r"$\Delta r$ = $r_L - r_R$ [mm]")
    for side, colour in (("left", "C0"), ("right", "C3")):
        angle = [np.degrees(p["contact_angle_rad"]) if p else np.nan
                 for p in (_main_patch(r[side]) for r in rows)]
        ax_angle.plot(shift, angle, color=colour, lw=1.4, label=f"{side} wheel")
    ax_angle.set_ylabel("contact angle [deg]")
    ax_angle.legend(fontsize=8)
    for ax in (ax_dr, ax_angle):
        ax.set_xlabel("lateral shift of the wheelset, positive left [mm]")
        ax.grid(alpha=0.3)

    # Contact point map of the left wheel, centred wheelset coordinates [mm].
    y_rail, z_rail = sample_profile(rail, n=601)
    ax_map.plot(rail_offset_mm + y_rail, z_rail, color="0.3", lw=1.4, label=rail_name(rail))
    taping = 1e3 * HALF_TAPING_DISTANCE
    curves = [sample_profile(wheel, n=601, surface=k) for k in range(len(wheel.surfaces))]
    lift = z_rail.max() + _MAP_LIFT + max(np.max(f) for _, f in curves)
    for k, (y_wheel, f_wheel) in enumerate(curves):
        ax_map.plot(taping + y_wheel, lift - f_wheel, color="C1", lw=1.4,
                    label=getattr(wheel, "name", "wheel") if k == 0 else None)
    colours = matplotlib.colormaps["viridis"]((shift - shift.min()) / max(np.ptp(shift), 1e-12))
    nominal_mm = 1e3 * float(wheel.nominal_radius)
    for row, colour in zip(rows, colours):
        for p in row["left"]:
            wheel_z = lift - (p["rolling_radius_mm"] - nominal_mm)
            rail_z = np.interp(p["y_track_mm"] - rail_offset_mm, y_rail, z_rail)
            ax_map.plot([taping + p["y_wheel_mm"], p["y_track_mm"]], [wheel_z, rail_z],
                        color=colour, lw=0.7, marker=".", ms=3)
    mappable = matplotlib.cm.ScalarMappable(
        cmap="viridis", norm=matplotlib.colors.Normalize(shift.min(), shift.max()))
    fig.colorbar(mappable, ax=ax_map, label="shift [mm]", fraction=0.04, pad=0.02)
    ax_map.set_xlabel("lateral position from the track centre (wheelset centred) [mm]")
    ax_map.set_ylabel("height [mm] (wheel lifted)")
    ax_map.set_aspect("equal")
    ax_map.legend(fontsize=8, loc="lower left")
    ax_map.grid(alpha=0.3)

    settings = report.get("settings", {})
    fig.suptitle(title or f"{getattr(wheel, 'name', 'wheel')} on {rail_name(rail)}, gauge "
                 f"{settings.get('gauge_mm', '?')} mm", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
