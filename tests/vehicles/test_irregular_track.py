"""Runs on irregular track: the gradient of a run in the irregularity's amplitude
against central differences, a measured file written by ``jaxrail track
irregularities`` giving the same run as the realisation it holds, the irregularity in
the outputs, and the warnings and errors around the track's and the file's ends."""

import dataclasses
import warnings

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.cli import main
from jaxrail.scenarios import load_scenario, parse_scenario, run_scenario
from jaxrail.simulation import solve

SCENARIO = """
name = "wheelset-irregular"
[vehicle]
model = "single-wheelset"
wheel = "s1002"
[track]
rail = "uic60"
inclination = "1:40"
segments = [{ kind = "straight", length = 60.0 }]
[irregularities]
%s
[run]
speed = 15.0
misalignment = 0.001
duration = 0.3
[solver]
fixed_step = 2e-4
output_rate = 100.0
"""
SPECTRUM = 'spectrum = "german-high"\nseed = 7\nscale = 2.0'


@pytest.fixture(scope="module")
def spectral():
    return parse_scenario(SCENARIO % SPECTRUM, "spectral.toml")


@pytest.fixture(scope="module")
def spectral_run(spectral):
    return run_scenario(spectral)


def test_irregularity_at_each_wheelset_is_in_the_outputs(spectral_run):
    result, _, _, track = spectral_run
    assert result.status == "successful"
    s = np.asarray(result.q)[:, 0]  # the straight runs along global X from the origin
    expected = np.asarray(jax.vmap(track.irregularity.at)(jnp.asarray(s)))
    np.testing.assert_allclose(np.asarray(result.irregularity)[:, 0], expected, atol=1e-12)
    assert np.abs(np.asarray(result.irregularity)).max() > 1e-3


def test_a_measured_file_of_the_realisation_gives_the_same_run(spectral, spectral_run,
                                                               tmp_path, capsys):
    csv = tmp_path / "line.csv"
    assert main(["track", "irregularities", "--spectrum", "german-high", "--length", "60",
                 "--seed", "7", "--scale", "2", "--csv", str(csv)]) == 0
    measured = parse_scenario(SCENARIO % f'file = "{csv}"', "measured.toml")
    again, *_ = run_scenario(measured)
    first = spectral_run[0]
    assert again.status == "successful"
    for field in ("wheelset_lateral", "wheelset_vertical", "irregularity"):
        difference = np.abs(np.asarray(getattr(again, field)) - np.asarray(getattr(first, field)))
        assert difference.max() < 1e-9, (field, difference.max())
    # and the irregular run differs from the one without its irregularity (scale 0: the
    # same program) by far more than that
    flat = dataclasses.replace(spectral.irregularities, scale=0.0)
    smooth, *_ = run_scenario(dataclasses.replace(spectral, irregularities=flat))
    assert np.abs(np.asarray(smooth.wheelset_lateral) - np.asarray(first.wheelset_lateral)).max() > 1e-5


def test_gradient_of_a_run_in_the_amplitude_matches_central_differences():
    """Forward mode through the initial equilibrium and 0.1 s of fixed steps, against
    central differences. The run starts centred on the irregular track and holds one
    patch per wheel throughout: where a patch is born or dies the run is not
    differentiable (a kink in time that moves with the amplitude)."""
    scenario = parse_scenario(SCENARIO % 'spectrum = "german-low"\nseed = 3', "gradient.toml")
    vehicle, params, track = scenario.build()
    options = scenario.solver_options(duration=0.1)

    def output(scale):
        irregular = eqx.tree_at(lambda t: t.irregularity.scale, track, scale)
        result = solve(vehicle, params, irregular, 0.1, scenario.speed, 0.0, options=options,
                       adjoint=diffrax.ForwardMode())
        single = jnp.all(jnp.sum(result.wheels.active, axis=-1) == 1)
        # the wheelset's mean lateral displacement and its final yaw, weighted to a scalar
        return (jnp.mean(result.wheelset_lateral) + 0.1 * result.wheelset_yaw[-1, 0],
                jnp.mean(result.wheelset_vertical), single)

    value_and_slope = jax.jit(lambda k: jax.jvp(output, (k,), (jnp.ones_like(k),)))
    values, slopes = value_and_slope(jnp.asarray(1.0))
    assert bool(values[2])  # one patch per wheel all along
    h = 1e-5
    plus, minus = (value_and_slope(jnp.asarray(1.0 + d))[0] for d in (h, -h))
    for k in range(2):
        central = (float(plus[k]) - float(minus[k])) / (2 * h)
        assert np.isfinite(float(slopes[k])) and abs(central) > 1e-5
        assert float(slopes[k]) == pytest.approx(central, rel=1e-4)


