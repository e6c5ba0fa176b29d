"""The root locus of the hunting mode: damping ratio and frequency against speed."""

from ._figure import subplots
from .profiles import save_figure


def plot_root_locus(study: dict, path, title=None) -> None:
    """Two panels written whole to ``path`` (PNG): the hunting mode's damping ratio [-]
    and frequency [Hz] against speed [m/s], the linear critical speed marked.
    ``study``: :func:`jaxrail.stability.report.stability_study`."""
    rows = study["root_locus"]
    speed = [r["speed_m_s"] for r in rows]
    figure, (top, bottom) = subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    top.plot(speed, [r["damping_ratio"] for r in rows], "o-")
    top.axhline(0.0, color="black", linewidth=0.8)
    bottom.plot(speed, [r["frequency_hz"] for r in rows], "o-")
    critical = study["linear_critical_speed_m_s"]
    for axes in (top, bottom):
        axes.axvline(critical, color="tab:red", linestyle="--",
                     label=f"linear critical speed {critical:.1f} m/s")
        axes.grid(True, alpha=0.3)
    top.set_ylabel("hunting damping ratio [-]")
    bottom.set_ylabel("hunting frequency [Hz]")
    bottom.set_xlabel("speed [m/s]")
    top.legend()
    top.set_title(title or f"{study['vehicle']}: root locus of the hunting mode")
    save_figure(figure, path)
