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


def plot_bifurcation(study: dict, path, linear_speed=None, title=None) -> None:
    """The nonlinear study as a bifurcation diagram written whole to ``path`` (PNG): the
    ramp-down's amplitude [mm] against the programmed speed [m/s], each brute-force
    run's final amplitude (filled: hunting, open: died), both critical speeds and, if
    given, the linear one. ``study``: :func:`jaxrail.stability.report.nonlinear_study`."""
    ramp, brute = study["ramp_down"], study["brute_force"]
    figure, axes = subplots(1, 1, figsize=(6.4, 4.4))
    curve = [r for r in ramp.get("amplitude_against_speed", ()) if r["t_s"] > ramp["hold_s"]]
    axes.plot([r["speed_m_s"] for r in curve], [1e3 * r["amplitude_m"] for r in curve], "-",
              color="tab:blue",
              label=f"ramp-down, {ramp['rate_km_h_per_s']:g} km/h per s")
    for hunting, marker in ((True, "o"), (False, "o")):
        runs = [r for r in brute["runs"] if r["hunting"] == hunting and r["attractor"]]
        axes.plot([r["speed_m_s"] for r in runs],
                  [1e3 * r["attractor"]["amplitude_m"] for r in runs], marker,
                  color="tab:orange", fillstyle="full" if hunting else "none",
                  linestyle="none",
                  label="brute force: " + ("hunting" if hunting else "died"))
    for speed, colour, label in ((ramp["critical_speed_m_s"], "tab:blue", "ramp-down"),
                                 (brute["critical_speed_m_s"], "tab:orange", "brute force"),
                                 (linear_speed, "tab:red", "linear")):
        if speed is not None:
            axes.axvline(speed, color=colour, linestyle="--", linewidth=1.0,
                         label=f"{label} critical speed {speed:.1f} m/s")
    axes.axhline(1e3 * ramp["threshold_m"], color="grey", linewidth=0.8, linestyle=":")
    axes.set_xlabel("speed [m/s]")
    axes.set_ylabel(f"wheelset {ramp['wheelset'] + 1} lateral amplitude [mm]")
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=8)
    axes.set_title(title or "nonlinear critical speed: ramp-down and brute force")
    save_figure(figure, path)
