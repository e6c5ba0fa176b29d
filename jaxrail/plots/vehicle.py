"""A picture of a vehicle: side view and plan view of its bodies, wheelsets, joints and
force elements at the nominal layout (the vehicle frame: x forward, y left, z up)."""

import numpy as np
from matplotlib.patches import Circle, Rectangle

from ..track import standard_rails
from ._figure import subplots
from .profiles import save_figure

MIN_SIZE = 0.15  # [m]: the smallest side drawn for a body
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:olive", "tab:cyan")


def box_size(mass, inertia) -> np.ndarray:
    """Sides (3,) [m] (x, y, z) of the uniform box with this ``mass`` [kg] and principal
    ``inertia`` (3,) [kg m^2] (roll, pitch, yaw): a^2 = 6 (I_pitch + I_yaw - I_roll) / m
    and so on, each at least :data:`MIN_SIZE` (real bodies are not uniform boxes)."""
    i = np.asarray(inertia, dtype=float)
    squares = 6.0 * (np.sum(i) - 2.0 * i) / float(mass)
    return np.sqrt(np.maximum(squares, MIN_SIZE**2))


def _element_lines(system, system_params, layout):
    """``{kind: [(start (3,), end (3,))]}``: each force element between its two points,
    vehicle frame (the bodies unrotated at rest; the ground's points as they are)."""
    lines = {}
    for group in system.force_groups:
        e = system_params.forces[group.kind]
        if not (hasattr(e, "point_i") and hasattr(e, "point_j")):
            continue
        points = []
        for k, (i, j) in enumerate(zip(group.body_i, group.body_j)):
            start = np.asarray(e.point_i[k]) + (layout[i] if i >= 0 else 0.0)
            end = np.asarray(e.point_j[k]) + (layout[j] if j >= 0 else 0.0)
            points.append((start, end))
        lines[group.kind] = points
    return lines


def plot_vehicle(vehicle, params, path, title=None, rails=None) -> None:
    """Side view (x, z) above plan view (x, y) of ``vehicle`` written whole to ``path``
    (PNG): each body a box of its layout position and the size of the uniform box of its
    mass and inertia (:func:`box_size`), each wheelset a circle of its nominal radius
    (side) and an axle with two wheels (plan), each force element a line between its
    points (a diamond where its points coincide at rest, as a bushing's), coloured by kind,
    the rails in grey, at the profile origins of ``rails`` (default
    :func:`jaxrail.track.standard_rails`)."""
    system, system_params = vehicle.system, params.system
    layout = np.asarray(params.layout)
    mass = np.asarray(system_params.bodies.mass)
    inertia = np.diagonal(np.asarray(system_params.bodies.inertia), axis1=1, axis2=2)
    radius = float(params.nominal_radius)
    wheelsets = set(vehicle.wheelsets)
    half_gauge = float((standard_rails() if rails is None else rails).offset)
    figure, (side, plan) = subplots(2, 1, figsize=(12.0, 5.5))
    for k, name in enumerate(system.body_names):
        x, y, z = layout[k]
        if k in wheelsets:
            side.add_patch(Circle((x, radius), radius, fill=False, color="black", zorder=3))
            plan.plot([x, x], [-half_gauge, half_gauge], color="black", linewidth=2, zorder=3)
            for wheel in (-half_gauge, half_gauge):
                plan.add_patch(Rectangle((x - radius, wheel - 0.07), 2 * radius, 0.14,
                                         color="black", zorder=3))
            continue
        a, b, c = box_size(mass[k], inertia[k])
        style = dict(fill=True, alpha=0.25, edgecolor="black", zorder=1)
        side.add_patch(Rectangle((x - a / 2, z - c / 2), a, c, **style))
        plan.add_patch(Rectangle((x - a / 2, y - b / 2), a, b, **style))
        side.annotate(name, (x, z + c / 2), ha="center", va="bottom", fontsize=7)
    for n, (kind, lines) in enumerate(_element_lines(system, system_params, layout).items()):
        colour = COLOURS[n % len(COLOURS)]
        for m, (start, end) in enumerate(lines):
            label = kind.replace("_", " ") if m == 0 else None
            # an element whose points coincide at rest (a bushing) is a diamond there
            style = dict(marker="D" if np.allclose(start, end) else "o", color=colour,
                         markersize=4.0 if np.allclose(start, end) else 2.5,
                         linewidth=1.2, zorder=2)
            side.plot([start[0], end[0]], [start[2], end[2]], label=label, **style)
            plan.plot([start[0], end[0]], [start[1], end[1]], **style)
    span = (np.min(layout[:, 0]) - 3.0, np.max(layout[:, 0]) + 3.0)
    side.plot(span, (0.0, 0.0), color="grey", linewidth=1.5, zorder=0)
    for rail in (-half_gauge, half_gauge):
        plan.plot(span, (rail, rail), color="grey", linewidth=1.0, zorder=0)
    for axes, label in ((side, "z [m] (up)"), (plan, "y [m] (left)")):
        axes.set_aspect("equal")
        axes.autoscale_view()
        axes.set_xlabel("x [m] (forward)")
        axes.set_ylabel(label)
        axes.grid(True, alpha=0.3)
    side.set_title(title or f"{vehicle.name}: side view")
    plan.set_title("plan view")
    if side.get_legend_handles_labels()[0]:
        side.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    save_figure(figure, path)
