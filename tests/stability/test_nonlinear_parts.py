"""The parts of the nonlinear critical speed methods that need no simulation, against
closed forms: the amplitude envelope and frequency of a synthetic oscillation, the
classification of its attractor, the speed drive's force law, and the bad inputs each
method names before compiling. (The methods themselves run in
benchmarks/nonlinear_critical_speed.py: minutes of simulation each.)"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.stability.nonlinear import (attractor, brute_force, driven_body, envelope,
                                         oscillation_frequency, ramp_down)
from jaxrail.track import straight_track
from jaxrail.vehicles.drive import SpeedDrive, check_drive
from jaxrail.vehicles.suspended_wheelset import suspended_wheelset

RATE = 400.0  # [1/s] samples


def _decaying(t, amplitude, frequency, decay, offset=0.0):
    return offset + amplitude * np.exp(-decay * t) * np.sin(2 * np.pi * frequency * t + 0.3)


def test_envelope_and_frequency_of_a_sine():
    t = np.arange(0.0, 4.0, 1.0 / RATE)
    y = _decaying(t, 3e-3, 7.3, 0.0, offset=1e-4)
    amplitude = envelope(t, y, window=0.5)
    # a full period in the window: the peak-to-peak of the samples, 50 per period
    assert np.allclose(amplitude[(t >= 0.25) & (t <= 3.75)], 3e-3, rtol=2e-3)
    assert abs(oscillation_frequency(t, y) / 7.3 - 1.0) < 1e-4


def test_envelope_follows_a_decay_and_the_attractor_is_named():
    t = np.arange(0.0, 6.0, 1.0 / RATE)
    y = _decaying(t, 4e-3, 8.0, 0.8)
    amplitude = envelope(t, y, window=0.5)
    # the centred window's largest value is the decay within half a window either side
    inside = (t >= 0.25) & (t <= 5.75)
    assert np.all(amplitude[inside] <= 4e-3 * np.exp(-0.8 * (t[inside] - 0.25)) * 1.0001)
    assert np.all(amplitude[inside] >= 4e-3 * np.exp(-0.8 * (t[inside] + 0.25)) * 0.99)
    died = attractor(t, y, window=0.5, threshold=1e-3)
    assert died["kind"] == "rest (centred running)" and died["amplitude_m"] < 1e-3
    alive = attractor(t, _decaying(t, 4e-3, 8.0, 0.0), window=0.5, threshold=1e-3)
    assert alive["kind"] == "hunting limit cycle"
    assert abs(alive["frequency_hz"] / 8.0 - 1.0) < 1e-3
    assert abs(alive["amplitude_m"] / 4e-3 - 1.0) < 2e-3


def test_the_drive_force_holds_then_ramps():
    drive = SpeedDrive(0, speed=90.0, mass=1.0e4, deceleration=1.5, hold=2.0,
                       time_constant=0.05)
    qdot = jnp.zeros(14).at[0].set(89.0)
    # holding: the feedback alone, 1 m/s slow -> M / tau forward
    assert float(drive.force(1.0, qdot)) == pytest.approx(1.0e4 / 0.05)
    # ramping at t = 4 s: reference 87 m/s, body 2 m/s fast, plus the feed-forward
    assert float(drive.reference_speed(4.0)) == pytest.approx(87.0)
    assert float(drive.force(4.0, qdot)) == pytest.approx(1.0e4 * (-1.5 - 2.0 / 0.05))
    forces = drive.add_to(4.0, qdot, jnp.ones((2, 3)))
    assert float(forces[0, 0]) == pytest.approx(1.0 + float(drive.force(4.0, qdot)))
    assert np.array_equal(np.asarray(forces[:, 1:]), np.ones((2, 2)))
    # traced, batched and differentiable in its numbers
    speeds = jnp.array([80.0, 90.0])
    batched = jax.vmap(lambda v: SpeedDrive(0, v, 1.0e4).force(0.0, qdot))(speeds)
    assert np.allclose(np.asarray(batched), 1.0e4 * (speeds - 89.0) / 0.05)
    slope = jax.grad(lambda v: SpeedDrive(0, v, 1.0e4).force(0.0, qdot))(90.0)
    assert float(slope) == pytest.approx(1.0e4 / 0.05)


def test_bad_inputs_are_named_before_compiling():
    vehicle, params = suspended_wheelset()
    track = straight_track(100.0)
    assert vehicle.system.body_names[driven_body(vehicle)] == "frame"
    with pytest.raises(ValueError, match="body 5 is not one of the system's 3 bodies"):
        check_drive(SpeedDrive(5, 80.0, 1.0e4), vehicle.system.n_bodies)
    with pytest.raises(ValueError, match="time_constant must be positive"):
        check_drive(SpeedDrive(0, 80.0, 1.0e4, time_constant=0.0), 3)
    with pytest.raises(ValueError, match="speed must be finite"):
        check_drive(SpeedDrive(0, float("nan"), 1.0e4), 3)
    with pytest.raises(ValueError, match="ramp-down: need 0 < low < high"):
        ramp_down(vehicle, params, track, 70.0, 90.0)
    with pytest.raises(ValueError, match="rate, hold, window and threshold must be > 0"):
        ramp_down(vehicle, params, track, 90.0, 70.0, rate=0.0)
    with pytest.raises(ValueError, match="brute force: need 0 < low < high"):
        brute_force(vehicle, params, track, 90.0, 90.0)
    with pytest.raises(ValueError, match="at least 2 runs per batch"):
        brute_force(vehicle, params, track, 70.0, 90.0, runs_per_batch=1)


def test_a_state_moved_to_another_speed_keeps_its_creepages():
    """Each body's velocity along x changes by the speed difference, the wheelset's spin
    about its (yawed, rolled) axle by the difference over the nominal radius; nothing
    else moves."""
    from jaxrail.multibody import quaternion as qt
    from jaxrail.stability.nonlinear import state_at_speed

    vehicle, params = suspended_wheelset()
    n = vehicle.system.n_bodies
    rng = np.random.default_rng(3)
    p = [qt.normalize(jnp.array([1.0, *rng.normal(0.0, 0.02, 3)])) for _ in range(n)]
    q = jnp.concatenate([jnp.concatenate([jnp.array(rng.normal(size=3)), x]) for x in p])
    omega = rng.normal(size=(n, 3))
    qdot = jnp.concatenate([jnp.concatenate([jnp.array(rng.normal(size=3)),
                                             qt.pdot_from_omega_global(x, w)])
                            for x, w in zip(p, omega)])
    moved_q, moved = state_at_speed(vehicle, params, q, qdot, 80.0, 72.5)
    assert np.array_equal(np.asarray(moved_q), np.asarray(q))
    before, after = np.asarray(qdot).reshape(n, 7), np.asarray(moved).reshape(n, 7)
    np.testing.assert_allclose(after[:, 0] - before[:, 0], -7.5, rtol=1e-12)
    np.testing.assert_array_equal(after[:, 1:3], before[:, 1:3])
    r0 = float(params.wheel.nominal_radius)
    for k in range(n):
        spin = 2.0 * np.asarray(qt.e_matrix(p[k])) @ after[k, 3:]
        axle = np.asarray(qt.rotation_matrix(p[k]))[:, 1]
        change = -7.5 / r0 * axle if k in vehicle.wheelsets else np.zeros(3)
        np.testing.assert_allclose(spin - omega[k], change, atol=1e-10)


def _thin_basin(monkeypatch, fold, reach, period=0.1):
    """Brute force's runs replaced by a model of a thin basin: from a start on the cycle
    at speed S a run at v hunts when v >= fold + reach (S - v) (the closer the start,
    the nearer the true ``fold``); returns the speeds and starts it was asked for."""
    from jaxrail.stability import nonlinear

    asked = []
    n_state = 21  # the suspended wheelset: 3 bodies

    def cycle(vehicle, params, track, speed, *args):
        return (jnp.zeros(n_state), jnp.zeros(n_state),
                {"kind": "hunting limit cycle", "amplitude_m": 6e-3, "frequency_hz": 10.0})

    def run(vehicle, params, track, speeds, duration, disturbance, mass, start, **static):
        speeds, s = np.asarray(speeds), float(start[2])
        asked.append((s, speeds.tolist()))
        t = np.linspace(0.0, float(duration), static["options"].n_outputs)
        hunts = speeds >= fold + reach * (s - speeds)
        y = np.where(hunts[:, None], 6e-3, 1e-9) * np.sin(2 * np.pi * t / period)[None, :]
        b = len(speeds)
        return (y[:, :, None], speeds[:, None] + 0.0 * t[None, :], np.zeros(b, bool),
                np.ones(b, bool), np.ones((b, n_state)), np.ones((b, n_state)))

    monkeypatch.setattr(nonlinear, "limit_cycle", cycle)
    monkeypatch.setattr(nonlinear, "compile_program", lambda f, *a, **k: (run, 0.0))
    return asked


@pytest.mark.parametrize("reach", [0.0, 0.3, 1.0])
def test_brute_force_brackets_the_fold_from_ever_closer_starts(monkeypatch, reach):
    """Without the basin's effect (reach 0) the bracket holds the fold at once; with it
    the starts move down the cycle until the bracket holds it, the lower end that died
    from a far start tested again from a closer one (reach 1 hunts it then)."""
    asked = _thin_basin(monkeypatch, fold=73.7, reach=reach)
    vehicle, params = suspended_wheelset()
    study = brute_force(vehicle, params, straight_track(100.0), 65.0, 95.0, resolution=0.5,
                        duration=2.0)
    assert study["status"] == "found"
    low, high = study["bracket_m_s"]
    assert high - low <= 0.5
    # the bracket's bottom died and its top hunted from the start each was last run from
    last_start = {v: s for s, speeds in asked for v in speeds}
    assert low < 73.7 + reach * (last_start[low] - low)
    assert high >= 73.7 + reach * (last_start[high] - high)
    # below the fold every run dies, whatever its start: never more than the resolution low
    assert study["critical_speed_m_s"] > 73.7 - 0.25
    if reach == 0.0:
        assert low <= 73.7 <= high
    starts = [s for s, _ in asked]
    assert starts[0] == 95.0 and starts == sorted(starts, reverse=True)
    rows = [r for r in study["runs"] if r["hunting"]]
    assert all(r["attractor"]["kind"] == "hunting limit cycle" for r in rows)
