"""Identification of vehicle and contact parameters from measured time histories.

``identify(scenario, measurements, ["contact_stiffness", "friction"])`` simulates the
scenario with trial values of the named parameters
(:mod:`jaxrail.vehicles.parameters`), compares the measured channels
(:mod:`.measurements`) with the simulated ones, and fits the values
by weighted least squares with optax in bounded log space, gradients through the whole
simulation by AD (forward mode for up to ``FORWARD_MODE_PARAMETERS`` parameters, else
reverse mode with recursive checkpointing), closing with Gauss-Newton steps
(:mod:`.fit`). The uncertainty is the Gauss-Newton one at the optimum; per channel,
the same from that channel alone tells which measurement identifies which parameter.
"""

import dataclasses
import hashlib

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import compilation
from ..scenarios.checks import MAX_OUTPUTS
from ..simulation import SolverOptions, solve
from ..vehicles.parameters import (PARAMETERS, get_values, parameter, set_values,
                                   set_values_and_track)
from .fit import POLISH_ITERATIONS, FitResult, channel_standard_errors, least_squares
from .measurements import (Measurements, channel_values, check_channels,
                           gaussian_window, read_measurements, sample, write_measurements)

__all__ = ["FitResult", "Identification", "Measurements", "PARAMETERS", "channel_values",
           "get_values", "identify", "least_squares", "parameter", "read_measurements",
           "set_values", "set_values_and_track", "simulate_channels", "simulation_residuals",
           "write_measurements"]


# Simulation outputs per measurement sample period: the acquisition filter then sees a
# wheel-rail contact ringing (~100-300 Hz at 100 Hz sampling) as such.
OVERSAMPLING = 8
# Default low-pass cutoff of the acquisition, as a fraction of the sample rate: 20 Hz at
# 100 Hz, the wheel-rail force filter of EN 14363. The Gaussian filter passes 1.3 % at
# the Nyquist frequency and nothing measurable of the contact ringing.
CUTOFF_FRACTION = 0.2
# Fits of up to this many parameters take their gradients by forward mode (one product
# per parameter), more by one reverse pass (benchmarks/gradient.py).
FORWARD_MODE_PARAMETERS = 3


def _adjoint(options: SolverOptions, forward: bool, override=None):
    if forward:
        return diffrax.ForwardMode()
    if override is not None:
        return override
    if options.fixed_step is not None:
        # one checkpoint per step: no recomputation; memory ~ steps x solver state
        return diffrax.RecursiveCheckpointAdjoint(checkpoints=options.max_steps)
    return diffrax.RecursiveCheckpointAdjoint()


def sample_period(times) -> float:
    """Mean spacing [s] of the sample times (M,), M >= 2."""
    times = np.asarray(times, dtype=np.float64)
    return float(times[-1] - times[0]) / (len(times) - 1)


def output_count(times, duration) -> int:
    """The simulation's output times for samples at ``times`` (M,) [s] over ``duration``
    [s]: ``OVERSAMPLING`` per sample period; ValueError beyond
    :data:`jaxrail.scenarios.checks.MAX_OUTPUTS`."""
    period = sample_period(times)
    outputs = int(round(duration / period * OVERSAMPLING)) + 1
    if outputs > MAX_OUTPUTS:
        raise ValueError(f"measurements sampled every {period:g} s need {outputs} output times "
                         f"({OVERSAMPLING} per sample over {duration:g} s); at most "
                         f"{MAX_OUTPUTS}: resample them")
    return outputs


def simulate_channels(vehicle, params, track, channels, times, *, speed, misalignment,
                      duration, options: SolverOptions, s0=None, adjoint=None, cutoff=None,
                      contact_model=None):
    """Simulated channels (M, C) at ``times`` (M,) [s] as an acquisition sees them
    (traceable, differentiable): the simulation's outputs at ``OVERSAMPLING`` times the
    sample rate (more if ``options`` asks) through the Gaussian low-pass filter of
    :func:`.measurements.gaussian_window` with ``cutoff`` [Hz] (default
    ``CUTOFF_FRACTION`` times the sample rate, the inverse of the times' mean spacing).
    ``contact_model``: :mod:`jaxrail.vehicles.loads` (default the paper's search)."""
    period = sample_period(times)
    cutoff = CUTOFF_FRACTION / period if cutoff is None else cutoff
    options = dataclasses.replace(options, n_outputs=max(options.n_outputs,
                                                         output_count(times, duration)))
    result = solve(vehicle, params, track, duration, speed, misalignment, s0, options=options,
                   adjoint=adjoint, contact_model=contact_model)
    values = channel_values(channels, vehicle, params, track, result)
    return sample(result.t, values, jnp.asarray(times), gaussian_window(cutoff))


