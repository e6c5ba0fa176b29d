"""Scenarios: a vehicle, its profiles, a track layout, a speed, a misalignment, a
duration and solver options, read from TOML files; built-in ones by name.

Built-in: ``paper-curve`` (the paper's example with real S1002 / UIC60 1:40 profiles),
``paper-curve-simplified`` (the paper's simplified S1002), ``straight``, and
``bogie-curve-entry`` (a loaded bogie running into a 300 m curve onto the flange root
in 1 s, fixed steps: the identification scenario). The file
format is described in docs/scenarios.md.
"""

import dataclasses
import importlib.resources
import math
import tomllib
from pathlib import Path

import equinox as eqx

from ..profiles.named import named_profile
from ..simulate import INTEGRATORS, SolverOptions, simulate
from ..track import Arc, Straight, Track, Transition
from ..vehicles import CONTACT_MODELS, bogie, contact_model, single_wheelset, trailer
from ..vehicles.trailer import trailer_values

BUILTIN = ("paper-curve", "paper-curve-simplified", "straight", "bogie-curve-entry")
_SEGMENTS = {"straight": (Straight, {"length"}),
             "transition": (Transition, {"length"}),
             "arc": (Arc, {"length", "radius", "direction", "cant"})}
_MODELS = ("trailer", "bogie", "single-wheelset")


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A scenario as read from its file (plain Python values, SI units)."""

    name: str
    description: str
    model: str
    wheel: str
    rail: str
    inclination: str
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

    def solver_options(self, duration=None, progress=False) -> SolverOptions:
        """SolverOptions with ``output_rate`` samples per second over the duration."""
        duration = self.duration if duration is None else duration
        options = SolverOptions(rtol=self.rtol, atol=self.atol, progress=progress,
                                n_outputs=max(2, int(round(duration * self.output_rate)) + 1),
                                integrator=self.integrator)
        if self.fixed_step is None:
            return options
        steps = int(math.ceil(duration / self.fixed_step - 1e-9))
        return dataclasses.replace(options, fixed_step=self.fixed_step, max_steps=steps + 1)

    def contact_model(self, vehicle, contact=None, progress=False):
        """The contact model of this scenario (``contact`` overrides its ``[contact]
        mode``): the paper's search, or its table built or loaded for ``vehicle``."""
        return contact_model(self.contact if contact is None else contact, vehicle, progress)

    def track(self) -> Track:
        return Track.from_segments([_SEGMENTS[s["kind"]][0](**{k: v for k, v in s.items()
                                                               if k != "kind"})
                                    for s in self.segments])

    def build(self):
        """``(vehicle, params, track)``."""
        _, wheel = named_profile(self.wheel, self.inclination, kind=None)
        _, rail = named_profile(self.rail, self.inclination, kind=None)
        if self.model in ("trailer", "bogie"):
            values = trailer_values(self.vehicle_data)
            vehicle, params = (trailer if self.model == "trailer" else bogie)(wheel, rail, values)
        else:
            vehicle, params = single_wheelset(wheel, rail)
        params = eqx.tree_at(lambda p: p.contact.friction, params, self.friction)
        return vehicle, params, self.track()


def _require(table, key, kind, where):
    if key not in table:
        raise ValueError(f"{where}: missing {key!r}")
    value = table[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind):
        raise ValueError(f"{where}: {key!r} must be a {kind.__name__}, got {value!r}")
    return value


def _segments(raw, where):
    if not isinstance(raw, list) or not raw:
        raise ValueError(f"{where}: [track] segments must be a non-empty list")
    out = []
    for k, segment in enumerate(raw):
        here = f"{where}: track segment {k + 1}"
        kind = segment.get("kind")
        if kind not in _SEGMENTS:
            raise ValueError(f"{here}: kind must be one of {sorted(_SEGMENTS)}, got {kind!r}")
        allowed = _SEGMENTS[kind][1]
        unknown = set(segment) - allowed - {"kind"}
        if unknown:
            raise ValueError(f"{here}: unknown keys {sorted(unknown)} for {kind}")
        values = {"kind": kind}
        for key in allowed:
            if key == "direction":
                values[key] = segment.get(key, "left")
                if values[key] not in ("left", "right"):
                    raise ValueError(f"{here}: direction must be 'left' or 'right'")
            elif key == "cant":
                values[key] = float(segment.get(key, 0.0))
            else:
                values[key] = _require(segment, key, float, here)
                if values[key] <= 0.0:
                    raise ValueError(f"{here}: {key} must be > 0, got {values[key]}")
        out.append(values)
    return tuple(out)


