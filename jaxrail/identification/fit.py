"""Weighted least squares in bounded log space with optax, and the Gauss-Newton
uncertainty at the optimum.

The parameters ``v`` (k,) are fitted through ``z``: ``log v = log lo + (log hi - log lo)
sigmoid(z)``, so every value stays inside its bounds ``[lo, hi]`` and a stiffness of
1e6 N/m and a friction of 0.4 take comparable steps (relative changes). The loss is
``0.5 sum r^2`` of whitened residuals ``r = (simulated - measured) / noise``.

Uncertainty: with ``J = dr / d log v`` at the optimum, ``cov(log v) = (J^T J)^-1``
(Gauss-Newton, the noise levels taken as stated) and ``std(v) = v std(log v)``. J is
by central differences over ``JACOBIAN_STEP`` in log v: a simulation through wheel-rail
impacts is rough at finer scales (the ringing after an impact, and what it leaves at
low frequencies, shifts with a 0.05 % change of the contact stiffness), and there the
local derivative measures the ripple's slope, not what the data tell about the
parameter. The local (AD) errors are kept beside them: much smaller local errors flag
such a loss (docs/identification.md).

On such a loss the optax iterations stop in one of the ripple's local minima, anywhere
the ripple's slope outweighs the bowl's: the scatter of the fitted values then far
exceeds any standard error. The fit therefore ends with a few Gauss-Newton steps with
that central-difference Jacobian, which see the bowl and not the ripple; they stop
when a step is below ``POLISH_TOLERANCE`` standard errors (tests/identification/test_fit.py
checks the errors against the scatter of repeated fits of a rough model).
"""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import optax

