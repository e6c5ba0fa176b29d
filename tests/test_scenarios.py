"""Scenario files: the built-in ones parse and build; bad files are named clearly."""

import numpy as np
import pytest

from jaxrail.scenarios import BUILTIN, load_scenario, parse_scenario
from jaxrail.track import curvature, superelevation

MINIMAL = """
name = "x"
[vehicle]
model = "trailer"
wheel = "s1002"
rail = "uic60"
[track]
segments = [{ kind = "straight", length = 100.0 }]
[run]
speed = 10.0
duration = 1.0
[solver]
"""


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_scenarios_build(name):
    scenario = load_scenario(name)
    vehicle, params, track = scenario.build()
    assert scenario.name == name
    assert vehicle.n_wheelsets == {"trailer": 4, "bogie": 2}[scenario.model]
    assert float(params.contact.friction) == scenario.friction
    assert scenario.solver_options().n_outputs == int(scenario.duration * scenario.output_rate) + 1


def test_paper_curve_layout():
    scenario = load_scenario("paper-curve")
    assert (scenario.speed, scenario.duration, scenario.misalignment) == (18.3, 41.0, 0.002)
    _, _, track = scenario.build()
    # full curve (300 m, left, 110 mm cant) from 120 m to 706 m, ramps either side
    for s in (130.0, 400.0, 700.0):
        assert float(curvature(track, s)) == pytest.approx(1 / 300.0, rel=1e-12)
        assert float(superelevation(track, s)) == pytest.approx(0.110, rel=1e-12)
    assert float(curvature(track, 85.0)) == pytest.approx(0.5 / 300.0, rel=1e-9)
    assert float(curvature(track, 10.0)) == 0.0 and float(curvature(track, 800.0)) == 0.0
    # the leading wheelset (10.78 m ahead of the carbody centre, which starts at
    # 5 m + 10.78 m) enters the full curve at about 5.1 s and leaves it at 37.1 s
    start = 5.0 + 2 * 10.78
    assert (120.0 - start) / scenario.speed == pytest.approx(5.1, abs=0.05)
    assert (706.0 - start) / scenario.speed == pytest.approx(37.1, abs=0.05)
    assert np.isclose(float(track.segment_start[-1]) + 100.0, 876.0)


def test_simplified_scenario_differs_only_in_the_wheel():
    real, simplified = load_scenario("paper-curve"), load_scenario("paper-curve-simplified")
    assert simplified.wheel == "s1002-simplified" and real.wheel == "s1002"
    assert real.segments == simplified.segments and real.speed == simplified.speed


@pytest.mark.parametrize("change, message", [
    (("[run]\nspeed = 10.0", "[run]\nspeed = -1.0"), "speed must be > 0"),
    (('kind = "straight"', 'kind = "spiral"'), "kind must be one of"),
    (('model = "trailer"', 'model = "tram"'), "vehicle model must be one of"),
    (("length = 100.0", "length = 100.0, radius = 3.0"), "unknown keys"),
    (("[solver]", ""), r"missing table \[solver\]"),
    (("duration = 1.0", 'duration = "long"'), "'duration' must be a float"),
    (("[solver]", "[solver]\nfixed_step = 0.0"), "fixed_step must be > 0"),
])
def test_bad_scenarios_are_named(change, message):
    text = MINIMAL.replace(*change)
    assert text != MINIMAL
    with pytest.raises(ValueError, match=message):
        parse_scenario(text, "bad.toml")


def test_unknown_scenario_lists_the_builtin_ones():
    with pytest.raises(ValueError, match="paper-curve"):
        load_scenario("no-such-scenario")


def test_fixed_steps_cover_the_duration_exactly():
    scenario = load_scenario("bogie-curve-entry")
    options = scenario.solver_options()
    assert options.fixed_step == 5e-4 and options.max_steps == 2001  # 2000 steps + 1
    assert scenario.solver_options(duration=0.25).max_steps == 501
    assert load_scenario("paper-curve").solver_options().fixed_step is None


def test_bogie_carries_half_the_carbody():
    vehicle, params, _ = load_scenario("bogie-curve-entry").build()
    masses = dict(zip(vehicle.system.body_names, np.asarray(params.system.bodies.mass)))
    assert masses["frame"] == 2615.0 + 32000.0 / 2  # bogie + carbody / 2 [V-src]
    assert masses["wheelset_1"] + masses["axlebox_1"] == 1813.0
    preload = np.asarray(params.system.forces["bushing"].preload)[:, 2]
    assert np.allclose(-4 * preload, masses["frame"] * 9.81)  # four primary bushings
