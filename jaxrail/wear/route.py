"""A route: a weighted mix of track sections (straights and curves with their cant, at
their speeds, on their irregularity seeds) that one vehicle runs, read from a TOML file.

    name = "curved-route"
    description = "..."
    scenario = "paper-curve"     # the vehicle, wheel, rails, contact, solver and
                                 # irregularity spectrum (a built-in name or a file)
    duration = 10.0              # [s] of each section's run
    wear_model = "archard-kth"   # jaxrail.wear.laws.MODELS
    # [wear] k1 = 5e-4 ...       # optional: the law's fields (checked against their
                                 # published ranges)

    [[sections]]
    weight = 0.2                 # share of the route's distance (normalised)
    radius = 300.0               # [m]; absent for a straight
    cant = 0.150                 # [m]
    direction = "left"           # or "right"
    speed = 15.0                 # [m/s]
    seed = 1                     # irregularity seed (a scenario with a spectrum)
    # transition = 60.0          # [m] optional: the transition's length

Each section is run on its own track: 10 m of straight, then for a curve a clothoid
transition over which the cant rises (``max(20 m, 400 cant)`` long unless given: a ramp
of at most 1:400) and the arc. Wear counts from the time the vehicle's rearmost body
has run ``settle`` (default :data:`SETTLE_DISTANCE`, a route key) past the arc's start
(a straight's: past the first 10 m): the section's wear is its body's, not the entry's. Every track of a kind has the same
length, so the curved sections run as one batch and the straights as another.
"""

import dataclasses
import math
import tomllib

import numpy as np

from .._files import builtin_or_file_text
from ..scenarios import load_scenario
from .laws import MODELS, check_fields, wear_law

LEAD = 10.0  # [m] of straight before a section's body
SETTLE_DISTANCE = 20.0  # [m] run past the body's start by the last wheelset before wear counts
MIN_TRANSITION = 20.0  # [m]
RAMP = 400.0  # transition length per metre of cant [-]
BUILTIN = ("straight-route", "curved-route", "main-line-route")
_KEYS = {"name", "description", "scenario", "duration", "wear_model", "wear", "sections",
         "settle"}
_SECTION_KEYS = {"weight", "radius", "cant", "direction", "speed", "seed", "misalignment",
                 "transition"}


@dataclasses.dataclass(frozen=True)
class Section:
    """One section: ``weight`` its share of the route's distance (normalised);
    ``radius`` [m] (None: straight), ``cant`` [m], ``direction``; ``speed`` [m/s];
    ``seed`` the irregularity seed (None: the scenario's); ``misalignment`` [m];
    ``transition_length`` [m] (None: from the cant)."""

    weight: float
    speed: float
    radius: float | None = None
    cant: float = 0.0
    direction: str = "left"
    seed: int | None = None
    misalignment: float = 0.0
    transition_length: float | None = None

    @property
    def curved(self) -> bool:
        return self.radius is not None

    def transition(self) -> float:
        """The transition's length [m] (0 for a straight)."""
        if not self.curved:
            return 0.0
        if self.transition_length is not None:
            return self.transition_length
        return max(MIN_TRANSITION, RAMP * self.cant)

    def body_start(self) -> float:
        """Arc length [m] where the section's body (the arc, or the straight past the
        lead) starts."""
        return LEAD + self.transition()

    def segments(self, length: float) -> list[dict]:
        """The scenario-style segments of a track ``length`` [m] long."""
        if not self.curved:
            return [{"kind": "straight", "length": LEAD},
                    {"kind": "straight", "length": length - LEAD}]
        return [{"kind": "straight", "length": LEAD},
                {"kind": "transition", "length": self.transition()},
                {"kind": "arc", "length": length - self.body_start(), "radius": self.radius,
                 "cant": self.cant, "direction": self.direction}]


@dataclasses.dataclass(frozen=True)
class Route:
    """A route as read from its file (SI units); ``source`` names the file, ``text`` is
    its content."""

    name: str
    description: str
    scenario: str
    duration: float
    wear_model: str
    wear: dict
    sections: tuple[Section, ...]
    source: str
    text: str = ""
    settle: float = 20.0

    def shares(self) -> np.ndarray:
        """The sections' shares of the route's distance (sum 1)."""
        weights = np.array([s.weight for s in self.sections], dtype=np.float64)
        return weights / weights.sum()

    def law(self):
        """The wear law of ``wear_model`` with the ``[wear]`` fields."""
        return wear_law(self.wear_model, **self.wear)

    def base(self):
        """The base :class:`~jaxrail.scenarios.Scenario`."""
        return load_scenario(self.scenario)


def _number(value, what, where, positive=False, minimum=None):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where}: {what} must be a finite number, got {value!r}")
    if positive and not value > 0.0:
        raise ValueError(f"{where}: {what} must be > 0, got {value!r}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{where}: {what} must be >= {minimum:g}, got {value!r}")
    return float(value)


