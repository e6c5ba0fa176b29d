"""Scenario files: the built-in ones parse and build; bad files are named clearly."""

import importlib.resources
import re
from pathlib import Path

import numpy as np
import pytest

from jaxrail.scenarios import BUILTIN, load_scenario, parse_scenario
from jaxrail.track import curvature, superelevation

MINIMAL = """
name = "x"
[vehicle]
model = "trailer"
wheel = "s1002"
[track]
rail = "uic60"
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
    assert vehicle.n_wheelsets == {"trailer": 4, "bogie": 2, "suspended-wheelset": 1,
                                  "coach": 4, "wagon": 2}[
        scenario.model]
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


ARC = '[{ kind = "arc", length = 50.0, radius = 300.0, cant = 0.1 }]'
# (what is changed in MINIMAL, the error's text): each bad input gets an error that names
# the file, the entry, what is allowed and what was given, before anything compiles.
BAD_INPUTS = [
    (("[run]\nspeed = 10.0", "[run]\nspeed = -1.0"),
     "bad.toml: [run] speed must be within [0.1, 160] m/s, got -1.0"),
    (("speed = 10.0", "speed = 500.0"), "[run] speed must be within [0.1, 160] m/s, got 500.0"),
    (("speed = 10.0", "speed = 1e-9"), "[run] speed must be within [0.1, 160] m/s, got 1e-09"),
    (('kind = "straight"', 'kind = "spiral"'), "kind must be one of"),
    (('model = "trailer"', 'model = "tram"'), "[vehicle] model must be one of"),
    (("length = 100.0", "length = 100.0, radius = 3.0"),
     "track segment 1: unknown key 'radius' in a straight segment"),
    (("[solver]", ""), "missing table [solver]"),
    (("duration = 1.0", 'duration = "long"'), "[run] duration must be a number [s], got 'long'"),
    (("duration = 1.0", "duration = inf"),
     "[run] duration must be within [0.0001, 3600] s, got inf"),
    (("[solver]", "[solver]\nfixed_step = 0.0"), "[solver] fixed_step must be within"),
    (("[track]", "[contact]\nfrction = 0.1\n[track]"),
     "unknown key 'frction' in [contact] (did you mean 'friction'?)"),
    (("[run]", "[run]\nmisalignement = 0.002"),
     "unknown key 'misalignement' in [run] (did you mean 'misalignment'?)"),
    (("[track]", "[contactx]\nfriction = 0.3\n[track]"), "unknown key 'contactx' in the scenario"),
    (("[track]", "[contact]\nfriction = true\n[track]"),
     "[contact] friction must be a number [-], got True"),
    (("[track]", '[contact]\nfriction = "high"\n[track]'),
     "[contact] friction must be a number [-], got 'high'"),
    (("[track]", '[contact]\nmode = "fast"\n[track]'), "[contact] mode must be one of"),
    (('name = "x"', 'name = "x"\ncontact = 5'), "[contact] must be a table, got 5"),
    (('[{ kind = "straight", length = 100.0 }]', ARC.replace("0.1 }", '"lots" }')),
     "track segment 1: cant must be a number [m], got 'lots'"),
    (('[{ kind = "straight", length = 100.0 }]', "[1, 2]"), "track segment 1 must be a table"),
    (('wheel = "s1002"', 'wheel = "s1002"\ndata = "nofile.toml"'),
     "[vehicle] data: no such file"),
    (("[run]", "[run]\nmisalignment = nan"), "[run] misalignment must be within"),
    (("[solver]", "[solver]\noutput_rate = 1e9"), "[solver] output_rate must be within"),
    (("duration = 1.0\n[solver]", "duration = 3600.0\n[solver]\noutput_rate = 1e5"),
     "is 360000001 output times (the trailer's results alone 1.37e+03 GB); at most 200001"),
    (("[solver]", '[solver]\nintegrator = "rk4"'), "[solver] integrator must be one of"),
    (('model = "trailer"', 'model = "trailer"\nformulation = "twists"'),
     "[vehicle] formulation must be one of ('auto', 'joints')"),
    # siblings of the cases above
    (("[track]", "[contact]\nfriction = -0.3\n[track]"),
     "[contact] friction must be within [0.01, 1.5] -, got -0.3"),
    (("[track]", "[contact]\nfriction = 0\n[track]"),
     "[contact] friction must be within [0.01, 1.5] -, got 0.0"),
    (("[track]", "[contact]\nrestitution = 2.0\n[track]"),
     "unknown key 'restitution' in [contact]"),
    (("[track]", "[contact]\nmode = 1\n[track]"), "[contact] mode must be a string, got 1"),
    (('[{ kind = "straight", length = 100.0 }]', ARC.replace("300.0", "0.0")),
     "track segment 1: radius must be within [10, 1e+07] m, got 0.0"),
    (('[{ kind = "straight", length = 100.0 }]', ARC.replace("300.0", "-300.0")),
     "track segment 1: radius must be within [10, 1e+07] m, got -300.0"),
    (('[{ kind = "straight", length = 100.0 }]', ARC.replace("0.1 }", "0.5 }")),
     "track segment 1: cant must be within [-0.2, 0.2] m, got 0.5"),
    (("length = 100.0", "length = -5.0"),
     "track segment 1: length must be within [0.001, 100000] m, got -5.0"),
    (('[{ kind = "straight", length = 100.0 }]', "[]"),
     "[track] segments must be a non-empty list of tables"),
    (('{ kind = "straight", length = 100.0 }', '{ kind = "straight" }'),
     "track segment 1: missing 'length'"),
    (('[{ kind = "straight", length = 100.0 }]', ARC.replace("}", ', direction = "up" }')),
     "track segment 1: a arc segment direction must be one of ('left', 'right'), got 'up'"),
    (("[track]\n", "[track]\nsegment = []\n"), "unknown key 'segment' in [track]"),
    (("[solver]", "[solver]\nrtol = 0"), "[solver] rtol must be within [1e-12, 0.1] -, got 0.0"),
    (("[solver]", "[solver]\natol = -1e-9"), "[solver] atol must be within"),
    (("[solver]", '[solver]\nfixed_step = "1ms"'),
     "[solver] fixed_step must be a number [s], got '1ms'"),
    (("[solver]", "[solver]\nmax_steps = 10"), "unknown key 'max_steps' in [solver]"),
    (("[solver]", "[solver]\njacobian_every = 0"),
     "[solver] jacobian_every must be an integer from 1 to 1000, got 0"),
    (("[solver]", "[solver]\njacobian_every = 2.5"),
     "[solver] jacobian_every must be an integer from 1 to 1000, got 2.5"),
    (("duration = 1.0\n[solver]", "duration = 3600.0\n[solver]\nfixed_step = 1e-7"),
     "3600 s in fixed steps of 1e-07 s is 3.6e+10 steps; at most 2000000"),
    (('name = "x"', "name = 5"), "the scenario name must be a string, got 5"),
    (('name = "x"', 'name = ""'), "the scenario name must not be empty"),
    (("speed = 10.0", "speed = [10.0]"), "[run] speed must be a number [m/s], got [10.0]"),
    (("duration = 1.0", "duration = 0"), "[run] duration must be within [0.0001, 3600] s, got 0.0"),
    (("duration = 1.0", "duration = -1.0"), "[run] duration must be within"),
    (("[run]", "[run]\nmisalignment = 0.05"),
     "[run] misalignment must be within [-0.035, 0.035] m, got 0.05"),
    (("[run]", '[run]\nmisalignment = "2mm"'), "[run] misalignment must be a number [m], got '2mm'"),
    (('model = "trailer"', "model = 3"), "[vehicle] model must be a string, got 3"),
    (("[vehicle]", "[vehicle]\nwheelbase = 2.5"), "unknown key 'wheelbase' in [vehicle]"),
    (('rail = "uic60"', 'rail = "uic60"\ninclination = 40'),
     "[track] inclination must be a string, got 40"),
    # the rails are the track's: [track] rail, inclination and gauge [m]
    (('wheel = "s1002"', 'wheel = "s1002"\nrail = "uic60"'),
     "bad.toml: [vehicle] rail: the rails belong to the track: give rail in [track]"),
    (('wheel = "s1002"', 'wheel = "s1002"\ngauge = 1.435'),
     "bad.toml: [vehicle] gauge: the rails belong to the track: give gauge in [track]"),
    (('rail = "uic60"', 'rail = "uic60"\ngauge = 1435.0'),
     "bad.toml: [track] gauge must be within [0.6, 1.7] m, got 1435.0"),
    # [track] flexible: true, false or a table of [lateral, vertical] values
    (("length = 100.0 }]", 'length = 100.0 }]\nflexible = "yes"'),
     "bad.toml: [track] flexible must be true, false or a table of mass, stiffness and "
     "damping, got 'yes'"),
    (("length = 100.0 }]", "length = 100.0 }]\nflexible = { stiffness = [5e7] }"),
     "bad.toml: [track] flexible: stiffness must be [lateral, vertical], got [50000000.0]"),
    (("length = 100.0 }]", "length = 100.0 }]\nflexible = { mass = [165.0, -165.0] }"),
     "bad.toml: [track] flexible: mass must be within [1, 10000] kg, got -165.0"),
    (("length = 100.0 }]", 'length = 100.0 }]\nflexible = { damping = [1e5, "soft"] }'),
     "bad.toml: [track] flexible: damping must be a number [N s/m], got 'soft'"),
    (("length = 100.0 }]", "length = 100.0 }]\nflexible = { stifness = [5e7, 7.5e7] }"),
     "unknown key 'stifness' in [track] flexible (did you mean 'stiffness'?)"),
]

# Entries whose values are only known wrong when the scenario is built (profiles by name
# or file, the layout's joints): build() names the file and the entry, before compiling.
BAD_BUILDS = [
    (('rail = "uic60"', 'rail = "uic61"'), "bad.toml: [track] rail: unknown profile 'uic61'"),
    (('rail = "uic60"', 'rail = "s1002"'), "bad.toml: [track] rail: 's1002' is a wheel profile"),
    (('wheel = "s1002"', 'wheel = "s1003"'), "bad.toml: [vehicle] wheel: unknown profile 's1003'"),
    (('wheel = "s1002"', 'wheel = "uic60"'), "bad.toml: [vehicle] wheel: 'uic60' is a rail profile"),
    (('rail = "uic60"', 'rail = "uic60"\ninclination = "1:30"'),
     "bad.toml: [track] rail: uic60: unknown inclination '1:30'"),
    (('length = 100.0 }]', 'length = 100.0 }, { kind = "transition", length = 30.0 }]'),
     "bad.toml: [track] segments: segments[1] (Transition): a transition at the end"),
    (('[{ kind = "straight", length = 100.0 }]',
      '[{ kind = "straight", length = 100.0 }, ' + ARC[1:]),
     "bad.toml: [track] segments: discontinuous layout: cant jumps from 0.0 m to 0.1 m"),
]


@pytest.mark.parametrize("change, message", BAD_BUILDS)
def test_bad_scenarios_are_named_when_built(change, message):
    scenario = parse_scenario(MINIMAL.replace(*change), "bad.toml")
    with pytest.raises(ValueError, match=re.escape(message)):
        scenario.build()


@pytest.mark.parametrize("change, message", BAD_INPUTS)
def test_bad_scenarios_are_named(change, message):
    text = MINIMAL.replace(*change)
    assert text != MINIMAL
    with pytest.raises(ValueError, match=re.escape(message)):
        parse_scenario(text, "bad.toml")


def test_flexible_track_values_reach_the_track():
    text = MINIMAL.replace("length = 100.0 }]", "length = 100.0 }]\nflexible = { stiffness = "
                           "[4e7, 6e7] }")
    _, _, track = parse_scenario(text, "flex.toml").build()
    np.testing.assert_array_equal(np.asarray(track.support.stiffness), [4e7, 6e7])
    assert float(track.support.mass[1]) == 165.0  # the default where none is given
    assert parse_scenario(MINIMAL.replace("length = 100.0 }]", "length = 100.0 }]\n"
                                          "flexible = false")).build()[2].support is None


def test_unknown_scenario_lists_the_builtin_ones():
    with pytest.raises(ValueError, match="paper-curve"):
        load_scenario("no-such-scenario")


def test_fixed_steps_cover_the_duration_exactly():
    scenario = load_scenario("bogie-curve-entry")
    options = scenario.solver_options()
    assert options.fixed_step == 5e-4 and options.max_steps == 2001  # 2000 steps + 1
    assert scenario.solver_options(duration=0.25).max_steps == 501
    assert load_scenario("paper-curve").solver_options().fixed_step is None


def test_the_jacobian_interval_reaches_the_solver():
    path = importlib.resources.files("jaxrail.scenarios").joinpath("data/paper-curve.toml")
    text = path.read_text().replace("[solver]", "[solver]\njacobian_every = 4")
    assert parse_scenario(text, "x.toml").solver_options().solver().jacobian_every == 4
    assert load_scenario("paper-curve").solver_options().solver().jacobian_every == 8


def test_bogie_carries_half_the_carbody():
    vehicle, params, _ = load_scenario("bogie-curve-entry").build()
    masses = dict(zip(vehicle.system.body_names, np.asarray(params.system.bodies.mass)))
    assert masses["frame"] == 2615.0 + 32000.0 / 2  # bogie + carbody / 2 [V-src]
    assert masses["wheelset_1"] == 1813.0  # with the axlebox body it carries
    preload = np.asarray(params.system.forces["bushing"].preload)[:, 2]
    assert np.allclose(-4 * preload, masses["frame"] * 9.81)  # four primary bushings


def test_the_suspended_wheelset_refuses_a_curved_track(tmp_path):
    text = (Path(__file__).parents[1] / "jaxrail" / "scenarios" / "data"
            / "suspended-wheelset.toml").read_text()
    text = text.replace('segments = [{ kind = "straight", length = 400.0 }]',
                        'segments = [{ kind = "straight", length = 100.0 }, '
                        '{ kind = "arc", length = 100.0, radius = 1000.0 }]')
    path = tmp_path / "curved.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"straight track only.*segments \[2\]"):
        load_scenario(str(path)).build()


def test_the_suspended_wheelset_is_its_vehicle_file_straight_or_curved():
    """The scenario builds the built-in file: a prismatic guide to the ground, or with
    a curve radius the revolute joint about the curve's centre."""
    scenario = load_scenario("suspended-wheelset")
    for radius, kind in ((None, "prismatic"), (650.0, "revolute")):
        vehicle, _, _ = scenario.build(radius)
        kinds = {n: g.kind for g in vehicle.system.joint_groups for n in g.names}
        assert kinds["guide"] == kind and vehicle.name == "suspended wheelset"