def parse_scenario(text: str, where: str = "<scenario>") -> Scenario:
    """A :class:`Scenario` from TOML text; ValueError names the file and the entry."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{where}: {error}") from error
    tables = {}
    for name in ("vehicle", "track", "run", "solver"):
        if not isinstance(raw.get(name), dict):
            raise ValueError(f"{where}: missing table [{name}]")
        tables[name] = raw[name]
    vehicle, run, solver = tables["vehicle"], tables["run"], tables["solver"]
    model = _require(vehicle, "model", str, where)
    if model not in _MODELS:
        raise ValueError(f"{where}: vehicle model must be one of {_MODELS}, got {model!r}")
    scenario = Scenario(
        name=_require(raw, "name", str, where),
        description=raw.get("description", ""),
        model=model,
        wheel=_require(vehicle, "wheel", str, where),
        rail=_require(vehicle, "rail", str, where),
        inclination=str(vehicle.get("inclination", "1:40")),
        vehicle_data=vehicle.get("data"),
        friction=float(raw.get("contact", {}).get("friction", 0.4)),
        segments=_segments(tables["track"].get("segments"), where),
        speed=_require(run, "speed", float, where),
        misalignment=float(run.get("misalignment", 0.0)),
        duration=_require(run, "duration", float, where),
        rtol=float(solver.get("rtol", 1e-4)),
        atol=float(solver.get("atol", 1e-7)),
        output_rate=float(solver.get("output_rate", 50.0)),
        source=where,
        fixed_step=None if "fixed_step" not in solver else float(solver["fixed_step"]),
        contact=raw.get("contact", {}).get("mode", "online"),
        integrator=solver.get("integrator", "tsit5"),
    )
    if scenario.integrator not in INTEGRATORS:
        raise ValueError(f"{where}: [solver] integrator must be one of {INTEGRATORS}, got "
                         f"{scenario.integrator!r}")
    if scenario.contact not in CONTACT_MODELS:
        raise ValueError(f"{where}: [contact] mode must be one of {CONTACT_MODELS}, got "
                         f"{scenario.contact!r}")
    if scenario.fixed_step is not None and not scenario.fixed_step > 0.0:
        raise ValueError(f"{where}: fixed_step must be > 0, got {scenario.fixed_step}")
    for key in ("speed", "duration", "rtol", "atol", "output_rate", "friction"):
        if not getattr(scenario, key) > 0.0:
            raise ValueError(f"{where}: {key} must be > 0, got {getattr(scenario, key)}")
    return scenario


def load_scenario(name_or_path) -> Scenario:
    """A built-in scenario by name (:data:`BUILTIN`) or a scenario TOML file."""
    if str(name_or_path) in BUILTIN:
        text = importlib.resources.files(__package__).joinpath(
            "data", f"{name_or_path}.toml").read_text()
        return parse_scenario(text, f"built-in scenario {name_or_path}")
    path = Path(name_or_path)
    if not path.exists():
        raise ValueError(f"unknown scenario {str(name_or_path)!r}: use one of "
                         f"{', '.join(BUILTIN)} or a .toml file")
    return parse_scenario(path.read_text(), str(path))


def run_scenario(scenario: Scenario, duration=None, progress=False, contact=None):
    """Build and simulate a scenario: ``(result, vehicle, params, track)``. ``contact``:
    ``"online"`` or ``"table"``, overriding the scenario's ``[contact] mode``."""
    vehicle, params, track = scenario.build()
    model = scenario.contact_model(vehicle, contact, progress)
    duration = scenario.duration if duration is None else float(duration)
    result = simulate(vehicle, track, params, duration, scenario.speed, scenario.misalignment,
                      options=scenario.solver_options(duration, progress), contact_model=model)
    return result, vehicle, params, track
