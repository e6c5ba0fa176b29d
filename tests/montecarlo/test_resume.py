"""Monte Carlo over irregularity realisations, and a study that resumes: a study that
dies after its first chunk is written leaves a checkpoint; the same command then
finishes, and its table equals that of an uninterrupted run. A different study refuses
the checkpoint unless asked to overwrite it.

A single wheelset for 0.1 s on straight track with German-high irregularities, the
seed and the amplitude scale drawn."""

import json

import numpy as np
import pytest

from jaxrail.montecarlo import read_table
from jaxrail.montecarlo import checkpoint as checkpoints
from jaxrail.montecarlo import coordination
from jaxrail.montecarlo.checkpoint import Checkpoint, shared_rows

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
spectrum = "german-high"
seed = 1
[run]
speed = 10.0
misalignment = 0.0
duration = 0.1
[solver]
rtol = 1e-4
atol = 1e-7
output_rate = 100.0
"""


def _command(scenario, out, *extra):
    return ["montecarlo", str(scenario), "--samples", "4", "--chunk", "2", "--seed", "3",
            "--vary", "irregularity_seed=0:1000", "--vary", "irregularity_scale=0.5:1.5",
            "--out", str(out), "--quiet", *extra]


class Killed(BaseException):
    """The process dies (no handler of the command's catches it)."""


def test_a_killed_study_resumes_to_the_uninterrupted_table(tmp_path, monkeypatch, capsys):
    """The study dies right after its first chunk's checkpoint is written (the moment a
    kill leaves behind: the file is written whole, then nothing more happens); the same
    command then finishes from it. One process, so the three runs share one compiled
    program."""
    from jaxrail.cli import main

    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO)
    whole = tmp_path / "whole.csv"
    assert main(_command(scenario, whole)) == 0
    assert not (tmp_path / "whole.csv.chunks.json").exists()  # removed once written
    table = read_table(whole)
    assert list(table["status"]) == ["successful"] * 4
    seeds = np.asarray(table["irregularity_seed"])
    assert np.all(seeds == np.floor(seeds)) and len(set(seeds)) == 4
    assert np.all((table["irregularity_scale"] >= 0.5) & (table["irregularity_scale"] <= 1.5))
    # every realisation runs its own way
    assert len(set(np.round(table["max_lateral_displacement_1_m"], 9))) == 4

    out = tmp_path / "resumed.csv"
    checkpoint = tmp_path / "resumed.csv.chunks.json"
    write = Checkpoint.add

    def add_then_die(self, rows):
        write(self, rows)
        raise Killed

    monkeypatch.setattr(Checkpoint, "add", add_then_die)
    with pytest.raises(Killed):
        main(_command(scenario, out))
    monkeypatch.setattr(Checkpoint, "add", write)
    assert checkpoint.exists() and not out.exists()
    rows = json.loads(checkpoint.read_text())["rows"]
    assert list(rows) == ["0", "1"]  # the first chunk's two samples, and only they
    capsys.readouterr()

    assert main(_command(scenario, out)) == 0
    assert "resuming from the finished chunks" in capsys.readouterr().err
    first, second = read_table(whole), read_table(out)
    assert list(first) == list(second)
    for key in first:
        if np.asarray(first[key]).dtype.kind == "f":
            np.testing.assert_array_equal(first[key], second[key])
        else:
            assert list(first[key]) == list(second[key])
    assert not checkpoint.exists()


def test_another_study_refuses_the_checkpoint_unless_overwritten(tmp_path):
    path = tmp_path / "t.csv.chunks.json"
    saved = Checkpoint.open(path, "study-a", 4)
    saved.add({0: {"status": "successful", "max_normal_force_N": 1.5e4, "steps": 12,
                   "simulated_time_s": float("nan")}})
    again = Checkpoint.open(path, "study-a", 4)
    assert again.rows[0]["steps"] == 12 and np.isnan(again.rows[0]["simulated_time_s"])
    with pytest.raises(ValueError, match="another study.*--overwrite"):
        Checkpoint.open(path, "study-b", 4)
    assert Checkpoint.open(path, "study-b", 4, overwrite=True).rows == {}
    path.write_text("not json")
    with pytest.raises(ValueError, match="not a jaxrail Monte Carlo checkpoint"):
        Checkpoint.open(path, "study-a", 4)


