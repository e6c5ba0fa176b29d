"""A route run once, and the wheel profile it wears into step by step.

:func:`route_wear`: every section of a :class:`~jaxrail.wear.route.Route` simulated (the
curved sections as one batch, the straights as another), each run's wear
(:func:`~jaxrail.wear.run_wear.run_wear`) from the time its section's body is reached,
and the route's wear per km as the sections' wear per km weighted by their shares of
the distance. A group's runs are split over the devices (several CPU devices with
:func:`jaxrail.use_host_devices`), padded to a multiple of them.

:func:`evolve`: from the scenario's wheel, per step of ``step`` km: run the route, take
the wheels' mean height loss per km (one wheel profile serves every wheel of a
vehicle: the mean over all of them, each in its own profile coordinate, so left and
right curves wear one profile), smooth it (a Gaussian of :data:`SMOOTHING` standard
deviation, which keeps its integral), scale it to the step and take it off the profile,
which becomes a measured profile (a natural spline through the grid,
:class:`~jaxrail.profiles.tabulated.TabulatedProfile`). The online search takes it as
it is; table mode builds the worn profile's table at every step (in memory, not in the
cache: about 2.5 min each on 2 cores). The rails stay new. After each step the profile
measures (equivalent conicity at 3 mm, flange height, flange thickness, qR) are
evaluated and the whole evolution so far is written (:mod:`.wear_file`), so an
interrupted evolution resumes from its last completed step.
"""

import dataclasses
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..geometry.quasistatic import wheelset_geometry
from ..geometry.report import conicity_entries
from ..profiles import WheelProfile
from ..profiles.measures import flange_height, flange_qr, flange_thickness
from ..profiles.tabulated import TabulatedProfile
from ..simulation.integrate import solve
from ..vehicles.loads import contact_model
from .._devices import over_devices, split_rows, warn_if_devices_may_stall
from ..compilation import compile_program
from .distribution import lateral_grid
from .route import Route, section_scenario, track_length, wear_start
from .run_wear import run_wear
from .wear_file import PENDING_FIELDS

GRID_SPACING = 0.5e-3  # [m] of the wheel and rail grids
AXIS = "sections"  # the mesh axis the sections are split along
SMOOTHING = 1.0e-3  # [m] standard deviation of the Gaussian smoothing the height loss
CONICITY_AMPLITUDE_MM = 3.0
CONICITY_SHIFTS_MM = np.arange(-10.0, 10.0 + 1e-9, 0.25)


@dataclasses.dataclass
class RouteWear:
    """The route's wear with one wheel profile (host arrays; W wheelsets, S sections).

    volume_per_km (W, 2) [mm^3/km] per wheel; flange_fraction (W, 2) [-];
    wheel_depth_per_km (W, 2, Kw) [m/km]; rail_depth_per_pass (2, Kr) [m] the mean over
    the sections; extrapolated_fraction [-] of the volume from elements beyond the
    law's range; sections_volume_per_km, sections_flange_per_km (S, W, 2) [mm^3/km]
    each section's wear and the part on the flange; sections_depth_per_km (S, W, 2, Kw)
    [m/km]; wheel_nodes, rail_nodes [m];
    completed (S,) the section's run reached its end without derailing (a run that
    stopped counts the wear of the part it ran); run_s, compile_s [s].
    """

    volume_per_km: np.ndarray
    flange_fraction: np.ndarray
    wheel_depth_per_km: np.ndarray
    rail_depth_per_pass: np.ndarray
    extrapolated_fraction: float
    sections_volume_per_km: np.ndarray
    sections_flange_per_km: np.ndarray
    sections_depth_per_km: np.ndarray
    wheel_nodes: np.ndarray
    rail_nodes: np.ndarray
    completed: np.ndarray
    run_s: float
    compile_s: float


def _stack(trees):
    """The trees' leaves stacked on the host (they go to the devices split by section)."""
    return jax.tree.map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *trees)


def _sections(vehicle, params, contact, law, wheel_nodes, rail_nodes, tracks, speeds,
              misalignments, t_from, *, duration, options):
    """The runs of one group of sections and their wear (vmapped over the sections)."""
    def one(track, speed, misalignment, start):
        result = solve(vehicle, params, track, duration, speed, misalignment,
                       options=options, contact_model=contact)
        wear = run_wear(result, vehicle, params, law, wheel_nodes, rail_nodes,
                        t_from=start)
        return wear, jnp.all(result.valid) & ~result.derailed
    return jax.vmap(one)(tracks, speeds, misalignments, t_from)