def simulation_residuals(vehicle, params, track, names, measurements: Measurements, *,
                         speed, misalignment, duration, options: SolverOptions, s0=None,
                         forward=False, adjoint=None, cutoff=None, contact_model=None):
    """``(values (k,), measured (M, C)) -> r (M C,)``: whitened residuals (simulated -
    measured) / noise, sample-major, of the simulation with the named parameters (the
    vehicle's and the track's) set to ``values``.
    ``forward``: use diffrax's forward-mode adjoint (for ``jax.jacfwd``) instead of
    recursive checkpointing (for ``jax.grad``; with fixed steps one checkpoint per step,
    else diffrax's default; ``adjoint`` overrides it). ``cutoff`` [Hz]: the
    acquisition's low-pass and ``contact_model`` the contact model
    (:func:`simulate_channels`). Samples after an early stop (derailed, failed) count as
    1e3 noise levels off."""
    check_channels(measurements.channels, vehicle)
    get_values(vehicle, params, names, track)  # raises if the vehicle lacks one
    if measurements.time[-1] > duration + 1e-12:
        raise ValueError(f"measurements reach {measurements.time[-1]} s, the simulation "
                         f"only {duration} s")
    output_count(measurements.time, duration)  # refuse too dense samples before tracing
    noise = jnp.asarray(measurements.noise)
    adjoint = _adjoint(options, forward, adjoint)

    def residuals(values, measured):
        trial, moved = set_values_and_track(vehicle, params, track, names, values)
        simulated = simulate_channels(vehicle, trial, moved, measurements.channels,
                                      measurements.time, speed=speed,
                                      misalignment=misalignment, duration=duration,
                                      options=options, s0=s0, adjoint=adjoint,
                                      cutoff=cutoff, contact_model=contact_model)
        finite = jnp.isfinite(simulated)
        r = (jnp.where(finite, simulated, 0.0) - measured) / noise
        return jnp.where(finite, r, 1e3).ravel()

    return residuals


@dataclasses.dataclass(frozen=True)
class Identification:
    """Outcome of :func:`identify`: ``fit`` (:class:`FitResult`), the ``measurements``,
    the channels ``simulated`` (M, C) with the fitted values, and
    ``channel_standard_errors``: {channel: (k,) standard errors from it alone}."""

    fit: FitResult
    measurements: Measurements
    simulated: np.ndarray
    channel_standard_errors: dict

    def as_dict(self) -> dict:
        out = self.fit.as_dict()
        out["channel_standard_errors"] = self.channel_standard_errors
        out["channels"] = list(self.measurements.channels)
        out["rms_residual_per_channel"] = dict(zip(self.measurements.channels, np.sqrt(
            np.mean(((self.simulated - self.measurements.values) / self.measurements.noise)
                    ** 2, axis=0)).tolist()))
        return out


def _content_key(tree) -> str:
    """SHA-256 of a pytree's content: its structure with every static value, and each
    array leaf's dtype, shape and bytes (a contact model and its table)."""
    leaves, treedef = jax.tree.flatten(tree)
    digest = hashlib.sha256(str(treedef).encode())
    for leaf in leaves:
        if eqx.is_array(leaf):
            leaf = np.asarray(leaf)
            digest.update(f"{leaf.dtype}{leaf.shape}".encode())
            digest.update(np.ascontiguousarray(leaf).tobytes())
        else:
            digest.update(repr(leaf).encode())
    return digest.hexdigest()


def _residual_functions(vehicle, params, track, names, measurements, common):
    """The reverse- and forward-mode residual functions, the same objects for the same
    model, names, sample times, channels and noise levels: the fits of one process
    (e.g. noise-free and noisy data of one study) then share their compiled programs
    (the measured values are an argument, not part of the function). They are kept in
    the process's program cache (:func:`jaxrail.compilation.kept`)."""
    key = ("identification.residuals", id(vehicle), id(params), id(track), names,
           measurements.channels, measurements.time.tobytes(), measurements.noise.tobytes(),
           tuple(sorted((k, v) for k, v in common.items() if k != "contact_model")),
           _content_key(common.get("contact_model")))

    def functions():
        made = tuple(simulation_residuals(vehicle, params, track, names, measurements,
                                          forward=forward, **common)
                     for forward in (False, True))
        # the model is kept with the functions so that its ids stay unique while cached
        return made, (vehicle, params, track)

    return compilation.kept(key, functions)[0]