def _section(raw, where) -> Section:
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: a section is a table ([[sections]]), got {raw!r}")
    unknown = sorted(set(raw) - _SECTION_KEYS)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; a section has "
                         f"{sorted(_SECTION_KEYS)}")
    if "weight" not in raw or "speed" not in raw:
        raise ValueError(f"{where}: a section needs a weight and a speed [m/s]")
    weight = _number(raw["weight"], "weight", where, minimum=0.0)
    speed = _number(raw["speed"], "speed [m/s]", where, positive=True)
    radius = raw.get("radius")
    if radius is not None:
        radius = _number(radius, "radius [m]", where, positive=True)
    cant = _number(raw.get("cant", 0.0), "cant [m]", where, minimum=0.0)
    if radius is None and cant:
        raise ValueError(f"{where}: a straight section (no radius) has no cant, got {cant}")
    direction = raw.get("direction", "left")
    if direction not in ("left", "right"):
        raise ValueError(f"{where}: direction must be 'left' or 'right', got {direction!r}")
    seed = raw.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise ValueError(f"{where}: seed must be a non-negative integer, got {seed!r}")
    misalignment = _number(raw.get("misalignment", 0.0), "misalignment [m]", where)
    transition = raw.get("transition")
    if transition is not None:
        if radius is None:
            raise ValueError(f"{where}: a straight section (no radius) has no transition")
        transition = _number(transition, "transition [m]", where, positive=True)
    return Section(weight, speed, radius, cant, direction, seed, misalignment, transition)


def parse_route(text: str, where: str = "<route>") -> Route:
    """A :class:`Route` from TOML ``text``; ValueError names ``where`` and what is
    wrong (before anything compiles): no sections, a negative weight or weights that do
    not sum to a positive number, an unknown wear model or a law's field outside its
    published range, a seed without an irregularity spectrum."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{where}: not a TOML file ({error})") from None
    unknown = sorted(set(raw) - _KEYS)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; a route has {sorted(_KEYS)}")
    for key in ("name", "scenario", "duration"):
        if key not in raw:
            raise ValueError(f"{where}: missing {key!r}")
    sections = raw.get("sections", [])
    if not isinstance(sections, list) or not sections:
        raise ValueError(f"{where}: the route has no sections (give [[sections]] tables)")
    parsed = tuple(_section(s, f"{where}: sections[{k}]") for k, s in enumerate(sections))
    if not sum(s.weight for s in parsed) > 0.0:
        raise ValueError(f"{where}: the sections' weights sum to "
                         f"{sum(s.weight for s in parsed):g}; they must sum to a positive "
                         "number")
    model = raw.get("wear_model", "archard-kth")
    if model not in MODELS:
        raise ValueError(f"{where}: unknown wear model {model!r}: use one of "
                         f"{', '.join(MODELS)}")
    wear = raw.get("wear", {})
    if not isinstance(wear, dict):
        raise ValueError(f"{where}: [wear] must be a table of the law's fields")
    try:
        check_fields(model, wear)
    except ValueError as error:
        raise ValueError(f"{where}: [wear]: {error}") from None
    route = Route(name=str(raw["name"]), description=str(raw.get("description", "")),
                  scenario=str(raw["scenario"]),
                  duration=_number(raw["duration"], "duration [s]", where, positive=True),
                  wear_model=model, wear=dict(wear), sections=parsed, source=where, text=text,
                  settle=_number(raw.get("settle", SETTLE_DISTANCE), "settle [m]", where,
                                 minimum=0.0))
    try:
        base = route.base()
    except ValueError as error:
        raise ValueError(f"{where}: scenario: {error}") from None
    seeded = [k for k, s in enumerate(parsed) if s.seed is not None]
    if seeded and (base.irregularities is None or base.irregularities.source != "spectrum"):
        raise ValueError(f"{where}: sections {seeded} give an irregularity seed, but the "
                         f"scenario {base.name!r} has no irregularity spectrum")
    for k, s in enumerate(parsed):
        start = wear_start(route, s)
        if start >= route.duration:
            raise ValueError(
                f"{where}: sections[{k}]: at {s.speed:g} m/s the vehicle reaches the "
                f"section's body after {start:.1f} s, beyond the run's {route.duration:g} s: "
                "give a longer duration")
    return route


def load_route(name_or_path) -> Route:
    """A built-in route by name (:data:`BUILTIN`) or a route TOML file."""
    return parse_route(*builtin_or_file_text(name_or_path, __package__, BUILTIN, "route"))


REAR_START = 5.0  # [m] where a run starts the vehicle's rearmost body (initial_state's s0)
VEHICLE_LENGTH = 30.0  # [m] an upper bound on a vehicle's length (the trailer's bogie
#                        centres are 19 m apart)


def wear_start(route: Route, section: Section) -> float:
    """Time [s] from which the section's wear counts (module docstring): the rearmost
    body, at :data:`REAR_START` at the start, ``route.settle`` past the body's start
    (the last wheelset is at least as far)."""
    return max(0.0, section.body_start() + route.settle - REAR_START) / section.speed


def section_scenario(base, section: Section, length: float):
    """The base scenario with ``section``'s track (``length`` [m]), speed, misalignment
    and irregularity seed: one section as a scenario of its own."""
    scenario = dataclasses.replace(base, segments=tuple(section.segments(length)),
                                   speed=section.speed, misalignment=section.misalignment)
    if section.seed is not None and scenario.irregularities is not None:
        scenario = dataclasses.replace(scenario, irregularities=dataclasses.replace(
            scenario.irregularities, seed=section.seed))
    return scenario


def track_length(route: Route, sections) -> float:
    """A common length [m] for the tracks of ``sections``: the longest run plus the
    body's start and a margin."""
    return max(s.body_start() + s.speed * route.duration for s in sections) \
        + REAR_START + 2 * VEHICLE_LENGTH