@eqx.filter_jit
def _batch(shared, rows, *, devices, **static):
    """:func:`_sections` with the sections (``rows``) split over ``devices``."""
    return over_devices(lambda *args: _sections(*args, **static), devices, shared, rows,
                        AXIS)


def route_wear(route: Route, wheel=None, contact=None, progress=False, built=None,
               cache_table=True, devices=None) -> RouteWear:
    """The wear of ``route`` (module docstring) with ``wheel`` (a
    :class:`~jaxrail.profiles.WheelProfile`; default the scenario's); ``contact``
    ``"online"`` or ``"table"`` (default the scenario's mode); ``built``: the base
    scenario's ``build()`` to reuse; ``devices``: the devices each group's runs are
    split over (default all: several CPU devices with
    :func:`jaxrail.use_host_devices`)."""
    base = route.base()
    devices = tuple(jax.devices() if devices is None else devices)
    warn_if_devices_may_stall(devices)
    vehicle, params, _ = base.build() if built is None else built
    if wheel is not None:
        params = eqx.tree_at(lambda p: p.wheel, params, wheel)
    law = route.law()
    mode = base.contact if contact is None else contact
    wheel_nodes = lateral_grid(params.wheel.surfaces[0].domain, GRID_SPACING)
    groups = {}
    for k, section in enumerate(route.sections):
        groups.setdefault(section.curved, []).append(k)
    shares = route.shares()
    per_km = np.zeros((len(route.sections), vehicle.n_wheelsets, 2))
    parts = [None] * len(route.sections)
    completed = np.zeros(len(route.sections), dtype=bool)
    run_s = compile_s = 0.0
    model = None
    options = base.solver_options(route.duration)
    for curved, members in groups.items():
        sections = [route.sections[k] for k in members]
        length = track_length(route, sections)
        padded = sections + [sections[-1]] * (-len(sections) % len(devices))
        tracks = [section_scenario(base, s, length).track() for s in padded]
        rail_nodes = lateral_grid(tracks[0].rails.profile.domain, GRID_SPACING)
        if model is None:
            model = contact_model(mode, vehicle, params, tracks[0], progress, cache_table)
        shared = (vehicle, params, model, law, jnp.asarray(wheel_nodes),
                  jnp.asarray(rail_nodes))
        rows = jax.tree.map(lambda x: split_rows(x, devices, AXIS), (
            _stack(tracks), np.array([s.speed for s in padded]),
            np.array([s.misalignment for s in padded]),
            np.array([wear_start(route, s) for s in padded])))
        static = {"duration": route.duration, "options": options, "devices": devices}
        compiled, seconds = compile_program(_batch, shared, rows, **static)
        compile_s += seconds
        start = time.perf_counter()
        wear, done = jax.block_until_ready(compiled(shared, rows, **static))
        run_s += time.perf_counter() - start
        host = jax.tree.map(np.asarray, wear)
        for i, k in enumerate(members):
            parts[k] = jax.tree.map(lambda x: x[i], host)
            completed[k] = bool(np.asarray(done)[i])
            per_km[k] = np.asarray(parts[k].volume_per_km())
    flange_per_km = np.stack([np.asarray(p.flange_fraction()) for p in parts]) * per_km
    depths = np.stack([np.asarray(p.wheel_depth_per_km()) for p in parts])
    volume, fraction, depth, rail = _mix(
        shares, per_km, flange_per_km, depths,
        np.stack([np.asarray(p.rail_depth_per_pass()) for p in parts]))
    total = np.array([np.sum(p.volume) for p in parts])
    outside = np.array([np.sum(p.extrapolated_volume) for p in parts])
    return RouteWear(
        volume_per_km=volume, flange_fraction=fraction,
        wheel_depth_per_km=depth, rail_depth_per_pass=rail,
        extrapolated_fraction=float(np.sum(outside) / max(np.sum(total), 1e-300)),
        sections_volume_per_km=per_km, sections_flange_per_km=flange_per_km,
        sections_depth_per_km=depths, wheel_nodes=np.asarray(wheel_nodes),
        rail_nodes=np.asarray(parts[0].rail_nodes), completed=completed, run_s=run_s,
        compile_s=compile_s)


