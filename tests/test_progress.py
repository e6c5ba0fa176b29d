"""A run with the progress bar (integrated in segments, the bar drawn between them)
gives the one-piece run's answer, and its programs go into the persistent caches:
traced programs (jaxrail._program_cache) and XLA's."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from jaxrail.profiles import rail_offset, uic60
from jaxrail.profiles.analytic import conical_wheel
from jaxrail.track import straight_track
from jaxrail.vehicles import simulate_single_wheelset

T1 = 0.5


def _run(progress, lateral=2e-3):
    rail = uic60()
    return simulate_single_wheelset(conical_wheel(0.05), rail, straight_track(30.0),
                                    rail_offset(rail), 5.0, lateral, T1, n_outputs=101,
                                    progress=progress)[0]


@pytest.fixture(scope="module")
def runs():
    return _run(False), _run(True)


def test_segments_give_the_one_piece_answer(runs):
    whole, segmented = runs
    assert whole.status == segmented.status == "successful"
    np.testing.assert_allclose(segmented.t, whole.t, atol=1e-12)
    # rtol 1e-6: each segment restarts the step-size controller, nothing else changes
    np.testing.assert_allclose(segmented.wheelset_lateral, whole.wheelset_lateral, atol=1e-8)
    np.testing.assert_allclose(segmented.q, whole.q, atol=1e-7)
    assert abs(int(segmented.accepted_steps) / int(whole.accepted_steps) - 1.0) < 0.1


def test_a_derailment_stops_the_segments_and_keeps_the_start():
    result = _run(True, lateral=0.04)  # beyond the 35 mm limit: derailed at once
    assert result.status == "derailed"
    valid = np.asarray(result.valid)
    assert valid[0] and not valid[-1] and result.simulated_time_s < T1 / 2
    assert np.all(np.isnan(np.asarray(result.wheelset_lateral)[~valid]))


@pytest.mark.parametrize("progress", [False, True])
def test_a_non_finite_state_fails_rather_than_derails(progress):
    result = _run(progress, lateral=float("nan"))
    assert result.status == "failed" and not bool(result.derailed)
    assert result.simulated_time_s == 0.0


def test_bar_counts_simulated_seconds_and_shows_the_real_time_factor(capfd):
    _run(True)
    shown = capfd.readouterr().err
    drawn = [float(part.split("/")[0]) for part in shown.split("\r")
             if part.strip().endswith("]") and f"/{T1:.2f} s simulated" in part]
    assert "x real time" in shown
    assert len(drawn) >= 10 and drawn == sorted(drawn)
    assert drawn[-1] == pytest.approx(T1)


_CHILD = """
import json, jax
from jaxrail import enable_float64
enable_float64()
hits = []
jax.monitoring.register_event_listener(
    lambda name, **kw: hits.append(name) if name.endswith("cache_hits") else None)
from tests.test_progress import _run
result = _run(True)
print(json.dumps({"hits": len(hits), "status": result.status,
                  "lateral": result.wheelset_lateral[:, 0].tolist()}))
"""


def test_programs_go_into_the_persistent_compilation_cache(tmp_path):
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(tmp_path / "xla"),
               JAXRAIL_CACHE_DIR=str(tmp_path))
    env.pop("JAXRAIL_COMPILATION_CACHE", None)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    runs = [json.loads(subprocess.run([sys.executable, "-c", _CHILD], env=env, cwd=root,
                                      capture_output=True, text=True, check=True)
                       .stdout.splitlines()[-1]) for _ in range(2)]
    assert [r["status"] for r in runs] == ["successful", "successful"]
    assert len(os.listdir(tmp_path / "programs")) >= 3  # rest pose, segment, results
    assert len(os.listdir(tmp_path / "xla")) >= 1
    assert runs[0]["hits"] == 0 and runs[1]["hits"] >= 1
    assert runs[1]["lateral"] == runs[0]["lateral"]