@pytest.mark.parametrize("model", ["bogie", "suspended-wheelset"])
def test_vehicle_data_replaces_the_files_parameters(model, tmp_path):
    """``[vehicle] data`` (the trailer's old format) replaces the built-in file's
    parameters of the same names, as it replaced the Python builders' values."""
    import equinox as eqx
    import jax

    from jaxrail.vehicles import bogie, trailer_values
    from jaxrail.vehicles.suspended_wheelset import suspended_wheelset
    from jaxrail.vehicles.vehicle_file import data_folder

    data = tmp_path / "heavy.toml"
    text = (data_folder() / "manchester_trailer.toml").read_text()
    data.write_text(text.replace("value = 32000.0", "value = 36000.0"))
    # with the axle joints, as the Python builders build it
    text = MINIMAL.replace('model = "trailer"', f'model = "{model}"\ndata = "{data}"\n'
                           'formulation = "joints"')
    vehicle, params, _ = parse_scenario(text, str(tmp_path / "s.toml")).build()
    values = trailer_values(data)
    assert values["carbody.mass"] == 36000.0
    builder = {"bogie": bogie, "suspended-wheelset": suspended_wheelset}[model]
    vehicle_py, params_py = builder(values=values)
    assert vehicle == vehicle_py
    params_py = eqx.tree_at(lambda p: p.contact.friction, params_py, params.contact.friction)
    for a, b in zip(jax.tree.leaves(params), jax.tree.leaves(params_py)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_a_scenario_names_a_vehicle_file_relative_to_itself(tmp_path):
    """``[vehicle] file`` is read relative to the scenario, and the built-in name
    ``trailer`` is that same vehicle file: the two build the same vehicle, number for
    number; the file's own profiles serve where the scenario names none."""
    import jax

    from jaxrail.vehicles.vehicle_file import data_folder

    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "my_vehicle.toml").write_text((data_folder() / "trailer.toml").read_text())
    text = MINIMAL.replace('model = "trailer"\nwheel = "s1002"',
                           'file = "my_vehicle.toml"')
    (folder / "run.toml").write_text(text)
    from_file, params_file, _ = load_scenario(folder / "run.toml").build()
    builtin, params_builtin, _ = parse_scenario(MINIMAL).build()
    assert from_file.system == builtin.system and from_file.wheelsets == builtin.wheelsets
    for a, b in zip(jax.tree.leaves(params_file), jax.tree.leaves(params_builtin)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("vehicle, message", [
    ('model = "trailer"\nfile = "v.toml"', "give a model or a file, not both"),
    ('file = "nowhere.toml"', "[vehicle] file: no such file"),
    ('model = "tram"', "model must be one of"),
    ('wheel = "s1002"', "needs a model"),
])
def test_bad_vehicle_entries_are_named(vehicle, message):
    text = MINIMAL.replace('model = "trailer"\nwheel = "s1002"', vehicle)
    with pytest.raises(ValueError, match=re.escape(message)):
        parse_scenario(text, "bad.toml")


def test_the_tracks_rail_and_gauge_reach_its_rails():
    from jaxrail.track import standard_rails

    _, _, track = parse_scenario(MINIMAL).build()
    assert float(track.rails.offset) == float(standard_rails().offset)
    text = MINIMAL.replace('rail = "uic60"', 'rail = "uic60"\ninclination = "1:20"\n'
                           'gauge = 1.445')
    rails = parse_scenario(text).build()[2].rails
    assert rails.profile.name == "UIC60 1:20"
    assert float(rails.gauge) == pytest.approx(1.445, abs=1e-15)