def _mix(weights, volume_per_km, flange_per_km, depth_per_km, rail_depth):
    """Weighted means over parts (leading axis S, ``weights`` (S,) summing to 1) of the
    wear per km (S, W, 2) [mm^3/km], its flange part, the wheels' depth per km (S, W, 2,
    K) and the rails' depth per pass (S, 2, Kr): ``(volume, flange fraction of the
    mean volume, depth, rail depth)``."""
    volume = np.einsum("s,swj->wj", weights, volume_per_km)
    flange = np.einsum("s,swj->wj", weights, flange_per_km)
    fraction = np.where(volume > 0, flange / np.where(volume > 0, volume, 1.0), 0.0)
    return (volume, fraction, np.einsum("s,swjk->wjk", weights, depth_per_km),
            np.einsum("s,sjk->jk", weights, rail_depth))


def smooth(nodes, values, sigma=SMOOTHING):
    """``values`` at the uniform ``nodes`` [m] convolved with a Gaussian of standard
    deviation ``sigma`` [m], each node's weights normalised over the grid (the sum of
    the values is kept where the grid's ends carry none)."""
    nodes = np.asarray(nodes)
    if sigma <= 0.0:
        return np.asarray(values)
    d = (nodes[:, None] - nodes[None, :]) / sigma
    kernel = np.exp(-0.5 * d * d)
    kernel /= kernel.sum(axis=0, keepdims=True)  # each source spreads exactly its value
    return kernel @ np.asarray(values)


def profile_heights(wheel: WheelProfile, nodes) -> np.ndarray:
    """The heights [m] of ``wheel``'s (one-surface) profile at ``nodes`` [m]."""
    return np.asarray(jax.vmap(wheel.surfaces[0].height)(jnp.asarray(nodes)))


def measured_wheel(nodes, heights, nominal_radius, name="worn") -> WheelProfile:
    """A one-surface wheel whose profile is the natural spline through ``heights`` (K,)
    [m] at ``nodes`` (K,) [m] (a measured profile), of ``nominal_radius`` [m]."""
    return WheelProfile((TabulatedProfile.from_points(np.asarray(nodes), np.asarray(heights),
                                                      name=name),),
                        nominal_radius, name=name)


def profile_measures(wheel: WheelProfile, rails) -> dict:
    """Equivalent conicity at 3 mm (EN 15302 on ``rails``), flange height, flange
    thickness Sd and qR (EN 15313) [m] of ``wheel``."""
    surface = wheel.surfaces[0]
    shifts = 1e-3 * CONICITY_SHIFTS_MM
    geometry = wheelset_geometry(wheel, rails, jnp.asarray(shifts))
    conicity = conicity_entries(shifts, np.asarray(geometry.delta_r),
                                float(wheel.nominal_radius), (CONICITY_AMPLITUDE_MM,))[0]
    value = conicity["tan_gamma_e"]
    return {"equivalent_conicity": np.nan if value is None else value,
            "flange_height": float(flange_height(surface)),
            "flange_thickness": float(flange_thickness(surface)),
            "qr": float(flange_qr(surface))}


def step_lengths(distance_km: float, step_km: float) -> list[float]:
    """The steps [km] that cover ``distance_km``: whole steps of ``step_km``, the last one
    shorter where the distance is not a multiple; ValueError for a step larger than the
    distance, or a distance or step that is not positive."""
    if not (np.isfinite(distance_km) and distance_km > 0.0):
        raise ValueError(f"--distance {distance_km:g}: must be a positive number of km")
    if not (np.isfinite(step_km) and step_km > 0.0):
        raise ValueError(f"--step {step_km:g}: must be a positive number of km")
    if step_km > distance_km:
        raise ValueError(f"--step {step_km:g} km is larger than --distance {distance_km:g} km")
    whole = int(np.floor(distance_km / step_km + 1e-9))
    rest = distance_km - whole * step_km
    return [float(step_km)] * whole + ([rest] if rest > 1e-9 * distance_km else [])


def _empty(nodes, rail_nodes, n_wheelsets):
    return {"distance_km": np.zeros(1), "profile_y": np.asarray(nodes),
            "profile_height": np.zeros((0, len(nodes))), "rail_y": np.asarray(rail_nodes),
            "wear/volume_per_km": np.zeros((0, n_wheelsets, 2)),
            "wear/flange_fraction": np.zeros((0, n_wheelsets, 2)),
            "wear/depth_per_km": np.zeros((0, n_wheelsets, 2, len(nodes))),
            "wear/height_loss": np.zeros((0, len(nodes))),
            "rail/depth_per_pass": np.zeros((0, 2, len(rail_nodes))),
            "substeps": np.zeros(0, dtype=int), "measures": {}}


