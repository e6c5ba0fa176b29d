"""Least squares in bounded log space (jaxrail.identification.fit) on models with a known
answer: the fit recovers the truth, and the Gauss-Newton standard errors match the
scatter of repeated noisy fits (an independent Monte Carlo estimate)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.identification.fit import gauss_newton_covariance, least_squares

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


def test_forward_mode_gradient_follows_the_reverse_mode_path():
    """The fit with forward-mode gradients (k products) takes the same steps as with
    reverse mode, and its first gradient matches central differences of the loss."""
    start = TRUTH * [1.3, 0.7]
    fits = [least_squares(decay_residuals, ("a", "k"), start, TRUTH / 10, TRUTH * 10,
                          data=clean(), max_iterations=40, gradient=mode)
            for mode in ("reverse", "forward")]
    assert len(fits[0].loss_history) == len(fits[1].loss_history)
    assert np.allclose(fits[0].value_history, fits[1].value_history, rtol=1e-9)

    from jaxrail.identification.fit import _compiled, _transform
    bounds = (jnp.asarray(TRUTH / 10), jnp.asarray(TRUTH * 10))
    _, gradient, residuals_z, _ = _compiled(decay_residuals, "lbfgs", 0.1, decay_residuals)
    z = _transform(*bounds)[1](jnp.asarray(start))
    loss = lambda z: 0.5 * np.sum(np.asarray(residuals_z(z, bounds, clean())) ** 2)  # noqa: E731
    h = 1e-6
    central = [(loss(z + h * e) - loss(z - h * e)) / (2 * h) for e in np.eye(2)]
    assert np.allclose(gradient(z, bounds, clean())[1], central, rtol=1e-6)


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


RIPPLE = 1e-3  # amplitude of the rough model's ripple, 0.1 noise level
PERIOD = 2e-3  # its period in the decay rate, far below the rate's standard error


def rough_residuals(values, data):
    """The decay plus a fast ripple in the parameter, like the ringing after a wheel-rail
    impact shifting with the contact stiffness."""
    ripple = RIPPLE * jnp.sin(2 * jnp.pi * values[1] / PERIOD) * jnp.cos(7.0 * T)
    return (values[0] * jnp.exp(-values[1] * T) + ripple - data) / SIGMA


def test_standard_errors_match_scatter_on_a_rough_loss():
    """On a loss with a fast ripple the local (AD) errors are several times too small and
    the optax iterations alone stop in the ripple's minima far from the optimum; the
    closing Gauss-Newton steps with central differences bring the scatter of the
    fitted values down to their standard errors."""
    rng = np.random.default_rng(0)
    clean = rough_residuals(jnp.asarray(TRUTH), 0.0) * SIGMA
    estimates, raw, errors, local = [], [], [], []
    for _ in range(150):
        data = clean + SIGMA * rng.standard_normal(T.shape)
        fit = least_squares(rough_residuals, ("a", "k"), TRUTH * [1.3, 0.7], TRUTH / 10,
                            TRUTH * 10, data=data, max_iterations=60)
        assert fit.converged
        estimates.append(fit.values)
        errors.append(fit.standard_error)
        local.append(fit.local_standard_error)
        raw.append(least_squares(rough_residuals, ("a", "k"), TRUTH * [1.3, 0.7],
                                 TRUTH / 10, TRUTH * 10, data=data, max_iterations=60,
                                 polish_iterations=0).values)
    scatter = np.std(estimates, axis=0, ddof=1)
    assert np.allclose(np.median(errors, axis=0), scatter, rtol=0.2)
    assert np.median(local, axis=0)[1] < 0.3 * scatter[1]
    assert np.all(np.std(raw, axis=0, ddof=1) > 3.0 * scatter)


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
    with pytest.raises(ValueError, match="gradient must be"):
        least_squares(decay_residuals, ("a", "k"), [2.0, 1.0], [1.0, 0.5], [3.0, 3.0],
                      data=clean(), gradient="central")


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
