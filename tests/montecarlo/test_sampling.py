"""Sampling designs: reproducible from the seed, Latin hypercube strata filled once
each, normal draws with the right moments, grids from lo to hi, bad specs named."""

import numpy as np
import pytest

from jaxrail.vehicles.parameters import PARAMETERS
from jaxrail.montecarlo import Variation, draw, parse_variation
from jaxrail.montecarlo.sampling import check_names


def test_parse_the_three_spreads():
    assert parse_variation("speed=10:25") == Variation("speed", "uniform", (10.0, 25.0))
    assert parse_variation("friction=normal:0.4,0.05") == Variation("friction", "normal",
                                                                    (0.4, 0.05))
    assert parse_variation("misalignment=0,1e-3,2e-3").values == (0.0, 1e-3, 2e-3)


@pytest.mark.parametrize("text, message", [
    ("speed", "expected NAME=lo:hi"), ("speed=25:10", "lo <= hi"),
    ("speed=a:b", "could not convert"), ("friction=normal:0.4,-1", "sd >= 0"),
    ("speed=1:nan", "finite")])
def test_bad_spreads_are_named(text, message):
    with pytest.raises(ValueError, match=message):
        parse_variation(text)


def test_unknown_and_repeated_inputs_are_named():
    with pytest.raises(ValueError, match="unknown inputs \\['sped'\\]"):
        check_names([parse_variation("sped=1:2").name], PARAMETERS)
    with pytest.raises(ValueError, match="each input once"):
        check_names(["speed", "speed"], PARAMETERS)


def test_latin_hypercube_fills_each_stratum_once_and_is_reproducible():
    variations = [parse_variation("speed=10:25"), parse_variation("misalignment=0:5e-3")]
    a = draw(variations, 50, seed=3)
    b = draw(variations, 50, seed=3)
    c = draw(variations, 50, seed=4)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not np.array_equal(a["speed"], c["speed"])
    for name, (lo, hi) in (("speed", (10.0, 25.0)), ("misalignment", (0.0, 5e-3))):
        strata = np.floor((a[name] - lo) / (hi - lo) * 50).astype(int)
        assert sorted(strata) == list(range(50))
    assert abs(np.corrcoef(a["speed"], a["misalignment"])[0, 1]) < 0.4


def test_random_normal_draws_have_the_given_moments():
    x = draw([parse_variation("friction=normal:0.4,0.05")], 4000, seed=1, design="random")
    assert abs(np.mean(x["friction"]) - 0.4) < 3 * 0.05 / np.sqrt(4000)
    assert abs(np.std(x["friction"]) / 0.05 - 1.0) < 0.05


def test_grid_is_the_full_factorial_from_lo_to_hi():
    g = draw([parse_variation("speed=10:20"), parse_variation("friction=0.3,0.4")], 9,
             design="grid")
    assert len(g["speed"]) == 3 * 2
    assert sorted(set(g["speed"])) == [10.0, 15.0, 20.0]
    assert sorted(set(g["friction"])) == [0.3, 0.4]


def test_choices_are_drawn_evenly():
    x = draw([parse_variation("friction=0.2,0.3,0.4")], 300, seed=0)
    values, counts = np.unique(x["friction"], return_counts=True)
    assert list(values) == [0.2, 0.3, 0.4] and list(counts) == [100, 100, 100]