def _append(evolution, name, value):
    evolution[name] = np.concatenate([evolution[name], np.asarray(value)[None]])


PART_FIELDS = tuple(PENDING_FIELDS)
"""A sub-step's record (kept in the file while its step is not complete)."""


def _part(wear: RouteWear, length: float) -> dict:
    return {"length_km": np.asarray(length), "volume_per_km": wear.volume_per_km,
            "flange_per_km": wear.volume_per_km * wear.flange_fraction,
            "depth_per_km": wear.wheel_depth_per_km,
            "rail_depth_per_pass": wear.rail_depth_per_pass}


def update_per_km(nodes, depth_per_km):
    """The height the profile update takes off per km [m/km]: the wheels' mean (W, 2, K)
    -> (K,), smoothed."""
    return smooth(nodes, np.mean(depth_per_km, axis=(0, 1)))


def _run_step(route, wheel, heights, contact, built, length, nodes, max_depth, first, say,
              done_parts=None, save=None):
    """One step of ``length`` [km]: the route run with ``wheel`` (its profile ``heights``
    [m] at ``nodes``), in sub-steps that take at most ``max_depth`` [m] off the profile
    (None: one), the profile worn between them. ``done_parts``: the records of sub-steps
    already run (:data:`PART_FIELDS`, stacked), from a file; ``save(parts)`` is called
    with the records after each sub-step that leaves some of the step. Returns the
    step's record: per-km quantities weighted by the sub-steps' lengths (the flange
    fraction by their volumes), the height loss [m] it took off, the sub-steps' count
    and this call's :class:`RouteWear` of each sub-step."""
    parts = [] if done_parts is None else [
        {name: done_parts[name][i] for name in PART_FIELDS}
        for i in range(len(done_parts["length_km"]))]
    loss = sum((update_per_km(nodes, p["depth_per_km"]) * float(p["length_km"])
                for p in parts), np.zeros(len(nodes)))
    remaining = length - sum(float(p["length_km"]) for p in parts)
    if parts:
        wheel = measured_wheel(nodes, heights - loss, wheel.nominal_radius)
    runs = []
    while remaining > 1e-9 * length:
        wear = route_wear(route, wheel, contact, built=built,
                          cache_table=(first and not parts))
        depth = update_per_km(nodes, wear.wheel_depth_per_km)  # [m/km]
        peak = float(np.max(depth))
        part = remaining if (max_depth is None or peak <= 0.0) else min(remaining,
                                                                        max_depth / peak)
        runs.append(wear)
        parts.append(_part(wear, part))
        loss = loss + depth * part
        remaining -= part
        if remaining > 1e-9 * length:
            if say is not None:
                say(f"  sub-step {len(parts)}: {part:.4g} km (at most {1e3 * max_depth:g} mm "
                    f"off the profile), {remaining:.4g} km left in the step")
            if save is not None:
                save({name: np.stack([p[name] for p in parts]) for name in PART_FIELDS})
            wheel = measured_wheel(nodes, heights - loss, wheel.nominal_radius)
    stack = lambda field: np.stack([p[field] for p in parts])  # noqa: E731
    volume, fraction, depth, rail = _mix(
        stack("length_km") / length, stack("volume_per_km"), stack("flange_per_km"),
        stack("depth_per_km"), stack("rail_depth_per_pass"))
    return {"volume_per_km": volume, "flange_fraction": fraction, "depth_per_km": depth,
            "height_loss": loss, "depth_per_pass": rail, "substeps": len(parts),
            "route_wear": runs}


