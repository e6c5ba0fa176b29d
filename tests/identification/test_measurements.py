"""Measurement files: written whole and read back exactly; bad files get errors that
name the file, the line and what is wrong; channel names are checked against the
vehicle."""

import numpy as np
import pytest

from jaxrail.identification import Measurements, read_measurements, write_measurements
from jaxrail.identification.measurements import (check_channels, gaussian_window, sample,
                                          triangular_window)
from jaxrail.vehicles import bogie

CHANNELS = ("wheelset_lateral_1", "wheel_vertical_force_2_right", "lateral_acceleration_frame")


def make():
    t = np.linspace(0.0, 1.0, 11)
    values = np.stack([1e-3 * np.sin(t), 5e4 + 1e3 * t, 0.1 * np.cos(t)], axis=1)
    return Measurements(t, CHANNELS, values, [1e-4, 500.0, 0.05])


def test_round_trip_is_exact(tmp_path):
    path = tmp_path / "m.csv"
    write_measurements(path, make(), comment="synthetic\nsecond line")
    back = read_measurements(path)
    assert back.channels == CHANNELS
    for field in ("time", "values", "noise"):
        assert np.array_equal(getattr(back, field), getattr(make(), field))


@pytest.mark.parametrize("text, message", [
    ("t,a\nnoise,1\n0,1\n1,2\n", "header must be time"),
    ("time,wheelset_lateral_1\nsigma,1\n0,1\n1,2\n", ":2: the second row must be noise"),
    ("time,wheelset_lateral_1\nnoise,1\n0,1\n1,x\n", ":4: could not convert"),
    ("time,wheelset_lateral_1\nnoise,1\n0,1\n1\n", ":4: 1 values, header has 2"),
    ("time,wheelset_lateral_1\nnoise,0\n0,1\n1,2\n", "noise must be > 0"),
    ("time,wheelset_lateral_1\nnoise,1\n1,1\n0,2\n", "strictly increasing"),
    ("time,wheelset_lateral_1\nnoise,1\n0,1\n", "at least two samples"),
])
def test_bad_files_are_named(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as error:
        read_measurements(path)
    assert "bad.csv" in str(error.value)


def test_channel_names_are_checked_against_the_vehicle():
    vehicle, _ = bogie()
    check_channels(CHANNELS, vehicle)
    with pytest.raises(ValueError, match="has 2 wheelsets"):
        check_channels(("wheelset_yaw_3",), vehicle)
    with pytest.raises(ValueError, match="no body 'carbody'"):
        check_channels(("lateral_acceleration_carbody",), vehicle)
    with pytest.raises(ValueError, match="unknown channel 'wheelset_roll_1'"):
        check_channels(("wheelset_roll_1",), vehicle)


def test_sampling_interpolates_linearly_between_outputs():
    t = np.linspace(0.0, 1.0, 5)
    values = np.stack([2.0 * t + 1.0, t**2], axis=1)
    out = np.asarray(sample(t, values, np.array([0.1, 0.5, 0.9])))
    assert np.allclose(out[:, 0], [1.2, 2.0, 2.8])
    assert np.allclose(out[1, 1], 0.25)


def test_gaussian_low_pass_has_its_analytic_response():
    """Sampled at 100 Hz from outputs at 800 Hz through the 20 Hz Gaussian: sines of
    2, 10 and 20 Hz keep the amplitude exp(-ln 2 (f / 20)^2) (0.993, 0.841, 0.5), a
    170 Hz ringing (aliased to 30 Hz by plain sampling) is gone."""
    t = np.linspace(0.0, 1.0, 801)
    times = np.linspace(0.0, 1.0, 101)
    inner = slice(5, -5)  # the window is cut at the ends
    for f in (2.0, 10.0, 20.0):
        out = np.asarray(sample(t, np.sin(2 * np.pi * f * t)[:, None], times,
                                gaussian_window(20.0)))[inner, 0]
        gain = np.exp(-np.log(2.0) * (f / 20.0) ** 2)
        assert np.max(np.abs(out - gain * np.sin(2 * np.pi * f * times[inner]))) < 2e-3
    ringing = np.sin(2 * np.pi * 170.0 * t + 0.3)
    plain = np.asarray(sample(t, ringing[:, None], times))[:, 0]
    assert np.max(np.abs(plain)) > 0.9  # plain sampling keeps the full ringing, aliased
    out = np.asarray(sample(t, ringing[:, None], times, gaussian_window(20.0)))[inner, 0]
    assert np.max(np.abs(out)) < 1e-6


def test_low_pass_keeps_a_constant_at_the_ends_and_rejects_a_bad_cutoff():
    t = np.linspace(0.0, 1.0, 801)
    out = np.asarray(sample(t, np.full((801, 1), 3.0), np.linspace(0.0, 1.0, 11),
                            gaussian_window(20.0)))
    assert np.allclose(out, 3.0)
    with pytest.raises(ValueError, match="cutoff must be > 0"):
        gaussian_window(0.0)


def test_a_nan_output_spoils_only_the_samples_whose_window_reaches_it():
    t = np.linspace(0.0, 1.0, 81)
    values = np.ones((81, 1))
    values[60:] = np.nan  # a run that stopped at 0.74 s
    out = np.asarray(sample(t, values, np.linspace(0.0, 1.0, 11),
                            triangular_window(0.1)))[:, 0]
    assert np.allclose(out[:7], 1.0)  # windows up to 0.7 s end before 0.75 s
    assert np.all(np.isnan(out[8:]))
