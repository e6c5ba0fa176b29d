"""The study's statistics against a hand-made table: only successful samples and finite
values count, integer, string and index columns have none, a column with no value is
left out, and the run's facts come first in a fixed order."""

import numpy as np

from jaxrail.montecarlo import MonteCarlo, column_statistics, study_statistics, successful


def _table():
    return {
        "sample": np.arange(5.0),  # float, as read back from CSV: still no statistics
        "speed": np.array([10.0, 12.0, 14.0, 16.0, 18.0]),
        "status": np.array(["successful", "derailed", "successful", "failed", "successful"]),
        "steps": np.array([100, 50, 120, 7, 130]),  # integers: no statistics
        "max_Y_over_Q_1": np.array([0.25, 5.0, np.nan, 9.0, 0.75]),  # NaN left out
        "max_sum_Y_1_N": np.array([np.inf, 1.0, 3e4, 2.0, -np.inf]),  # infinities too
        "flange_contact_fraction_1_left": np.array([np.nan, 0.2, np.nan, 0.3, np.nan]),
    }


def test_successful_is_the_status_mask():
    assert successful(_table()).tolist() == [True, False, True, False, True]


def test_column_statistics_of_the_successful_finite_values():
    stats = column_statistics(_table())
    assert list(stats) == ["speed", "max_Y_over_Q_1", "max_sum_Y_1_N"]
    assert stats["speed"] == {"min": 10.0, "median": 14.0, "max": 18.0}
    assert stats["max_Y_over_Q_1"] == {"min": 0.25, "median": 0.5, "max": 0.75}
    assert stats["max_sum_Y_1_N"] == {"min": 3e4, "median": 3e4, "max": 3e4}
    assert list(stats["speed"]) == ["min", "median", "max"]
    assert all(type(v) is float for entry in stats.values() for v in entry.values())


def _result(table):
    return MonteCarlo(table, {}, compile_time_s=1.5, run_time_s=2.5, chunk=2, devices=1,
                      seed=7)


def test_study_statistics_gives_the_run_facts_then_the_columns():
    stats = study_statistics(_result(_table()), "wheelset-straight", 0.05)
    assert list(stats) == ["scenario", "samples", "seed", "duration_s", "statuses",
                           "compile_time_s", "run_time_s", "devices", "chunk",
                           "successful_samples"]
    assert {k: v for k, v in stats.items() if k != "successful_samples"} == {
        "scenario": "wheelset-straight", "samples": 5, "seed": 7, "duration_s": 0.05,
        "statuses": {"derailed": 1, "failed": 1, "successful": 3}, "compile_time_s": 1.5,
        "run_time_s": 2.5, "devices": 1, "chunk": 2}
    assert stats["successful_samples"] == column_statistics(_table())


def test_without_a_successful_sample_there_are_no_column_statistics():
    table = {"sample": np.arange(2), "speed": np.array([10.0, 12.0]),
             "status": np.array(["failed", "derailed"])}
    assert column_statistics(table) == {}
    stats = study_statistics(_result(table), "s", 0.1)
    assert "successful_samples" not in stats
    assert stats["statuses"] == {"derailed": 1, "failed": 1}