from .. import compilation


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of :func:`least_squares`.

    values, initial, lower, upper, standard_error (k,): in the parameters' units;
    covariance, correlation (k, k): of log v; loss_history (iterations + 1,);
    value_history (iterations + 1, k); gradient_norm: |dloss/dz| at the end;
    local_standard_error (k,): from the local (forward-mode AD) Jacobian instead;
    gauss_newton_iterations: the closing Gauss-Newton steps taken (module docstring);
    converged: the gradient or the relative loss change fell below the tolerance;
    reduced_chi2: 2 loss / (M - k), about 1 if the residuals are pure noise of the
    stated levels; jacobian (M, k) = dr / d log v (the one of the standard errors) and
    residuals (M,) at the values;
    evaluations: number of simulations run (line-search trials, gradients, the
    Gauss-Newton steps' differences and the final Jacobians);
    stop_reason.
    """

    names: tuple[str, ...]
    values: np.ndarray
    initial: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    standard_error: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    loss_history: np.ndarray
    value_history: np.ndarray
    gradient_norm: float
    converged: bool
    reduced_chi2: float
    local_standard_error: np.ndarray
    gauss_newton_iterations: int
    jacobian: np.ndarray = dataclasses.field(repr=False)
    residuals: np.ndarray = dataclasses.field(repr=False)
    evaluations: int = 0
    stop_reason: str = ""

    def as_dict(self) -> dict:
        """Plain-Python summary (JSON-serialisable)."""
        return {
            "parameters": {n: {"value": float(v), "standard_error": float(s),
                               "local_standard_error": float(ls), "initial": float(i),
                               "lower": float(lo), "upper": float(hi)}
                           for n, v, s, ls, i, lo, hi in zip(
                               self.names, self.values, self.standard_error,
                               self.local_standard_error, self.initial, self.lower,
                               self.upper)},
            "correlation": self.correlation.tolist(),
            "loss_history": self.loss_history.tolist(),
            "value_history": self.value_history.tolist(),
            "iterations": len(self.loss_history) - 1, "evaluations": self.evaluations,
            "gauss_newton_iterations": self.gauss_newton_iterations,
            "gradient_norm": self.gradient_norm, "converged": self.converged,
            "stop_reason": self.stop_reason,
            "reduced_chi2": self.reduced_chi2,
        }


def _transform(lower, upper):
    log_lo, span = jnp.log(lower), jnp.log(upper) - jnp.log(lower)
    to_values = lambda z: jnp.exp(log_lo + span * jax.nn.sigmoid(z))  # noqa: E731
    to_z = lambda v: jnp.log((jnp.log(v) - log_lo) / (log_lo + span - jnp.log(v)))  # noqa: E731
    return to_values, to_z


def gauss_newton_covariance(jacobian):
    """cov (k, k) of log v and its correlation matrix from ``J = dr / d log v`` (M, k)."""
    information = jacobian.T @ jacobian
    covariance = np.linalg.pinv(information)
    std = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    return covariance, covariance / np.outer(std, std)


ARMIJO = 1e-4  # sufficient decrease of the backtracking line search
BACKTRACKS = 20  # halvings of the step before the line search gives up
MAX_STEP = 0.3  # longest step in z: about 30 % in value mid-range
# L-BFGS stops when the decrease of the loss that its model predicts is below this. The
# loss is 0.5 chi^2, which rises by 0.5 when a parameter moves by one standard error:
# 1e-4 of that is far below any statistical meaning (in the study, 0.04 % of the
# stiffness); a smaller threshold only lets the fit zig-zag along its valley, at minutes
# per iteration.
DECREMENT = 1e-4
# Central-difference step in log v of the Jacobian of the uncertainty: 1 %, above the
# roughness of impact dynamics (0.1 % in the study) and below any useful uncertainty.
JACOBIAN_STEP = 1e-2
POLISH_ITERATIONS = 6  # most Gauss-Newton steps at the end of a fit
# [standard errors] a Gauss-Newton step this short has converged: on a rough loss the
# steps settle at about a tenth of a standard error (tests/identification/test_fit.py)
POLISH_TOLERANCE = 0.2
# Rise of the loss a Gauss-Newton step may take: 0.5, what moving one parameter by one
# standard error costs, about the ripple of a rough loss.
LOSS_SLACK = 0.5


def _compiled(residuals, method, learning_rate, forward_residuals=None):
    """``(optimizer, gradient, residuals_z, update)``, jitted once per residual function
    object and method. ``gradient(z, bounds, data)`` is ``(loss, dloss/dz, J_z)``: by
    reverse mode (J_z None), or by forward mode through ``forward_residuals`` if given
    (k products, cheaper for a few parameters; J_z = dr/dz). ``residuals_z(z, bounds,
    data)`` is r, a forward simulation: the line search's trials and the central
    differences of the uncertainty. Fits that pass the same functions share the
    compiled programs (data and bounds are arguments, not constants), kept in the
    process's program cache (:func:`jaxrail.compilation.kept`)."""
    if method == "lbfgs":
        optimizer = optax.lbfgs(linesearch=None)
    elif method == "adam":
        optimizer = optax.adam(learning_rate)
    else:
        raise ValueError(f"method must be 'lbfgs' or 'adam', got {method!r}")

    def residuals_z(z, bounds, data):
        return residuals(_transform(*bounds)[0](z), data)

    def reverse(z, bounds, data):
        value, grad = jax.value_and_grad(
            lambda z: 0.5 * jnp.sum(residuals_z(z, bounds, data) ** 2))(z)
        return value, grad, None

    def forward(z, bounds, data):
        to_values = _transform(*bounds)[0]
        return loss_gradient_jacobian(lambda z: forward_residuals(to_values(z), data), z)

    def programs():
        return (optimizer, compilation.jit(reverse if forward_residuals is None else forward),
                compilation.jit(residuals_z),
                jax.jit(lambda grad, state, z: optimizer.update(grad, state, z)))

    key = ("identification.fit", residuals, method, learning_rate, forward_residuals)
    return compilation.kept(key, programs)


def jacobian_by_jvp(function, x):
    """``function(x)`` (M,) and its Jacobian (M, k) by k forward-mode products (the
    primal computed once, the tangents batched)."""
    basis = jnp.eye(x.shape[0])
    r, columns = jax.vmap(lambda e: jax.jvp(function, (x,), (e,)), out_axes=(None, 0))(basis)
    return r, columns.T


def loss_gradient_jacobian(function, x):
    """``0.5 |r|^2``, its gradient ``J^T r`` and ``J`` (M, k) of ``r = function(x)`` by
    forward mode (:func:`jacobian_by_jvp`)."""
    r, jacobian = jacobian_by_jvp(function, x)
    return 0.5 * jnp.sum(r ** 2), jacobian.T @ r, jacobian


def residuals_and_jacobian(residuals, values, data):
    """Residuals (M,) and ``J = dr / d log v`` (M, k) at ``values`` by forward mode."""
    return jacobian_by_jvp(lambda x: residuals(jnp.exp(x), data),
                            jnp.log(jnp.asarray(values)))


def least_squares(residuals, names, initial, lower, upper, data=None, method="lbfgs",
                  max_iterations=50, tolerance=1e-9, learning_rate=0.1,
                  jacobian_residuals=None, gradient="reverse", jacobian_step=JACOBIAN_STEP,
                  polish_iterations=POLISH_ITERATIONS, progress=None) -> FitResult:
    """Minimise ``0.5 sum residuals(v, data)^2`` over ``v`` in ``[lower, upper]``.

    Arguments:
        residuals: ``(v (k,), data) -> r (M,)``, whitened; must support ``jax.grad``.
            Reuse one function object across fits: the compiled step is cached on it.
        names: the k parameter names (labels); initial, lower, upper: (k,), > 0.
        data: a pytree of arrays passed to ``residuals`` (the measurements).
        method: ``"lbfgs"`` (optax's L-BFGS direction, a backtracking Armijo line
            search on the host) or ``"adam"`` (``learning_rate`` in z).
        max_iterations; tolerance: stop when |dloss/dz| < tolerance * max(1, loss) or
            (L-BFGS) the loss changes by less than ``tolerance`` relative, or the
            decrease the L-BFGS model predicts, g^T H^-1 g, is below ``DECREMENT``
            (the loss is in units of noise variance: 1e-6 is no information).
        jacobian_residuals: the same function for forward mode (simulations need
            diffrax's forward-mode adjoint); default ``residuals``.
        gradient: ``"reverse"`` (one reverse pass, any number of parameters) or
            ``"forward"`` (k forward-mode products through ``jacobian_residuals``:
            cheaper for a few parameters, benchmarks/gradient.py).
        jacobian_step: central-difference step in log v of the uncertainty's Jacobian
            and of the closing Gauss-Newton steps (None: the local forward-mode
            Jacobian and no closing steps; module docstring).
        polish_iterations: most closing Gauss-Newton steps.
        progress: None, or a callable ``(iteration, loss, values)`` called each step.

    The L-BFGS steps are at most ``MAX_STEP`` long in z; when the line search finds
    no decrease the fit stops, not converged, with that reason.
    """
    initial, lower, upper = (np.asarray(x, dtype=np.float64) for x in (initial, lower, upper))
    if not (initial.shape == lower.shape == upper.shape == (len(names),)):
        raise ValueError("initial, lower and upper need one value per parameter")
    for n, v, lo, hi in zip(names, initial, lower, upper):
        if not 0.0 < lo < v < hi:
            raise ValueError(f"{n}: need 0 < lower < initial < upper, got {lo}, {v}, {hi}")
    if gradient not in ("reverse", "forward"):
        raise ValueError(f"gradient must be 'reverse' or 'forward', got {gradient!r}")
    forward = residuals if jacobian_residuals is None else jacobian_residuals
    optimizer, gradient_program, residuals_z, update = _compiled(
        residuals, method, learning_rate, forward if gradient == "forward" else None)
    bounds = (jnp.asarray(lower), jnp.asarray(upper))
    to_values, to_z = _transform(*bounds)

    # every simulation goes through value_and_grad or residuals_at, which count them
    def value_and_grad(z):
        nonlocal jacobian_z, evaluations
        evaluations += 1
        value, grad, jacobian_z = gradient_program(z, bounds, data)
        return value, grad

    def residuals_at(z):
        nonlocal evaluations
        evaluations += 1
        return np.asarray(residuals_z(z, bounds, data))

    def residuals_in_log(x):
        return residuals_at(to_z(jnp.exp(jnp.asarray(x))))

    def value_only(z):
        return 0.5 * float(np.sum(residuals_at(z) ** 2))

    jacobian_z, evaluations = None, 0
    z = to_z(jnp.asarray(initial))
    state = optimizer.init(z)
    value, grad = value_and_grad(z)
    losses, values, converged = [float(value)], [np.asarray(to_values(z))], False
    reason = "maximum iterations"
    if progress is not None:
        progress(0, losses[0], values[0])
    for iteration in range(1, max_iterations + 1):
        direction, state = update(grad, state, z)
        if method == "lbfgs":
            # backtracking (Armijo) along the L-BFGS direction, steepest descent if it
            # is not a descent direction
            decrement = -float(jnp.vdot(grad, direction))  # ~ g^T H^-1 g
            if 0.0 <= decrement < DECREMENT:
                converged, reason = True, "predicted decrease below DECREMENT"
                break
            if not decrement > 0.0:
                direction = -grad
            # at most MAX_STEP in z (a factor of about e in value) per iteration
            direction = direction * jnp.minimum(1.0, MAX_STEP / jnp.linalg.norm(direction))
            slope = float(jnp.vdot(grad, direction))
            step = 1.0
            for _ in range(BACKTRACKS):
                trial = z + step * direction
                trial_value = value_only(trial)
                if trial_value <= float(value) + ARMIJO * step * slope:
                    trial_value, trial_grad = value_and_grad(trial)
                    break
                step *= 0.5
            else:
                reason = "no decrease along the search direction (at the loss's precision)"
                break
        else:
            trial = optax.apply_updates(z, direction)
            trial_value, trial_grad = value_and_grad(trial)
        previous = float(value)
        z, value, grad = trial, trial_value, trial_grad
        losses.append(float(value))
        values.append(np.asarray(to_values(z)))
        if progress is not None:
            progress(iteration, losses[-1], values[-1])
        small_gradient = float(jnp.linalg.norm(grad)) < tolerance * max(1.0, losses[-1])
        stalled = abs(previous - losses[-1]) <= tolerance * max(abs(losses[-1]), 1e-300)
        if small_gradient or (method == "lbfgs" and stalled):
            converged, reason = True, "small gradient" if small_gradient else "loss stalled"
            break

    gauss_newton_iterations, jacobian = 0, None
    if jacobian_step is not None and polish_iterations > 0:
        x, polished, jacobian, gauss_newton_iterations, stop = gauss_newton(
            residuals_in_log, np.log(np.asarray(to_values(z))), np.log(lower),
            np.log(upper), jacobian_step, polish_iterations)
        for loss, values_x in polished:
            losses.append(loss)
            values.append(np.exp(values_x))
            if progress is not None:
                progress(len(losses) - 1, loss, values[-1])
        if stop is not None:
            converged, reason = stop == "converged", f"Gauss-Newton: {stop}"
        if gauss_newton_iterations:
            z = to_z(jnp.exp(jnp.asarray(x)))
            if gradient == "forward":  # the local J at the final point
                value, grad = value_and_grad(z)
    fitted = np.asarray(to_values(z))
    # d log v / dz of the bounded transform
    log_slope = (jnp.log(bounds[1]) - jnp.log(bounds[0])) * jax.nn.sigmoid(z) * jax.nn.sigmoid(-z)
    if gradient == "forward":  # J at the last gradient, in log v
        r = residuals_at(z)
        local = np.asarray(jacobian_z / log_slope)
    else:
        r, local = residuals_and_jacobian(forward, fitted, data)
        evaluations += 1
        r, local = np.asarray(r), np.asarray(local)
        if gauss_newton_iterations:  # the gradient at the final point, from the same J
            grad = (local * np.asarray(log_slope)).T @ r
    if jacobian_step is None:
        jacobian = local
    elif jacobian is None:
        jacobian = secant_jacobian(residuals_in_log, np.log(fitted), np.log(lower),
                                   np.log(upper), jacobian_step)
    covariance, correlation = gauss_newton_covariance(jacobian)
    local_covariance, _ = gauss_newton_covariance(local)
    m = jacobian.shape[0]
    return FitResult(tuple(names), fitted, initial, lower, upper,
                     fitted * np.sqrt(np.maximum(np.diag(covariance), 0.0)), covariance,
                     correlation, np.array(losses), np.array(values),
                     float(jnp.linalg.norm(grad)), converged,
                     2.0 * losses[-1] / max(m - len(names), 1),
                     fitted * np.sqrt(np.maximum(np.diag(local_covariance), 0.0)),
                     gauss_newton_iterations, jacobian, np.asarray(r), evaluations, reason)


def secant_jacobian(function, x, lower, upper, step):
    """Jacobian (M, k) of ``function`` (k,) -> (M,) at ``x`` by central differences of
    ``step``, shortened to stay inside ``[lower, upper]`` (half the room to a bound)."""
    room = 0.5 * np.minimum(x - lower, upper - x)
    return np.stack([central_difference(function, x, i, min(step, room[i]))
                     for i in range(len(x))], axis=1)


def gauss_newton(function, x, lower, upper, step, iterations):
    """Gauss-Newton on ``0.5 |function(x)|^2`` from ``x`` (k,) inside ``(lower, upper)``,
    the Jacobian by :func:`secant_jacobian`. A step is halved while it raises the loss
    by more than ``LOSS_SLACK`` (a rough loss rises and falls by about that between
    points a fraction of a standard error apart) and kept inside the bounds.

    Returns ``(x, [(loss, x) per step taken], J at x, steps taken, stop)`` with stop
    "converged" (the next step below ``POLISH_TOLERANCE`` standard errors), "no
    acceptable Gauss-Newton step", or None (``iterations`` reached).
    """
    r = function(x)
    jacobian = secant_jacobian(function, x, lower, upper, step)
    history = []
    for _ in range(iterations):
        delta = -np.linalg.lstsq(jacobian, r, rcond=None)[0]
        standard_error = np.sqrt(np.maximum(np.diag(gauss_newton_covariance(jacobian)[0]),
                                            1e-300))
        if np.all(np.abs(delta) < POLISH_TOLERANCE * standard_error):
            return x, history, jacobian, len(history), "converged"
        inside = lower + 1e-9 + np.clip(x + delta - lower - 1e-9, 0.0, upper - lower - 2e-9)
        delta = inside - x
        for _ in range(BACKTRACKS):
            trial = function(x + delta)
            if 0.5 * float(trial @ trial) <= 0.5 * float(r @ r) + LOSS_SLACK:
                break
            delta = 0.5 * delta
        else:
            return x, history, jacobian, len(history), "no acceptable Gauss-Newton step"
        x, r = x + delta, trial
        history.append((0.5 * float(r @ r), x))
        jacobian = secant_jacobian(function, x, lower, upper, step)
    return x, history, jacobian, len(history), None


def central_difference(function, x, i, step):
    """(f(x + step e_i) - f(x - step e_i)) / (2 step) of an array function f."""
    e = np.zeros_like(x)
    e[i] = step
    return (function(x + e) - function(x - e)) / (2.0 * step)


def channel_standard_errors(fit: FitResult, channels, samples_per_channel) -> dict:
    """Standard errors (k,) of the fitted values from each channel alone: the
    Gauss-Newton information of that channel's rows of the Jacobian (residuals ordered
    sample-major: M samples x C channels). Infinite where a channel alone does not
    determine the parameters."""
    c = len(channels)
    jacobian = fit.jacobian.reshape(samples_per_channel, c, -1)
    out = {}
    for k, channel in enumerate(channels):
        information = jacobian[:, k, :].T @ jacobian[:, k, :]
        if np.linalg.cond(information) > 1e12:
            out[channel] = [math.inf] * len(fit.names)
        else:
            covariance, _ = gauss_newton_covariance(jacobian[:, k, :])
            out[channel] = (fit.values * np.sqrt(np.diag(covariance))).tolist()
    return out
