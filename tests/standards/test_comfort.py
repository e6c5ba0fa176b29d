"""EN 12299 comfort of a results file: floor readings of a swaying carbody against the
closed form N_MV = 6 a |Wd(f)| / sqrt(2) of a lateral sine of amplitude a."""

import h5py
import numpy as np
import pytest

from jaxrail.standards.comfort import comfort_of_file, format_comfort

WD_AT_1_HZ = 1.011  # ISO 2631-1 Table 3, Wd weighting factor at 1 Hz (its precision)


def _write(path, amplitude=0.5, frequency=1.0, rate=50.0, duration=30.0, qddot=True):
    t = np.arange(int(duration * rate) + 1) / rate
    w = 2 * np.pi * frequency
    n = 2  # carbody, wheelset
    q = np.zeros((len(t), n, 7))
    q[:, :, 3] = 1.0
    q[:, 0, 1] = -amplitude / w**2 * np.sin(w * t)
    q[:, 0, 2] = 2.0
    qdot = np.zeros_like(q)
    qdot[:, 0, 1] = -amplitude / w * np.cos(w * t)
    acc = np.zeros_like(q)
    acc[:, 0, 1] = amplitude * np.sin(w * t)
    with h5py.File(path, "w") as f:
        f["time"], f["valid"] = t, np.ones(len(t), np.uint8)
        f["bodies/q"], f["bodies/qdot"] = q, qdot
        f["bodies/q"].attrs["body_names"] = ["carbody", "wheelset_1"]
        if qddot:
            f["bodies/qddot"] = acc
    return path


def test_swaying_carbody_has_the_closed_form_mean_comfort(tmp_path):
    comfort = comfort_of_file(_write(tmp_path / "run.h5"))
    assert comfort["blocks_of_5_s"] == 6 and comfort["indicative"]
    expected = 6 * 0.5 * WD_AT_1_HZ / np.sqrt(2)
    for point in comfort["points"].values():  # a pure translation: every point alike
        assert point["n_mv"] == pytest.approx(expected, rel=2e-3)
        assert point["a_x_p95"] == pytest.approx(0.0, abs=1e-9)
        assert point["a_z_p95"] == pytest.approx(0.0, abs=1e-6)  # gravity: no Wb at 0 Hz
    assert "N_MV" in format_comfort(comfort) and "indicative" in format_comfort(comfort)


def test_missing_accelerations_and_bodies_are_named(tmp_path):
    with pytest.raises(ValueError, match="without bodies/qddot"):
        comfort_of_file(_write(tmp_path / "old.h5", qddot=False))
    with pytest.raises(ValueError, match="no body named 'coach'"):
        comfort_of_file(_write(tmp_path / "run.h5"), body="coach")
