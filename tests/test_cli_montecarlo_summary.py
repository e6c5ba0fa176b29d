"""The JSON statistics of ``jaxrail montecarlo`` (``--summary``), key for key, with the
study replaced by a hand-made result so that nothing compiles."""

import json
from pathlib import Path

import numpy as np

import jaxrail.montecarlo
from jaxrail.cli import main
from jaxrail.montecarlo import MonteCarlo

SCENARIO = str(Path(__file__).parent / "data" / "wheelset-straight.toml")


def _table():
    return {"sample": np.arange(4), "speed": np.array([10.0, 12.0, 14.0, 16.0]),
            "misalignment": np.array([0.0, 1e-3, 2e-3, 3e-3]),
            "status": np.array(["successful", "derailed", "successful", "successful"]),
            "steps": np.array([100, 50, 120, 130]),  # integers: no statistics
            "max_Y_over_Q_1": np.array([0.25, 0.9, np.nan, 0.75]),
            "flange_contact_fraction_1_left": np.array([np.nan, 0.2, np.nan, np.nan])}


def test_the_printed_statistics_are_those_of_the_successful_samples(monkeypatch, tmp_path,
                                                                    capsys):
    calls = []

    def fake_run_montecarlo(scenario, variations, n, *, seed, **kwargs):
        calls.append((scenario.name, [v.name for v in variations], n, seed))
        return MonteCarlo(_table(), {}, compile_time_s=1.5, run_time_s=2.5, chunk=2,
                          devices=1, seed=seed)

    monkeypatch.setattr(jaxrail.montecarlo, "run_montecarlo", fake_run_montecarlo)
    summary = tmp_path / "stats.json"
    status = main(["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=10:16",
                   "--seed", "7", "--duration", "0.05", "--summary", str(summary),
                   "--quiet"])
    assert status == 1  # a sample derailed
    assert calls == [("wheelset-straight", ["speed"], 4, 7)]
    stats = json.loads(summary.read_text())
    assert list(stats) == ["scenario", "samples", "seed", "duration_s", "statuses",
                           "compile_time_s", "run_time_s", "devices", "chunk",
                           "successful_samples"]
    assert stats == {
        "scenario": "wheelset-straight", "samples": 4, "seed": 7, "duration_s": 0.05,
        "statuses": {"derailed": 1, "successful": 3}, "compile_time_s": 1.5,
        "run_time_s": 2.5, "devices": 1, "chunk": 2,
        "successful_samples": {
            "speed": {"min": 10.0, "median": 14.0, "max": 16.0},
            "misalignment": {"min": 0.0, "median": 2e-3, "max": 3e-3},
            "max_Y_over_Q_1": {"min": 0.25, "median": 0.5, "max": 0.75}}}
    assert list(stats["successful_samples"]["speed"]) == ["min", "median", "max"]
    assert "wrote" in capsys.readouterr().err
