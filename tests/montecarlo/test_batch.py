"""A vmapped batch equals the same samples run one by one, a derailing sample
included; sharded over 2 forced host devices equals unsharded; chunks are padded and
cut back.

A single wheelset on straight track (the cheapest vehicle to compile) for 0.1 s, four
samples: three ordinary ones and one shifted 50 mm, beyond the 35 mm derailment limit,
which must stop alone with status "derailed".
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from jaxrail._devices import host_device_environment
from jaxrail.montecarlo import run_samples
from jaxrail.results import summarize
from jaxrail.scenarios import parse_scenario
from jaxrail.simulation import solve

SCENARIO = (Path(__file__).parents[1] / "data" / "wheelset-straight.toml").read_text()
SAMPLES = {"speed": [5.0, 10.0, 15.0, 12.0], "misalignment": [1e-3, 2e-3, 0.05, 3e-3],
           "friction": [0.3, 0.4, 0.4, 0.5]}


@pytest.fixture(scope="module")
def batch():
    scenario = parse_scenario(SCENARIO)
    built = scenario.build()
    samples = {k: np.array(v) for k, v in SAMPLES.items()}
    return scenario, built, run_samples(scenario, samples, chunk=4, keep_results=True,
                                        built=built)


def test_batch_equals_the_samples_run_one_by_one(batch):
    """Each sample alone: the unbatched ``solve`` (what ``simulate`` runs), compiled once
    with the parameters as an argument."""
    import jax

    from jaxrail.vehicles.parameters import set_values

    scenario, (vehicle, params, track), mc = batch
    assert list(mc.table["status"]) == ["successful", "successful", "derailed", "successful"]
    alone = jax.jit(lambda p, v, m: solve(vehicle, p, track, 0.1, v, m,
                                          options=scenario.solver_options()))
    for i in range(4):
        p = set_values(vehicle, params, ("friction",), np.array([SAMPLES["friction"][i]]))
        one = alone(p, SAMPLES["speed"][i], SAMPLES["misalignment"][i])
        batched = mc.results.wheelset_lateral[i]
        single = np.asarray(one.wheelset_lateral)
        assert np.array_equal(np.isnan(batched), np.isnan(single))
        assert one.status == mc.table["status"][i]
        if one.status == "successful":
            # same steps: the members keep their own step-size controllers
            assert int(one.steps) == mc.table["steps"][i]
            assert np.max(np.abs(batched - single)) < 1e-9  # [m]
            summary = summarize(one, friction=SAMPLES["friction"][i])
            assert mc.table["max_lateral_displacement_1_m"][i] == pytest.approx(
                summary["wheelsets"][0]["max_lateral_displacement_m"], rel=1e-6)
            assert mc.table["max_Y_over_Q_1"][i] == pytest.approx(
                max(w["max_Y_over_Q"] for w in summary["wheels"]), rel=1e-6)
            # Y/Q over 2 m (ratio of the 2 m means), by a loop over both wheels' windows
            y = -np.asarray(one.wheels.lateral_force)[:, 0, :]
            q = np.asarray(one.wheels.vertical_force)[:, 0, :]
            dt = float(one.t[1] - one.t[0])
            w = min(len(y), int(round(2.0 / (SAMPLES["speed"][i] * dt))))
            ratios = [np.mean(y[j:j + w, side]) / np.mean(q[j:j + w, side])
                      for side in range(2) for j in range(len(y) - w + 1)]
            # (the table's running sums round differently from the loop's means)
            assert mc.table["max_Y_over_Q_mean_1"][i] == pytest.approx(max(ratios), rel=1e-7)
        else:
            assert mc.table["simulated_time_s"][i] == 0.0
    # the derailed sample left the others' outputs complete
    assert np.all(np.isfinite(mc.results.wheelset_lateral[[0, 1, 3]]))


def test_sharded_over_two_host_devices_equals_unsharded(batch, tmp_path):
    _, _, mc = batch
    out = tmp_path / "sharded.json"
    script = textwrap.dedent(f"""
        import json, sys
        import numpy as np
        import jax
        from jaxrail import enable_float64
        enable_float64()
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from test_batch import SCENARIO, SAMPLES
        from jaxrail.montecarlo import run_samples
        from jaxrail.scenarios import parse_scenario
        assert len(jax.devices()) == 2, jax.devices()
        samples = {{k: np.array(v + [v[1]]) for k, v in SAMPLES.items()}}  # 5: padded chunk
        mc = run_samples(parse_scenario(SCENARIO), samples, chunk=4, keep_results=True)
        json.dump({{"devices": mc.devices, "chunk": mc.chunk,
                   "status": [str(s) for s in mc.table["status"]],
                   "lateral": np.nan_to_num(mc.results.wheelset_lateral, nan=99.0).tolist()}},
                  open({str(out)!r}, "w"))
    """)
    env = dict(os.environ)
    env.update(host_device_environment(2, env))
    subprocess.run([sys.executable, "-c", script], env=env, check=True, timeout=1500)
    sharded = json.loads(out.read_text())
    assert sharded["devices"] == 2 and sharded["chunk"] == 4
    assert sharded["status"] == list(mc.table["status"]) + ["successful"]
    lateral = np.array(sharded["lateral"])
    expected = np.nan_to_num(mc.results.wheelset_lateral, nan=99.0)
    assert np.max(np.abs(lateral[:4] - expected)) < 1e-12
    assert np.max(np.abs(lateral[4] - expected[1])) < 1e-12  # the repeated sample


def test_command_writes_the_table_and_figures(batch, tmp_path):
    """`jaxrail montecarlo` end to end, in this process: the batched program of the
    fixture (same vehicle structure, inputs and chunk) is reused, not compiled again."""
    from jaxrail.cli import main
    from jaxrail.montecarlo import read_table

    scenario = tmp_path / "wheelset.toml"
    scenario.write_text(SCENARIO)
    out = tmp_path / "mc"
    code = main(["montecarlo", str(scenario), "--samples", "4", "--chunk", "4", "--seed", "7",
                 "--vary", "speed=8:12", "--vary", "misalignment=0:3e-3",
                 "--vary", "friction=0.3:0.5", "--out", str(out / "table.csv"),
                 "--out", str(out / "table.parquet"), "--plots", str(out),
                 "--summary", str(out / "stats.json"), "--quiet"])
    assert code == 0
    csv, parquet = read_table(out / "table.csv"), read_table(out / "table.parquet")
    assert list(csv["status"]) == ["successful"] * 4
    assert np.allclose(csv["speed"], parquet["speed"], rtol=0, atol=0)
    assert np.all((csv["speed"] >= 8) & (csv["speed"] <= 12))
    assert np.all(csv["max_lateral_displacement_1_m"] > 0)
    stats = json.loads((out / "stats.json").read_text())
    assert stats["statuses"] == {"successful": 4} and stats["compile_time_s"] == 0.0
    for figure in ("maps.png", "distributions.png"):
        assert (out / figure).stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (("--samples", "0"), "--samples must be >= 1"),
    (("--samples", "4", "--vary", "speed"), "expected NAME=lo:hi"),
    (("--samples", "4", "--vary", "sped=1:2"), "unknown inputs"),
    (("--samples", "4", "--out", "t.xlsx"), "suffix must be .csv or .parquet"),
    (("--samples", "4", "--host-devices", "0"), "need a count >= 1"),
])
def test_bad_arguments_are_named_before_compiling(args, message):
    done = subprocess.run([sys.executable, "-m", "jaxrail.cli", "montecarlo",
                           "bogie-curve-entry", *args], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert message in done.stderr
