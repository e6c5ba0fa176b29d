"""Figures of a Monte Carlo table: the worst-wheel reduction against a hand
computation; maps and distributions are written for a synthetic table with a
derailed sample and NaN values in it."""

import numpy as np
import pytest

from jaxrail.plots.montecarlo import plot_distributions, plot_maps, worst


def synthetic_table(n=40, seed=0):
    rng = np.random.default_rng(seed)
    speed = rng.uniform(10, 25, n)
    shift = rng.uniform(0, 5e-3, n)
    status = np.array(["successful"] * n, dtype=object)
    status[3] = "derailed"
    table = {"sample": np.arange(n), "speed": speed, "misalignment": shift,
             "status": status.astype(str), "nadal_limit": np.full(n, 1.118),
             "max_normal_force_N": 6e4 + 1e3 * speed}
    for k in (1, 2):
        table[f"max_lateral_displacement_{k}_m"] = shift * (1.0 + 0.1 * k) + 1e-4 * speed
        table[f"max_Y_over_Q_{k}"] = 0.02 * speed / k
        table[f"max_Y_over_Q_mean_{k}"] = 0.015 * speed / k
        table[f"max_sum_Y_{k}_N"] = 1e3 * speed / k
        table[f"prudhomme_limit_{k}_N"] = np.full(n, 46e3)
        for side in ("left", "right"):
            table[f"flange_contact_fraction_{k}_{side}"] = np.clip((speed - 15) / 10, 0, 1)
            table[f"wear_number_{k}_{side}_N"] = 5.0 * speed
    for name in table:
        if name.startswith("max_") and name != "max_normal_force_N":
            table[name] = np.where(status == "derailed", np.nan, table[name])
    return table


def test_worst_takes_the_largest_column_and_divides_by_its_own_limit():
    table = {"a_1": np.array([1.0, np.nan, 2.0]), "a_2": np.array([3.0, np.nan, 1.0]),
             "lim_1": np.array([1.0, 1.0, 1.0]), "lim_2": np.array([6.0, 1.0, 1.0]),
             "a_b": np.array([9.0, 9.0, 9.0])}  # not a wheelset column
    assert np.array_equal(worst(table, "a_"), [3.0, np.nan, 2.0], equal_nan=True)
    assert np.array_equal(worst(table, "a_", "lim_"), [1.0, np.nan, 2.0], equal_nan=True)
    with pytest.raises(ValueError, match="no columns"):
        worst(table, "b_")


def test_maps_and_distributions_are_written(tmp_path):
    table = synthetic_table()
    plot_maps(table, tmp_path / "maps.png")
    plot_distributions(table, tmp_path / "distributions.png")
    assert (tmp_path / "maps.png").stat().st_size > 30_000
    assert (tmp_path / "distributions.png").stat().st_size > 20_000
