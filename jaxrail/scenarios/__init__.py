"""Scenarios: a vehicle, its wheel profile, a track (layout, rails, irregularities,
support), a speed, a misalignment, a duration and solver options, read from TOML files;
built-in ones by name.

Built-in: ``paper-curve`` (the paper's example with real S1002 / UIC60 1:40 profiles),
``paper-curve-simplified`` (the paper's simplified S1002), ``straight``,
``straight-irregular`` (the trailer on straight track with German low-level
irregularities), ``paper-curve-irregular`` (the paper's curve on German low-level
irregularities and the co-moving flexible track), and
``bogie-curve-entry`` (a loaded bogie running into a 300 m curve onto the flange root
in 1 s, fixed steps: the identification scenario), ``suspended-wheelset`` (one
wheelset on a primary suspension to a frame going straight on, the reference of the
linear stability analysis, docs/stability.md). The file
format is described in docs/scenarios.md.
"""

import dataclasses
import math
import tomllib
from pathlib import Path

import equinox as eqx

from .._files import builtin_or_file_text
from ..profiles.named import named_profile
from . import checks
from .irregularities import IrregularitySpec, parse_irregularities
from ..simulation import INTEGRATORS, SolverOptions, run_span, simulate
from ..track import RAIL_KEYS, STANDARD_GAUGE, Arc, Rails, Straight, Track, Transition
from ..track.flexible import FlexibleTrack
from ..vehicles import CONTACT_MODELS, contact_model
from ..vehicles.from_file import FORMULATIONS, vehicle_from_file, vehicle_names
from ..vehicles.suspended_wheelset import suspended_wheelset_file
from ..vehicles.trailer import trailer_values

__all__ = ["BUILTIN", "Scenario", "load_scenario", "parse_scenario", "prepare_scenario",
           "run_scenario"]

BUILTIN = ("paper-curve", "paper-curve-simplified", "paper-curve-irregular", "straight",
           "straight-irregular", "bogie-curve-entry", "suspended-wheelset",
           "coach-curve-irregular", "wagon-straight-irregular")