def evolve(route: Route, distance_km: float, step_km: float, contact: str = "table",
           out=None, progress: bool = False, overwrite: bool = False, say=None,
           max_depth=None) -> dict:
    """The wheel profile's evolution over ``distance_km`` in steps of ``step_km``
    (module docstring). ``out``: the HDF5 file written after every step
    (:mod:`.wear_file`); one that holds an earlier part of the same evolution (same
    route text and options) is resumed, another is refused unless ``overwrite``.
    ``say``: a function taking a line of text (progress notes). ``max_depth`` [m]: split
    each step into sub-steps that take at most this much off the profile (the route run
    again on the profile worn so far; None: one run per step). Returns the evolution
    (the file's arrays, plus ``"route_wear"``: this call's
    :class:`RouteWear` of each step, and ``"tables_built"``)."""
    from .wear_file import evolution_key, read_evolution, write_evolution

    steps = step_lengths(distance_km, step_km)
    if contact not in ("table", "online"):
        raise ValueError(f"contact must be 'online' or 'table', got {contact!r}")
    base = route.base()
    built = base.build()
    vehicle, params, track = built
    wheel = params.wheel
    if len(wheel.surfaces) != 1:
        raise ValueError(f"{route.source}: wear evolution needs a wheel of one surface (a "
                         f"real profile); the scenario's {wheel.name!r} has "
                         f"{len(wheel.surfaces)}")
    nodes = lateral_grid(wheel.surfaces[0].domain, GRID_SPACING)
    rail_nodes = lateral_grid(track.rails.profile.domain, GRID_SPACING)
    if max_depth is not None and not (np.isfinite(max_depth) and max_depth > 0.0):
        raise ValueError(f"--max-depth {1e3 * max_depth:g} mm: must be > 0")
    key = evolution_key(route.text, {"distance_km": distance_km, "step_km": step_km,
                                     "contact": contact, "duration_s": route.duration,
                                     "max_depth_m": max_depth})
    attrs = {"key": key, "route": route.name, "route_description": route.description,
             "wear_model": route.wear_model, "contact": contact,
             "distance_km": distance_km, "step_km": step_km}
    evolution = None
    if out is not None and not overwrite:
        from pathlib import Path

        if Path(out).exists():
            saved, saved_attrs = read_evolution(out)
            if saved_attrs.get("key") != key:
                raise ValueError(f"{out}: holds another evolution (route or options "
                                 "differ); give another --out or --overwrite")
            evolution = saved
    if evolution is None:
        evolution = _empty(nodes, rail_nodes, vehicle.n_wheelsets)
        evolution["profile_height"] = profile_heights(wheel, nodes)[None]
        evolution["measures"] = {k: np.array([v]) for k, v in
                                 profile_measures(wheel, track.rails).items()}
    done = len(evolution["wear/height_loss"])
    pending = evolution.pop("pending", None)
    heights = evolution["profile_height"][-1]
    if done:
        wheel = measured_wheel(nodes, heights, wheel.nominal_radius,
                               name=f"{route.name} {evolution['distance_km'][-1]:g} km")
    if (done or pending is not None) and say is not None:
        say(f"resuming after step {done} of {len(steps)} "
            f"({evolution['distance_km'][-1]:g} km) in {out}"
            + ("" if pending is None else
               f", with {len(pending['length_km'])} sub-steps of step {done + 1} run"))
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(steps), initial=done, unit="step", desc=route.name, ncols=100)
    kept = []
    for k in range(done, len(steps)):
        if say is not None and contact == "table" and k > 0:
            say(f"step {k + 1}: building the worn profile's contact table (in memory)")
        save = None if out is None else (
            lambda parts, k=k: write_evolution(out, {**evolution, "pending": parts},
                                               {**attrs, "completed_steps": k}))
        step = _run_step(route, wheel, heights, contact, built, steps[k], nodes, max_depth,
                         first=(k == 0), say=say,
                         done_parts=pending if k == done else None, save=save)
        kept.extend(step["route_wear"])
        heights = heights - step["height_loss"]
        distance = evolution["distance_km"][-1] + steps[k]
        wheel = measured_wheel(nodes, heights, wheel.nominal_radius,
                               name=f"{route.name} {distance:g} km")
        measures = profile_measures(wheel, track.rails)
        _append(evolution, "distance_km", distance)
        _append(evolution, "profile_height", heights)
        for name in ("wear/volume_per_km", "wear/flange_fraction", "wear/depth_per_km",
                     "wear/height_loss", "rail/depth_per_pass", "substeps"):
            _append(evolution, name, step[name.split("/")[-1]])
        for name, value in measures.items():
            evolution["measures"][name] = np.append(evolution["measures"][name], value)
        if out is not None:
            write_evolution(out, evolution, {**attrs, "completed_steps": k + 1})
        if bar is not None:
            bar.set_postfix_str(f"conicity {measures['equivalent_conicity']:.3f}")
            bar.update(1)
    if bar is not None:
        bar.close()
    evolution["route_wear"] = kept
    return evolution