def _checked_bounds(bounds, vehicle, params) -> dict:
    """User bounds {name: (lo, hi)}: within the parameter's range, 0 < lo < hi (the fit
    moves in log space)."""
    out = {}
    for name, pair in dict(bounds or {}).items():
        lo, hi = (parameter(name, vehicle, params).check(x, "bounds") for x in pair)
        if not 0.0 < lo < hi:
            raise ValueError(f"bounds: {name} needs 0 < lo < hi, got ({lo:g}, {hi:g})")
        out[name] = (lo, hi)
    return out


def identify(scenario, measurements: Measurements, names, initial=None, bounds=None,
             method="lbfgs", max_iterations=30, tolerance=1e-9, progress=False,
             built=None, cutoff=None, contact=None) -> Identification:
    """Fit the named parameters of ``scenario`` (:class:`jaxrail.scenarios.Scenario`)
    to ``measurements``.

    initial: {name: value} (default: the scenario's values); bounds: {name: (lo, hi)}
    (default a factor 10 either side of the initial value); method: "lbfgs" or "adam";
    cutoff: the low-pass cutoff [Hz] the measured channels were filtered with (default
    ``CUTOFF_FRACTION`` times their sample rate; :func:`simulate_channels`);
    progress: show a tqdm bar with the loss; built: ``(vehicle, params, track)`` if
    already built; contact: ``"online"`` or ``"table"`` (default the scenario's mode).
    """
    names = tuple(names)
    if not names or len(set(names)) != len(names):
        raise ValueError(f"give distinct parameter names to fit, got {names}")
    vehicle, params, track = scenario.build() if built is None else built
    current = np.asarray(get_values(vehicle, params, names, track))
    initial = dict(zip(names, current)) | dict(initial or {})
    unknown = set(initial) - set(names)
    if unknown:
        raise ValueError(f"initial values for parameters not fitted: {sorted(unknown)}")
    x0 = np.array([parameter(n, vehicle, params).check(initial[n], "initial value")
                   for n in names])
    limits = ({n: (v / 10.0, v * 10.0) for n, v in zip(names, x0)}
              | _checked_bounds(bounds, vehicle, params))
    lower = np.array([limits[n][0] for n in names])
    upper = np.array([limits[n][1] for n in names])
    for name, value, lo, hi in zip(names, x0, lower, upper):
        if not lo <= value <= hi:
            raise ValueError(f"the initial {name} {value:g} lies outside its bounds "
                             f"[{lo:g}, {hi:g}]")
    options = scenario.solver_options()
    common = dict(speed=scenario.speed, misalignment=scenario.misalignment,
                  duration=scenario.duration, options=options, cutoff=cutoff,
                  contact_model=scenario.contact_model(vehicle, params, track, contact,
                                                       progress))
    residuals, forward = _residual_functions(vehicle, params, track, names, measurements,
                                             common)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=max_iterations + POLISH_ITERATIONS, desc="identify", unit="it",
                   ncols=160)

    def report(iteration, loss, values):
        if bar is not None:
            bar.set_postfix_str(f"loss {loss:.6g} " + " ".join(
                f"{n}={v:.5g}" for n, v in zip(names, values)))
            if iteration:
                bar.update(1)

    try:
        fit = least_squares(residuals, names, x0, lower, upper,
                            data=jnp.asarray(measurements.values), method=method,
                            max_iterations=max_iterations, tolerance=tolerance,
                            jacobian_residuals=forward, progress=report,
                            gradient=("forward" if len(names) <= FORWARD_MODE_PARAMETERS
                                      else "reverse"))
    finally:
        if bar is not None:
            bar.close()
    simulated = measurements.values + measurements.noise * fit.residuals.reshape(
        measurements.values.shape)
    per_channel = channel_standard_errors(fit, measurements.channels, len(measurements.time))
    return Identification(fit, measurements, simulated, per_channel)
