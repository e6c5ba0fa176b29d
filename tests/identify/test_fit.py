"""Least squares in bounded log space (jaxrail.identify.fit) on models with a known
answer: the fit recovers the truth, and the Gauss-Newton standard errors match the
scatter of repeated noisy fits (an independent Monte Carlo estimate)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.identify.fit import gauss_newton_covariance, least_squares

T = jnp.linspace(0.0, 2.0, 50)
TRUTH = np.array([2.0, 1.5])  # amplitude [-], decay rate [1/s]
SIGMA = 0.01


def decay_residuals(values, data):
    return (values[0] * jnp.exp(-values[1] * T) - data) / SIGMA


def clean():
    return jnp.asarray(TRUTH[0] * np.exp(-TRUTH[1] * np.asarray(T)))


@pytest.mark.parametrize("method, iterations", [("lbfgs", 40), ("adam", 400)])
def test_recovers_truth_from_30_percent_off(method, iterations):
    fit = least_squares(decay_residuals, ("a", "k"), TRUTH * [1.3, 0.7], TRUTH / 10,
                        TRUTH * 10, data=clean(), method=method, max_iterations=iterations)
    assert np.allclose(fit.values, TRUTH, rtol=1e-4)
    assert fit.loss_history[-1] < 1e-3 * fit.loss_history[0]
    assert fit.value_history.shape == (len(fit.loss_history), 2)
    assert np.all((fit.value_history > TRUTH / 10) & (fit.value_history < TRUTH * 10))


def test_standard_errors_match_monte_carlo_scatter():
    rng = np.random.default_rng(0)
    estimates, chi2 = [], []
    for _ in range(150):
        data = clean() + SIGMA * rng.standard_normal(T.shape)
        fit = least_squares(decay_residuals, ("a", "k"), TRUTH * [1.3, 0.7], TRUTH / 10,
                            TRUTH * 10, data=data)
        assert fit.converged
        estimates.append(fit.values)
        chi2.append(fit.reduced_chi2)
    scatter = np.std(estimates, axis=0, ddof=1)
    # 150 samples: the scatter's own relative uncertainty is about 6 %
    assert np.allclose(fit.standard_error, scatter, rtol=0.2)
    assert abs(np.mean(chi2) - 1.0) < 0.05


def test_linear_model_covariance_is_exact():
    # r = (A x - b) / sigma with x = log v: cov(log v) = sigma^2 (A^T A)^-1 exactly
    a = np.random.default_rng(1).standard_normal((30, 3))
    jacobian = a / SIGMA
    covariance, correlation = gauss_newton_covariance(jacobian)
    assert np.allclose(covariance, SIGMA**2 * np.linalg.inv(a.T @ a), rtol=1e-10)
    assert np.allclose(np.diag(correlation), 1.0)


def test_bounds_hold_when_the_optimum_is_outside():
    fit = least_squares(decay_residuals, ("a", "k"), [1.5, 1.4], [1.0, 1.0], [1.8, 10.0],
                        data=clean(), max_iterations=60)
    assert 1.79 < fit.values[0] < 1.8  # pinned at its upper bound (the truth is 2)
    assert np.all(fit.value_history[:, 0] < 1.8)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="k: need 0 < lower < initial < upper"):
        least_squares(decay_residuals, ("a", "k"), [2.0, 20.0], [1.0, 1.0], [3.0, 3.0],
                      data=clean())
    with pytest.raises(ValueError, match="method"):
        least_squares(decay_residuals, ("a", "k"), [2.0, 1.0], [1.0, 0.5], [3.0, 3.0],
                      data=clean(), method="newton")


def test_batched_loss_gradient_is_the_sum_of_member_gradients():
    """grad of a vmapped, summed loss equals the sum of the members' gradients (here
    through diffrax: a decaying oscillator per member, parameters shared)."""
    import diffrax

    def member(values, omega):
        term = diffrax.ODETerm(lambda t, y, a: jnp.array([y[1], -a[0] * y[0] - a[1] * y[1]]))
        sol = diffrax.diffeqsolve(term, diffrax.Tsit5(), 0.0, 2.0, 0.01, jnp.array([1.0, 0.0]),
                                  args=(omega**2 * values[0], values[1]),
                                  saveat=diffrax.SaveAt(ts=T),
                                  stepsize_controller=diffrax.ConstantStepSize())
        return jnp.sum(sol.ys[:, 0] ** 2)

    omegas = jnp.array([1.0, 2.0, 3.0])
    values = jnp.array([1.1, 0.3])
    batched = jax.grad(lambda v: jnp.sum(jax.vmap(lambda w: member(v, w))(omegas)))(values)
    one_by_one = sum(jax.grad(member)(values, w) for w in omegas)
    assert np.allclose(batched, one_by_one, rtol=1e-12, atol=0.0)