_SEGMENTS = {"straight": (Straight, {"length"}),
             "transition": (Transition, {"length"}),
             "arc": (Arc, {"length", "radius", "direction", "cant"})}


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A scenario as read from its file (plain Python values, SI units)."""

    name: str
    description: str
    model: str
    wheel: str | None
    rail: str
    inclination: str
    gauge: float
    vehicle_data: str | None
    friction: float
    segments: tuple
    speed: float
    misalignment: float
    duration: float
    rtol: float
    atol: float
    output_rate: float
    source: str
    fixed_step: float | None = None
    contact: str = "online"
    integrator: str = "tsit5"
    jacobian_every: int = 8
    irregularities: IrregularitySpec | None = None
    flexible: dict | None = None
    vehicle_file: str | None = None
    formulation: str = "auto"

    def solver_options(self, duration=None, progress=False) -> SolverOptions:
        """SolverOptions with ``output_rate`` samples per second over the duration."""
        duration = self.duration if duration is None else duration
        options = SolverOptions(rtol=self.rtol, atol=self.atol, progress=progress,
                                n_outputs=max(2, int(round(duration * self.output_rate)) + 1),
                                integrator=self.integrator,
                                jacobian_every=self.jacobian_every)
        if self.fixed_step is None:
            return options
        steps = int(math.ceil(duration / self.fixed_step - 1e-9))
        return dataclasses.replace(options, fixed_step=self.fixed_step, max_steps=steps + 1)

    def contact_model(self, vehicle, params, track, contact=None, progress=False):
        """The contact model of this scenario (``contact`` overrides its ``[contact]
        mode``): the paper's search, or the table of the vehicle's wheel on ``track``'s
        rails, built or loaded."""
        return contact_model(self.contact if contact is None else contact, vehicle, params,
                             track, progress)

    def rails(self) -> Rails:
        """The rails of ``[track] rail``, ``inclination`` and ``gauge``."""
        return Rails.at_gauge(self._profile("rail", "track"), self.gauge)

    def track(self) -> Track:
        """The track of ``[track] segments`` and rails with the ``[irregularities]``;
        ValueError names the file and the segment or the irregularity's entry."""
        rails = self.rails()
        try:
            track = Track.from_segments([_SEGMENTS[s["kind"]][0](
                **{k: v for k, v in s.items() if k != "kind"}) for s in self.segments],
                rails=rails)
        except ValueError as error:
            raise ValueError(f"{self.source}: [track] segments: {error}") from error
        if self.flexible is not None:  # its values checked when the file was read
            track = track.with_support(FlexibleTrack(**self.flexible))
        if self.irregularities is None:
            return track
        try:
            irregularity = self.irregularities.build(float(track.total_length))
        except ValueError as error:
            raise ValueError(f"{self.source}: [irregularities]: {error}") from error
        return track.with_irregularity(irregularity)

    def check_irregularity_covers(self, track, params, duration, speed=None) -> None:
        """ValueError when the run's wheelsets (:func:`jaxrail.simulation.run_span`, at
        ``speed`` [m/s], default the scenario's) go beyond the samples of a measured
        file's or a spectrum's irregularity (a defect is zero outside its dip)."""
        spec = self.irregularities
        if spec is None or spec.covers_outside:
            return
        speed = self.speed if speed is None else float(speed)
        first, last = run_span(params, speed, duration)
        irregularity = track.irregularity
        start, end = float(irregularity.start), float(irregularity.end)
        if first < start - 1e-9 or last > end + 1e-9:
            what = f"file {spec.file!r}" if spec.source == "file" else "realisation"
            raise ValueError(
                f"{self.source}: [irregularities]: the {what} covers s = {start:g} to {end:g} m "
                f"but the run's wheelsets go from {first:.1f} to {last:.1f} m ({duration:g} s at "
                f"{speed:g} m/s); give a longer file or a shorter run")

    def _profile(self, key, table):
        """The ``[table] key`` profile (``[vehicle] wheel``, ``[track] rail``), None where
        the scenario leaves the wheel to the vehicle file; ValueError names the file, the
        key and what was given."""
        name = getattr(self, key)
        if name is None:
            return None
        try:
            kind, profile = named_profile(name, self.inclination, kind=None)
        except ValueError as error:
            raise ValueError(f"{self.source}: [{table}] {key}: {error}") from error
        if kind != key:
            raise ValueError(f"{self.source}: [{table}] {key}: {name!r} is a {kind} profile")
        return profile

    def build(self, curve_radius=None):
        """``(vehicle, params, track)``. ``curve_radius`` [m]: build the suspended wheelset
        for a left curve of that radius (its frame turning about the curve's centre) and
        leave the scenario's track to the caller (the stability analysis in a curve)."""
        # every model is a built-in vehicle file; [vehicle] data replaces its named
        # parameters (the suspended wheelset's primary longitudinal stiffness included)
        values = None if self.vehicle_data is None else trailer_values(self.vehicle_data)
        options = {"wheel": self._profile("wheel", "vehicle"), "parameters": values,
                   "formulation": self.formulation}
        if self.model == "suspended-wheelset":
            curved = [k + 1 for k, seg in enumerate(self.segments) if seg["kind"] != "straight"]
            if curved and curve_radius is None:
                raise ValueError(f"{self.source}: [vehicle] model = 'suspended-wheelset' runs "
                                 f"on straight track only (its frame slides along the "
                                 f"global x axis); track segments {curved} are not straight")
            vehicle, params = suspended_wheelset_file(curve_radius, **options)
        else:
            vehicle, params = vehicle_from_file(self.vehicle_file or self.model, **options)
        params = eqx.tree_at(lambda p: p.contact.friction, params, self.friction)
        return vehicle, params, self.track()


_TABLES = {"vehicle": {"model", "file", "wheel", "data", "formulation"},
           "contact": {"friction", "mode"},
           "track": {"segments", "rail", "inclination", "gauge", "flexible"},
           "run": {"speed", "misalignment", "duration"},
           "solver": {"rtol", "atol", "output_rate", "fixed_step", "integrator",
                      "jacobian_every"},
           "irregularities": None}