def test_a_file_that_does_not_cover_the_run_is_refused_before_compiling(tmp_path, capsys):
    csv = tmp_path / "short.csv"
    assert main(["track", "irregularities", "--spectrum", "german-low", "--length", "8",
                 "--csv", str(csv)]) == 0
    scenario = parse_scenario(SCENARIO % f'file = "{csv}"', "short.toml")
    with pytest.raises(ValueError, match=r"covers s = 0 to 8 m but the run's wheelsets go"):
        run_scenario(scenario)


def test_a_run_past_the_design_track_warns_naming_the_extension():
    scenario = load_scenario("straight")
    scenario = dataclasses.replace(scenario, segments=({"kind": "straight", "length": 40.0},),
                                   duration=10.0)
    vehicle, params, track = scenario.build()
    from jaxrail.simulation import run_span, warn_beyond_track

    with pytest.warns(UserWarning, match=r"past the end of the 40 m design track: its last "
                                         r"segment continues by its own law"):
        warn_beyond_track(track, run_span(params, 18.3, 10.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_beyond_track(track, run_span(params, 18.3, 0.01))  # within: silent


@pytest.mark.parametrize("table, message", [
    ('spectrum = "german-middle"', "unknown irregularity spectrum 'german-middle'"),
    ('spectrum = "fra-0"', "unknown irregularity spectrum 'fra-0'"),
    ('spectrum = "german-low"\nband = [150.0, 3.0]', "ends swapped"),
    ('spectrum = "german-low"\nscale = -0.5', r"\[irregularities\] scale"),
    ('spectrum = "german-low"\nseed = -1', "seed must be an integer >= 0"),
    ('file = "nowhere.csv"', "no such file"),
    ('spectrum = "german-low"\nfile = "x.csv"', "exactly one of"),
    ('defect = { kind = "lateral", wavelength = 10.0, amplitude = 0.005 }', "missing position"),
    ('defect = { kind = "twist", wavelength = 10.0, amplitude = 0.005, position = 5.0 }',
     "kind must be one of"),
    ('spectrum = "german-low"\nsed = 3', "unknown key 'sed'"),
])
def test_bad_irregularities_are_named(table, message):
    with pytest.raises(ValueError, match=message):
        parse_scenario(SCENARIO % table, "bad.toml").build()


def test_a_scenario_file_that_is_not_text_is_named(tmp_path):
    path = tmp_path / "scenario.toml"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe" * 10)
    with pytest.raises(ValueError, match=r"scenario.toml: not a text \(UTF-8\) scenario file"):
        load_scenario(path)


def test_defect_scenario_builds_its_dip():
    scenario = parse_scenario(SCENARIO % 'defect = { kind = "vertical", wavelength = 5.0, '
                                         'amplitude = 0.004, position = 20.0 }', "dip.toml")
    _, _, track = scenario.build()
    assert float(track.irregularity.at(22.5)[1]) == pytest.approx(-0.004, rel=1e-9)
    assert float(track.irregularity.at(40.0)[1]) == 0.0
