"""Per-sample quantities against hand computations: the 2 m sliding mean against a
brute-force loop, Prud'homme's limit, the sign of the track shifting force, the wear
number; the table files read back equal, NaN and strings included."""

from types import SimpleNamespace

import numpy as np
import pytest

from jaxrail.montecarlo import read_table, write_table
from jaxrail.montecarlo.summary import (prudhomme_limit, sliding_mean, sliding_ratio,
                                        track_shifting_force, wear_number)


def test_sliding_mean_equals_a_loop():
    x = np.random.default_rng(0).normal(size=37)
    for window in (1, 4, 11, 37, 50):
        w = min(window, 37)
        loop = [np.mean(x[i:i + w]) for i in range(37 - w + 1)]
        assert np.allclose(sliding_mean(x, window), loop, rtol=0, atol=1e-13)


def test_sliding_ratio_is_the_ratio_of_the_means_and_survives_an_unloaded_instant():
    y = np.array([10e3, 20e3, 0.0, 30e3, 10e3])
    q = np.array([50e3, 60e3, 0.0, 70e3, 40e3])  # the wheel lifts for one sample
    expected = [(10e3 + 20e3 + 0.0) / (50e3 + 60e3 + 0.0), (20e3 + 0.0 + 30e3) / 130e3,
                (0.0 + 30e3 + 10e3) / 110e3]
    assert np.allclose(sliding_ratio(y, q, 3), expected, rtol=1e-14)
    assert np.isnan(sliding_ratio(y, np.full(5, 500.0), 3)).all()  # mean Q under 1 kN


def test_prudhomme_limit_of_a_110_kN_axle():
    # alpha (10 kN + P/3): 110 kN static wheelset load -> 46.67 kN
    assert prudhomme_limit(110e3) == pytest.approx(10e3 + 110e3 / 3.0)
    assert prudhomme_limit(110e3, "freight") == pytest.approx(0.85 * (10e3 + 110e3 / 3.0))


def _wheels(**fields):
    return SimpleNamespace(wheels=SimpleNamespace(**fields))


def test_track_shifting_force_points_outward_for_a_flanging_outer_wheel():
    # Left curve: the rails push the wheelset to the left (inward), 20 kN on the flanging
    # right wheel and 3 kN on the left one. In lateral_force convention (towards the
    # wheel's own field side) that is +3 kN on the left wheel, -20 kN on the right one.
    result = _wheels(lateral_force=np.array([[[3e3, -20e3]]]),
                     vertical_force=np.array([[[60e3, 80e3]]]))
    assert track_shifting_force(result)[0, 0] == pytest.approx(-23e3)  # track pushed right


def test_wear_number_sums_active_patches_only():
    shape = (1, 1, 2, 3)
    active = np.zeros(shape, bool)
    active[0, 0, 1, :2] = True
    fx = np.full(shape, 1e3)
    fy = np.full(shape, -2e3)
    gx = np.full(shape, 1e-3)
    gy = np.full(shape, 2e-3)
    result = _wheels(active=active, creep_force_x=fx, creep_force_y=fy, creepage_x=gx,
                     creepage_y=gy)
    t_gamma = wear_number(result)
    assert t_gamma[0, 0, 0] == 0.0
    assert t_gamma[0, 0, 1] == pytest.approx(2 * (1.0 + 4.0))  # two patches x 5 N


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_table_files_read_back_equal(tmp_path, suffix):
    table = {"sample": np.arange(3), "speed": np.array([10.0, 12.5, 1.0 / 3.0]),
             "max_Y_over_Q_1": np.array([0.3, np.nan, 0.7]),
             "status": np.array(["successful", "derailed", "successful"])}
    path = tmp_path / f"table{suffix}"
    write_table(path, table)
    back = read_table(path)
    assert list(back) == list(table)
    assert np.array_equal(back["speed"], table["speed"])
    assert np.array_equal(back["max_Y_over_Q_1"], table["max_Y_over_Q_1"], equal_nan=True)
    assert list(back["status"]) == list(table["status"])
    assert list(back["sample"]) == [0, 1, 2]


def test_bad_tables_and_suffixes_are_named_and_nothing_is_written(tmp_path):
    with pytest.raises(ValueError, match="suffix must be one of"):
        write_table(tmp_path / "t.xlsx", {"a": np.ones(2)})
    with pytest.raises(ValueError, match="differ in length"):
        write_table(tmp_path / "t.csv", {"a": np.ones(2), "b": np.ones(3)})
    assert list(tmp_path.iterdir()) == []