def _segments(raw, where):
    if not isinstance(raw, list) or not raw:
        raise ValueError(f"{where}: [track] segments must be a non-empty list of tables")
    out = []
    for k, segment in enumerate(raw):
        here = f"{where}: track segment {k + 1}"
        if not isinstance(segment, dict):
            raise ValueError(f"{here} must be a table such as {{ kind = \"straight\", "
                             f"length = 100.0 }}, got {segment!r}")
        kind = segment.get("kind")
        if kind not in _SEGMENTS:
            raise ValueError(f"{here}: kind must be one of {sorted(_SEGMENTS)}, got {kind!r}")
        allowed = _SEGMENTS[kind][1]
        checks.known_keys(segment, allowed | {"kind"}, here, f"a {kind} segment")
        values = {"kind": kind}
        for key in sorted(allowed):
            if key == "direction":
                values[key] = checks.text(segment, key, here, f"a {kind} segment", "left",
                                          ("left", "right"))
            elif key == "cant":
                values[key] = checks.number(segment.get(key, 0.0), "cant", here)
            elif key not in segment:
                raise ValueError(f"{here}: missing {key!r}")
            else:
                values[key] = checks.number(segment[key], key, here)
        out.append(values)
    return tuple(out)


def _flexible(raw, where):
    """``[track] flexible``: false (rigid rails, the default), true (the co-moving
    flexible track with its default values) or a table of ``mass``, ``stiffness``,
    ``damping``, each [lateral, vertical] (:class:`jaxrail.track.FlexibleTrack`)."""
    if raw is None or raw is False:
        return None
    if raw is True:
        return {}
    here = f"{where}: [track] flexible"
    if not isinstance(raw, dict):
        raise ValueError(f"{here} must be true, false or a table of mass, stiffness and "
                         f"damping, got {raw!r}")
    checks.known_keys(raw, {"mass", "stiffness", "damping"}, where, "[track] flexible")
    values = {}
    for key, value in raw.items():
        if not (isinstance(value, list) and len(value) == 2):
            raise ValueError(f"{here}: {key} must be [lateral, vertical], got {value!r}")
        values[key] = tuple(checks.number(v, key, here) for v in value)
    return values


def _vehicle_path(vehicle, key, where):
    """The file of ``[vehicle] key`` (relative to the scenario file), checked; None if
    the key is not given."""
    if key not in vehicle:
        return None
    path = Path(checks.text(vehicle, key, where, "[vehicle]"))
    if not path.is_absolute() and Path(where).exists():
        path = Path(where).parent / path
    if not path.is_file():
        raise ValueError(f"{where}: [vehicle] {key}: no such file {str(path)!r}")
    return str(path)


def _profile_name(vehicle, key, where):
    """``[vehicle] wheel``: optional; a vehicle file names its own, which the
    scenario's replaces where given."""
    if key not in vehicle:
        return None
    return checks.text(vehicle, key, where, "[vehicle]")


def _no_rails_in_vehicle(vehicle, where):
    """ValueError for the rails' keys in ``[vehicle]``: the rails are the track's."""
    for key in RAIL_KEYS if isinstance(vehicle, dict) else ():
        if key in vehicle:
            raise ValueError(f"{where}: [vehicle] {key}: the rails belong to the track: give "
                             f"{key} in [track] ({', '.join(RAIL_KEYS)})")


def _vehicle_model(vehicle, where):
    """``[vehicle] model``: a built-in vehicle file's name (``"file"`` where a ``file``
    is given, which it names instead)."""
    models = tuple(vehicle_names())
    if "file" in vehicle:
        if "model" in vehicle:
            raise ValueError(f"{where}: [vehicle] give a model or a file, not both")
        return "file"
    if "model" not in vehicle:
        raise ValueError(f"{where}: [vehicle] needs a model (one of {', '.join(models)}) or "
                         f"a file")
    return checks.text(vehicle, "model", where, "[vehicle]", choices=models)


def _name(raw, where):
    name = checks.text(raw, "name", where, "the scenario")
    if not name.strip():
        raise ValueError(f"{where}: the scenario name must not be empty")
    return name


