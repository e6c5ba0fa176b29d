"""The progress bar of simulated seconds (jaxrail._progress) on a small diffrax solve."""

import diffrax
import jax.numpy as jnp

from jaxrail._progress import SimulatedTimeProgress


def test_bar_counts_simulated_seconds_and_shows_the_real_time_factor(capfd):
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(lambda t, y, args: -y), diffrax.Tsit5(), 0.0, 2.0, 0.01, jnp.ones(()),
        stepsize_controller=diffrax.ConstantStepSize(),
        progress_meter=SimulatedTimeProgress(refresh_steps=10, duration=2.0))
    assert abs(float(solution.ys[-1]) - float(jnp.exp(-2.0))) < 1e-9
    shown = capfd.readouterr().err
    assert "x real time" in shown
    drawn = [float(part.split("/")[0]) for part in shown.split("\r")
             if part.strip().endswith("]") and "/2.00 s simulated" in part]
    assert len(drawn) >= 10 and drawn == sorted(drawn)  # every 10 steps of 0.01 s
    assert 1.85 < drawn[-1] <= 2.0
