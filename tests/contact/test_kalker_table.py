"""The tabulated Kalker coefficients (the default, ``method="table"``) against the
defining evaluation (``method="direct"``, tested in test_kalker.py): accuracy on a dense
sample of a/b and nu, the joins, C1 smoothness, gradients, jit/vmap."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact import kalker
from jaxrail.contact.kalker import kalker_coefficients

TABLE_TOL = 5e-7  # measured: 1.5e-7 (next to the spline knots at a/b = 0.9, 1/0.9)
N_SAMPLE = 16384


def _stacked(r, nu, method="table"):
    return jnp.stack(kalker_coefficients(r, nu, method=method))


_batch = {m: jax.jit(lambda r, nu, m=m: _stacked(r, nu, m)) for m in ("table", "direct")}


def _sample():
    rng = np.random.default_rng(19)
    x = np.concatenate(
        [
            rng.uniform(-9.0, 9.0, N_SAMPLE // 4),  # past the table's |x| <= 6.01
            rng.uniform(-2.4, 2.4, N_SAMPLE // 4),  # Kalker's table 0.1 ... 10
            rng.uniform(-0.2, 0.2, N_SAMPLE // 4),  # around the spline knots next to 1
            np.linspace(-6.1, 6.1, N_SAMPLE // 4),
        ]
    )
    nu = np.concatenate([rng.uniform(0.0, 0.5, N_SAMPLE // 2), np.full(N_SAMPLE // 2, 0.28)])
    return np.exp(x), nu


def test_table_matches_direct_on_a_dense_sample():
    r, nu = _sample()
    table = np.asarray(_batch["table"](r, nu))
    direct = np.asarray(_batch["direct"](r, nu))
    assert np.all(np.isfinite(table))
    rel = np.abs(table / direct - 1.0)
    assert np.max(rel) < TABLE_TOL, np.max(rel, axis=1)


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_table_rows_and_asymptotes(nu):
    rows = kalker.TABLE_A_OVER_B
    c = np.asarray(_batch["table"](rows, np.full(rows.size, nu)))
    j = list(kalker.TABLE_NU).index(nu)
    np.testing.assert_allclose(c.T, kalker.TABLE[:, :, j], rtol=TABLE_TOL)
    far = np.array([1e-4, 1e-3, 1e3, 1e4])
    c = np.asarray(_batch["table"](far, np.full(far.size, nu)))
    asym = np.array([kalker.kalker_asymptotes(r, nu) for r in far]).T
    np.testing.assert_allclose(c, asym, rtol=1e-6)


def _log_c(x, nu):
    return jnp.log(_stacked(jnp.exp(x), nu))


def _log_c_direct(x, nu):
    return jnp.log(_stacked(jnp.exp(x), nu, "direct"))


_d1 = jax.jit(jax.vmap(jax.jacfwd(_log_c), (0, None)))
_d1_direct = jax.jit(jax.vmap(jax.jacfwd(_log_c_direct), (0, None)))


def test_c1_across_nodes_and_joins():
    # The slope is continuous at the grid nodes (Hermite), the table ends +-log 10 and
    # the grid end; the second derivative jumps slightly at the nodes (not tested).
    step, end = kalker._GRID_STEP, kalker._GRID_END
    x = np.concatenate([np.arange(-7, 8) * 37 * step, [-end, end, np.log(10.0), -np.log(10.0)]])
    h = 1e-9
    for nu in (0.0, 0.28, 0.5):
        left, right = np.asarray(_d1(x - h, nu)), np.asarray(_d1(x + h, nu))
        np.testing.assert_allclose(left, right, rtol=0, atol=1e-6)
        direct = np.asarray(_d1_direct(x, nu))
        np.testing.assert_allclose(left, direct, rtol=0, atol=1e-4)


_jac_rev = jax.jit(jax.jacrev(lambda v: _stacked(v[0], v[1])))
_jac_fwd = jax.jit(jax.jacfwd(lambda v: _stacked(v[0], v[1])))
_value = jax.jit(lambda v: _stacked(v[0], v[1]))


@pytest.mark.parametrize("r", [0.003, 0.07, 0.1, 0.45, 1.0, 3.7, 10.0, 40.0, 1e4])
def test_grad_matches_central_differences(r, central_jacobian):
    v = np.array([r, 0.28])
    jac = np.array(_jac_rev(v))
    fd = central_jacobian(_value, v, (1e-6 * r, 1e-6))
    scale = np.abs(np.array(_value(v)))[:, None] / np.array([r, 1.0])  # c / (a/b), c / nu
    np.testing.assert_allclose(jac / scale, fd / scale, rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.array(_jac_fwd(v)) / scale, jac / scale, rtol=0, atol=1e-12)
    assert np.all(np.isfinite(jac))


def test_broadcast_jit_and_vmap_agree():
    r = np.array([0.05, 0.3, 1.0, 2.2, 15.0, 800.0])
    nu = np.array([0.0, 0.1, 0.28, 0.3, 0.5, 0.28])
    broadcast = np.asarray(_batch["table"](r, nu))
    mapped = np.asarray(jax.jit(jax.vmap(_stacked, out_axes=1))(r, nu))
    np.testing.assert_allclose(mapped, broadcast, rtol=1e-14)
    scalar_nu = np.asarray(jax.jit(lambda r: _stacked(r, 0.28))(r))
    np.testing.assert_allclose(scalar_nu[:, 2], broadcast[:, 2], rtol=1e-14)
    with pytest.raises(ValueError, match="method"):
        kalker_coefficients(1.0, 0.28, method="exact")