def parse_scenario(text: str, where: str = "<scenario>") -> Scenario:
    """A :class:`Scenario` from TOML text; ValueError names the file, the entry, what is
    allowed (:mod:`.checks`) and what was given. Unknown tables and keys are errors."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{where}: {error}") from error
    checks.known_keys(raw, {"name", "description", *_TABLES}, where, "the scenario")
    for name in ("vehicle", "track", "run", "solver"):
        if name not in raw:
            raise ValueError(f"{where}: missing table [{name}]")
    _no_rails_in_vehicle(raw["vehicle"], where)
    tables = {name: checks.known_keys(raw.get(name, {}), keys, where, f"[{name}]")
              for name, keys in _TABLES.items() if keys is not None}
    vehicle, track, run, solver = (tables[k] for k in ("vehicle", "track", "run", "solver"))
    contact, number = tables["contact"], checks.number
    fixed_step = solver.get("fixed_step")
    scenario = Scenario(
        name=_name(raw, where),
        description=checks.text(raw, "description", where, "the scenario", ""),
        model=_vehicle_model(vehicle, where),
        wheel=_profile_name(vehicle, "wheel", where),
        rail=checks.text(track, "rail", where, "[track]", "uic60"),
        inclination=checks.text(track, "inclination", where, "[track]", "1:40"),
        gauge=number(track.get("gauge", STANDARD_GAUGE), "gauge", where, "[track] gauge"),
        vehicle_data=_vehicle_path(vehicle, "data", where),
        vehicle_file=_vehicle_path(vehicle, "file", where),
        formulation=checks.text(vehicle, "formulation", where, "[vehicle]", "auto",
                                FORMULATIONS),
        friction=number(contact.get("friction", 0.4), "friction", where, "[contact] friction"),
        segments=_segments(track.get("segments"), where),
        speed=number(run.get("speed"), "speed", where, "[run] speed"),
        misalignment=number(run.get("misalignment", 0.0), "misalignment", where,
                            "[run] misalignment"),
        duration=number(run.get("duration"), "duration", where, "[run] duration"),
        rtol=number(solver.get("rtol", 1e-4), "rtol", where, "[solver] rtol"),
        atol=number(solver.get("atol", 1e-7), "atol", where, "[solver] atol"),
        output_rate=number(solver.get("output_rate", 50.0), "output_rate", where,
                           "[solver] output_rate"),
        source=where,
        fixed_step=None if fixed_step is None else number(fixed_step, "fixed_step", where,
                                                          "[solver] fixed_step"),
        contact=checks.text(contact, "mode", where, "[contact]", "online", CONTACT_MODELS),
        integrator=checks.text(solver, "integrator", where, "[solver]", "tsit5", INTEGRATORS),
        jacobian_every=checks.count(solver.get("jacobian_every", 8), "[solver] jacobian_every",
                                    where, 1, 1000),
        irregularities=parse_irregularities(raw.get("irregularities"), where),
        flexible=_flexible(track.get("flexible"), where),
    )
    checks.run_size(scenario.duration, scenario.output_rate, scenario.fixed_step, where)
    return scenario


def load_scenario(name_or_path) -> Scenario:
    """A built-in scenario by name (:data:`BUILTIN`) or a scenario TOML file."""
    return parse_scenario(*builtin_or_file_text(name_or_path, __package__, BUILTIN,
                                                "scenario"))


def prepare_scenario(scenario: Scenario, duration=None):
    """``(vehicle, params, track)`` of ``scenario``, built and checked for a run of
    ``duration`` [s] (default the scenario's): ValueError when the irregularity (a
    measured file or a realisation) does not cover the run. Nothing is compiled or
    simulated; :func:`run_scenario` takes the result as ``prepared``."""
    vehicle, params, track = scenario.build()
    duration = scenario.duration if duration is None else float(duration)
    scenario.check_irregularity_covers(track, params, duration)
    return vehicle, params, track


def run_scenario(scenario: Scenario, duration=None, progress=False, contact=None,
                 prepared=None):
    """Build and simulate a scenario: ``(result, vehicle, params, track)``. ``contact``:
    ``"online"`` or ``"table"``, overriding the scenario's ``[contact] mode``.
    ``prepared``: :func:`prepare_scenario`'s ``(vehicle, params, track)`` for the same
    scenario and duration (built and checked again when not given)."""
    duration = scenario.duration if duration is None else float(duration)
    vehicle, params, track = (prepare_scenario(scenario, duration) if prepared is None
                              else prepared)
    model = scenario.contact_model(vehicle, params, track, contact, progress)
    result = simulate(vehicle, params, track, duration, scenario.speed, scenario.misalignment,
                      options=scenario.solver_options(duration, progress), contact_model=model)
    return result, vehicle, params, track