class KeyValueStore:
    """A stand-in for the coordination service's key-value store: a dict; a key read
    before it is set is an error (the real store would wait for it)."""

    def __init__(self):
        self.values = {}

    def key_value_set(self, key, value, allow_overwrite=False):
        assert allow_overwrite or key not in self.values, f"{key} set twice"
        self.values[key] = value

    def blocking_key_value_get(self, key, timeout_in_ms):
        return self.values[key]


def test_process_0s_finished_rows_reach_every_process(monkeypatch):
    """On several processes only process 0 opens the checkpoint; the others receive its
    rows (in pieces, here of 100 characters), NaN and text included, so that all skip
    the same chunks; a second share uses keys of its own."""
    monkeypatch.setattr(checkpoints, "PIECE_CHARACTERS", 100)
    store = KeyValueStore()
    rows = {i: {"status": "successful", "steps": 10 + i, "max_normal_force_N": 1.5e4 + i,
                "simulated_time_s": float("nan")} for i in (0, 1, 5)}
    # the same call on each process: each draws the next share's number
    monkeypatch.setattr(coordination, "_calls", iter([7, 7]))
    assert shared_rows(rows, store, process=0) is rows
    received = shared_rows({}, store, process=1)
    assert int(store.values["jaxrail/montecarlo/rows/7/pieces"]) > 2
    assert sorted(received) == [0, 1, 5]
    for i in rows:
        assert received[i]["status"] == "successful" and received[i]["steps"] == 10 + i
        assert received[i]["max_normal_force_N"] == 1.5e4 + i
        assert np.isnan(received[i]["simulated_time_s"])
    monkeypatch.setattr(coordination, "_calls", iter([8, 8]))
    shared_rows({}, store, process=0)
    assert shared_rows({}, store, process=1) == {}


@pytest.mark.parametrize("vary, message", [
    ("irregularity_scale=-1:1", "irregularity_scale"),
    ("irregularity_seed=-5:3", "irregularity_seed"),
])
def test_bad_irregularity_draws_are_named(tmp_path, vary, message, capsys):
    from jaxrail.cli import main

    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO)
    assert main(["montecarlo", str(scenario), "--samples", "2", "--vary", vary]) == 2
    assert message in capsys.readouterr().err


def test_varying_the_seed_of_a_track_without_irregularities_is_refused(tmp_path, capsys):
    from jaxrail.cli import main

    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO.replace('[irregularities]\nspectrum = "german-high"\nseed = 1\n',
                                         ""))
    assert main(["montecarlo", str(scenario), "--samples", "2",
                 "--vary", "irregularity_seed=0:9"]) == 2
    assert "has no [irregularities] to vary" in capsys.readouterr().err


def test_a_study_whose_fastest_sample_outruns_the_file_is_refused(tmp_path, capsys):
    from jaxrail.cli import main

    csv = tmp_path / "short.csv"
    assert main(["track", "irregularities", "--spectrum", "german-low", "--length", "8",
                 "--csv", str(csv)]) == 0
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO.replace('spectrum = "german-high"\nseed = 1',
                                         f'file = "{csv}"').replace("duration = 0.1",
                                                                    "duration = 0.2"))
    # at 10 m/s the run reaches 7 m; at 20 m/s 9 m, past the file's 8 m
    assert main(["montecarlo", str(scenario), "--samples", "2", "--vary", "speed=10:20",
                 "--design", "grid"]) == 2
    assert "covers s = 0 to 8 m but the run's wheelsets go from 5.0 to 9.0 m" in (
        capsys.readouterr().err)
