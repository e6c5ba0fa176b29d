"""A run with the progress bar is the run without it, bit for bit (one program, its
loop reporting the simulated time through jaxrail's FFI target), the bar shows the
simulated seconds as the run goes, and the run's programs go into the persistent
caches: traced programs (jaxrail.compilation.programs) and XLA's."""

import json
import os
import subprocess
import sys

import diffrax
import equinox as eqx
import jax
import numpy as np
import pytest

from jaxrail.profiles.analytic import conical_wheel
from jaxrail.track import straight_track
from jaxrail.simulation import simulate_single_wheelset

T1 = 0.5


def _run(progress, lateral=2e-3):
    return simulate_single_wheelset(conical_wheel(0.05), straight_track(30.0), 5.0, lateral,
                                    T1, n_outputs=101, progress=progress)[0]


@pytest.fixture(scope="module")
def runs():
    return _run(False), _run(True)


def test_the_bar_changes_nothing_to_the_last_bit(runs):
    quiet, shown = runs
    assert quiet.status == shown.status == "successful"
    assert float(shown.compile_time_s) == 0.0  # the quiet run's program, not another
    quiet_leaves, shown_leaves = (jax.tree_util.tree_flatten_with_path(r)[0] for r in runs)
    compared = 0
    for (path, a), (_, b) in zip(quiet_leaves, shown_leaves, strict=True):
        name = jax.tree_util.keystr(path)
        if name not in (".wall_time_s", ".compile_time_s"):
            assert np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True), name
            compared += 1
    assert compared >= 20  # states, outputs, every wheel field, counters
    assert int(shown.accepted_steps) == int(quiet.accepted_steps) > 0


def test_a_derailment_stops_the_run_with_the_bar_and_keeps_the_start():
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
    # the run (the rest pose is a jitted function: in XLA's cache only)
    assert len(os.listdir(tmp_path / "programs")) == 1
    assert len(os.listdir(tmp_path / "xla")) >= 1
    assert runs[0]["hits"] == 0 and runs[1]["hits"] >= 1
    assert runs[1]["lateral"] == runs[0]["lateral"]


def test_a_singular_implicit_solve_is_named_in_the_status(runs):
    """IMEX ends a run whose step matrix is singular with diffrax's ``singular`` result
    (tests/multibody/test_imex.py); the status names it."""
    failed = eqx.tree_at(lambda r: r.result, runs[0], diffrax.RESULTS.singular)
    assert failed.status == "failed: singular implicit solve"
