"""`jaxrail identify`: bad input is named before anything compiles; the figure of a fit
is written. (The fit itself runs in experiments/identify_contact: compiling the
gradient of a simulation takes about 10 minutes, over the suite's budget.)"""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.cli import main
from jaxrail.identification import Identification, Measurements, write_measurements
from jaxrail.identification.fit import least_squares
from jaxrail.plots.identification import plot_identification


def run(capfd, *args):
    """``jaxrail identify ARGS`` in this process: (exit status, what it wrote to stderr)."""
    capfd.readouterr()
    try:
        status = main(["identify", *args])
    except SystemExit as stop:  # argparse's errors
        status = stop.code
    return status, capfd.readouterr().err


@pytest.fixture
def measured(tmp_path):
    path = tmp_path / "m.csv"
    t = np.linspace(0.0, 0.5, 6)
    write_measurements(path, Measurements(t, ("wheelset_lateral_1",), 1e-3 * t[:, None],
                                          [1e-4]))
    return path


@pytest.mark.parametrize("args, message", [
    (("--fit", "stiffness"), "unknown parameter 'stiffness'"),
    (("--fit", "secondary_lateral_stiffness"), "no secondary suspension"),
    (("--fit", "friction", "--initial", "friction"), "--initial: expected name=value"),
    (("--fit", "friction", "--bounds", "friction=0.1"), "--bounds: expected name=lower:upper"),
    (("--fit", "friction", "--initial", "contact_stiffness=2"), "not fitted"),
    (("--fit", "friction", "--cutoff", "0"), "--cutoff must be > 0 Hz"),
    (("--fit", "friction", "--initial", "friction=-1"),
     "initial value: friction must be within [0.01, 1.5] -, got -1.0"),
    (("--fit", "friction", "--bounds", "friction=0.5:0.1"),
     "bounds: friction needs 0 < lo < hi, got (0.5, 0.1)"),
    (("--fit", "friction", "--initial", "friction=0.9", "--bounds", "friction=0.1:0.5"),
     "the initial friction 0.9 lies outside its bounds [0.1, 0.5]"),
])
def test_bad_arguments_are_named(measured, args, message, capfd):
    status, err = run(capfd, "bogie-curve-entry", "--measured", str(measured), *args)
    assert status == 2
    assert message in err


def test_measurements_longer_than_the_run_are_refused(tmp_path, capfd):
    path = tmp_path / "long.csv"
    write_measurements(path, Measurements([0.0, 2.0], ("wheelset_lateral_1",),
                                          [[0.0], [0.0]], [1e-4]))
    status, err = run(capfd, "bogie-curve-entry", "--measured", str(path),
                      "--fit", "friction")
    assert status == 2 and "only 1.0 s" in err


def test_measurements_too_dense_for_the_run_are_refused(tmp_path, capfd):
    path = tmp_path / "dense.csv"  # two samples 1 ns apart: 8e9 output times over 1 s
    write_measurements(path, Measurements([0.0, 1e-9], ("wheelset_lateral_1",),
                                          [[0.0], [0.0]], [1e-4]))
    status, err = run(capfd, "bogie-curve-entry", "--measured", str(path),
                      "--fit", "friction")
    assert status == 2
    assert "sampled every 1e-09 s need 8000000001 output times" in err


def test_figure_of_a_fit(tmp_path):
    t = np.linspace(0.0, 1.0, 30)
    data = 2.0 * np.exp(-1.5 * t)

    def residuals(v, y):
        return (v[0] * jnp.exp(-v[1] * jnp.asarray(t)) - y) / 0.01

    fit = least_squares(residuals, ("a", "k"), [2.5, 1.0], [0.2, 0.15], [20.0, 15.0],
                        data=jnp.asarray(data))
    measured = Measurements(t, ("wheelset_lateral_1",), data[:, None], [0.01])
    simulated = data[:, None] + 0.01 * fit.residuals[:, None]
    path = tmp_path / "fit.png"
    plot_identification(Identification(fit, measured, simulated, {}), path,
                        truth={"a": 2.0, "k": 1.5})
    assert path.stat().st_size > 10_000
