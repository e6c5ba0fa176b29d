"""Weighted least squares in bounded log space with optax, and the Gauss-Newton
uncertainty at the optimum.

The parameters ``v`` (k,) are fitted through ``z``: ``log v = log lo + (log hi - log lo)
sigmoid(z)``, so every value stays inside its bounds ``[lo, hi]`` and a stiffness of
1e6 N/m and a friction of 0.4 take comparable steps (relative changes). The loss is
``0.5 sum r^2`` of whitened residuals ``r = (simulated - measured) / noise``.

Uncertainty: with ``J = dr / d log v`` at the optimum, ``cov(log v) = (J^T J)^-1``
(Gauss-Newton, the noise levels taken as stated) and ``std(v) = v std(log v)``.
"""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import optax


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of :func:`least_squares`.

    values, initial, lower, upper, standard_error (k,): in the parameters' units;
    covariance, correlation (k, k): of log v; loss_history (iterations + 1,);
    value_history (iterations + 1, k); gradient_norm: |dloss/dz| at the end;
    converged: the gradient or the relative loss change fell below the tolerance;
    reduced_chi2: 2 loss / (M - k), about 1 if the residuals are pure noise of the
    stated levels; jacobian (M, k) = dr / d log v and residuals (M,) at the values;
    evaluations: number of simulations run (line-search trials and gradients);
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
    jacobian: np.ndarray = dataclasses.field(repr=False)
    residuals: np.ndarray = dataclasses.field(repr=False)
    evaluations: int = 0
    stop_reason: str = ""

    def as_dict(self) -> dict:
        """Plain-Python summary (JSON-serialisable)."""
        return {
            "parameters": {n: {"value": float(v), "standard_error": float(s),
                               "initial": float(i), "lower": float(lo), "upper": float(hi)}
                           for n, v, s, i, lo, hi in zip(self.names, self.values,
                                                         self.standard_error, self.initial,
                                                         self.lower, self.upper)},
            "correlation": self.correlation.tolist(),
            "loss_history": self.loss_history.tolist(),
            "value_history": self.value_history.tolist(),
            "iterations": len(self.loss_history) - 1, "evaluations": self.evaluations,
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


_COMPILED = {}
ARMIJO = 1e-4  # sufficient decrease of the backtracking line search
BACKTRACKS = 20  # halvings of the step before the line search gives up
MAX_STEP = 0.3  # longest step in z: about 30 % in value mid-range
# L-BFGS stops when the decrease of the loss that its model predicts is below this. The
# loss is 0.5 chi^2, which rises by 0.5 when a parameter moves by one standard error:
# 1e-4 of that is far below any statistical meaning (in the study, 0.04 % of the
# stiffness), and 1e-6 kept the noise-free fit zig-zagging in its valley for 3 minutes
# an iteration.
DECREMENT = 1e-4


def _compiled(residuals, method, learning_rate):
    """``(optimizer, value_and_grad, value, update)``, jitted once per residual function
    object and method: fits that pass the same function share the compiled programs
    (data and bounds are arguments, not constants). The line search runs on the host and tries steps
    with the loss alone (a forward simulation, about a tenth of a gradient's cost)."""
    key = (residuals, method, learning_rate)
    if key in _COMPILED:
        return _COMPILED[key]
    if method == "lbfgs":
        optimizer = optax.lbfgs(linesearch=None)
    elif method == "adam":
        optimizer = optax.adam(learning_rate)
    else:
        raise ValueError(f"method must be 'lbfgs' or 'adam', got {method!r}")

    def loss(z, bounds, data):
        return 0.5 * jnp.sum(residuals(_transform(*bounds)[0](z), data) ** 2)

    _COMPILED[key] = (optimizer, jax.jit(jax.value_and_grad(loss)), jax.jit(loss),
                      jax.jit(lambda grad, state, z: optimizer.update(grad, state, z)))
    return _COMPILED[key]


def residuals_and_jacobian(residuals, values, data):
    """Residuals (M,) and ``J = dr / d log v`` (M, k) at ``values`` by forward mode."""
    def in_log(x):
        return residuals(jnp.exp(x), data)

    x = jnp.log(jnp.asarray(values))
    basis = jnp.eye(x.shape[0])
    r, columns = jax.vmap(lambda e: jax.jvp(in_log, (x,), (e,)), out_axes=(None, 0))(basis)
    return r, columns.T


def least_squares(residuals, names, initial, lower, upper, data=None, method="lbfgs",
                  max_iterations=50, tolerance=1e-9, learning_rate=0.1,
                  jacobian_residuals=None, progress=None) -> FitResult:
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
    optimizer, value_and_grad, value_only, update = _compiled(residuals, method,
                                                              learning_rate)
    bounds = (jnp.asarray(lower), jnp.asarray(upper))
    to_values, to_z = _transform(*bounds)
    z = to_z(jnp.asarray(initial))
    state = optimizer.init(z)
    value, grad = value_and_grad(z, bounds, data)
    losses, values, converged, evaluations = [float(value)], [np.asarray(to_values(z))], False, 1
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
                trial_value = float(value_only(trial, bounds, data))
                evaluations += 1
                if trial_value <= float(value) + ARMIJO * step * slope:
                    trial_value, trial_grad = value_and_grad(trial, bounds, data)
                    evaluations += 1
                    break
                step *= 0.5
            else:
                reason = "no decrease along the search direction (at the loss's precision)"
                break
        else:
            trial = optax.apply_updates(z, direction)
            trial_value, trial_grad = value_and_grad(trial, bounds, data)
            evaluations += 1
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

    fitted = np.asarray(to_values(z))
    r, jacobian = residuals_and_jacobian(
        residuals if jacobian_residuals is None else jacobian_residuals, fitted, data)
    jacobian = np.asarray(jacobian)
    covariance, correlation = gauss_newton_covariance(jacobian)
    m = jacobian.shape[0]
    return FitResult(tuple(names), fitted, initial, lower, upper,
                     fitted * np.sqrt(np.maximum(np.diag(covariance), 0.0)), covariance,
                     correlation, np.array(losses), np.array(values),
                     float(jnp.linalg.norm(grad)), converged,
                     2.0 * losses[-1] / max(m - len(names), 1), jacobian, np.asarray(r),
                     evaluations, reason)


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
