"""Measurement files: written whole and read back exactly; bad files get errors that
name the file, the line and what is wrong; channel names are checked against the
vehicle."""

import numpy as np
import pytest

from jaxrail.identify import Measurements, read_measurements, write_measurements
from jaxrail.identify.measurements import check_channels, sample
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
