"""Inverses of small blocks in plain operations (jaxrail.multibody.block_inverse) and
IMEX's block-diagonal solve for systems without joints, against NumPy's LAPACK inverse,
the analytic derivative of an inverse and the dense (I - hg J)^-1 of the whole state."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody.block_inverse import block_inverses
from jaxrail.multibody.imex import StiffJacobian, stiff_jacobian

jax.config.update("jax_enable_x64", True)


def awkward_blocks():
    """(5, 7, 7): random blocks, one with a zero first pivot, one a permutation (every
    column's pivot below the diagonal), one nearly diagonal with a tiny entry."""
    rng = np.random.default_rng(11)
    a = rng.normal(size=(5, 7, 7))
    a[1, 0, 0] = 0.0
    a[2] = np.eye(7)[[3, 6, 0, 5, 1, 2, 4]]
    a[3] = np.diag(rng.uniform(1.0, 2.0, 7)) + 1e-9 * a[3]
    return a


def test_the_inverses_equal_lapacks():
    a = awkward_blocks()
    np.testing.assert_allclose(block_inverses(jnp.asarray(a)), np.linalg.inv(a), rtol=0,
                               atol=1e-12)


def test_under_jit_and_vmap():
    a = awkward_blocks()
    batched = jax.jit(jax.vmap(block_inverses))(jnp.asarray(np.stack([a, 2.0 * a])))
    np.testing.assert_allclose(batched[1], np.linalg.inv(2.0 * a), rtol=0, atol=1e-12)


def test_a_singular_block_gives_entries_that_are_not_finite_in_that_block_only():
    a = awkward_blocks()
    a[4, 5] = a[4, 2]
    inverses = np.asarray(block_inverses(jnp.asarray(a)))
    assert not np.isfinite(inverses[4]).all()
    assert np.isfinite(inverses[:4]).all()


def test_gradients_against_the_analytic_derivative_and_central_differences():
    """d(A^-1) = -A^-1 dA A^-1, forward and reverse mode, and central differences of a
    scalar of the inverses (step 1e-6, relative 1e-6)."""
    a = jnp.asarray(awkward_blocks()[:2])
    direction = jnp.asarray(np.random.default_rng(5).normal(size=a.shape))
    inverse = np.linalg.inv(np.asarray(a))
    analytic = -inverse @ np.asarray(direction) @ inverse
    _, tangent = jax.jvp(block_inverses, (a,), (direction,))
    np.testing.assert_allclose(tangent, analytic, rtol=0, atol=1e-10)

    def scalar(x):
        return jnp.sum(jnp.sin(block_inverses(x)))
    grad = jax.grad(scalar)(a)
    step = 1e-6
    fd = (scalar(a + step * direction) - scalar(a - step * direction)) / (2 * step)
    assert float(jnp.sum(grad * direction)) == pytest.approx(float(fd), rel=1e-6)


def test_the_block_diagonal_solve_equals_the_dense_inverse_of_the_whole_state():
    """Two stiff bodies (1 and 3 of 5) with 4 flexible-track states each, A_q and A_v
    random where a system without joints has them (each stiff body's and its states'
    rows in its own columns): ``solve`` with the blocks inverted apart equals
    (I - hg J)^-1 of the whole (q, qdot) by NumPy, and the dense path's solve."""
    n, bodies, r = 5, (1, 3), 4
    n7, k, half = 7 * n, 2, 11
    columns = tuple(c for j, b in enumerate(bodies)
                    for c in [7 * b + i for i in range(7)] + [n7 + r * j + i for i in range(r)])
    rows = n7 + r * k
    rng = np.random.default_rng(2)
    a_q, a_v = (rng.normal(scale=scale, size=(rows, k * half)) for scale in (3e3, 40.0))
    for j in range(k):  # zero outside each body's own rows and columns
        others = np.setdiff1d(np.arange(rows), np.asarray(columns).reshape(k, half)[j])
        for a in (a_q, a_v):
            a[np.ix_(others, np.arange(j * half, (j + 1) * half))] = 0.0
    jac_q, jac_v = np.zeros((rows, rows)), np.zeros((rows, rows))
    jac_q[:, list(columns)], jac_v[:, list(columns)] = a_q, a_v
    whole = np.block([[np.zeros((rows, rows)), np.eye(rows)], [jac_q, jac_v]])
    hg = 4e-4
    b_q, b_v = rng.normal(size=rows), rng.normal(size=rows)
    expected = np.linalg.solve(np.eye(2 * rows) - hg * whole, np.concatenate([b_q, b_v]))
    for block_diagonal in (True, False):
        jac = StiffJacobian(columns, jnp.asarray(a_q), jnp.asarray(a_v), k, block_diagonal)
        factored = jac.factor(hg)
        assert factored[1].shape == ((k, half, half) if block_diagonal else (22, 22))
        x_q, x_v, _ = jac.solve(hg, factored, (jnp.asarray(b_q), jnp.asarray(b_v), ()))
        np.testing.assert_allclose(np.concatenate([x_q, x_v]), expected, rtol=1e-10,
                                   atol=1e-12)


class BodyDampers(mb.AbstractLoads):
    """Stiff dampers along global x on each body, -c v, given to IMEX as body-local
    blocks."""

    c: jax.Array
    system: mb.System
    system_params: mb.SystemParams

    def __call__(self, t, q, qdot):
        n = self.system.n_bodies
        forces = jnp.zeros((n, 3)).at[:, 0].set(-self.c * qdot.reshape(n, 7)[:, 0])
        return forces, jnp.zeros((n, 3))

    def linearised(self, t, q, qdot, track=None, jacobian=True):
        n = self.system.n_bodies
        forces, torques = self(t, q, qdot)
        blocks = jnp.zeros((n, 7, 14)).at[:, 0, 7].set(-self.c)
        return forces, torques, tuple(range(n)), blocks


@pytest.mark.parametrize("joined", [False, True], ids=["jointless", "spherical"])
def test_stiff_jacobian_is_block_diagonal_exactly_when_the_system_has_no_joints(joined):
    """Two bodies with body-local stiff loads: without joints J's blocks couple no two
    bodies and ``stiff_jacobian`` marks it block-diagonal; a spherical joint couples
    them and keeps the dense inverse."""
    joints = [mb.Spherical("a", "b", (0.0, 0.0, -0.3), (0.0, 0.0, 0.2))] if joined else []
    system, params = mb.build_system(
        [mb.RigidBody("a", 3.0, (0.2, 0.3, 0.4)), mb.RigidBody("b", 1.0, (0.05, 0.1, 0.2))],
        joints=joints)
    assert system.jointless == (not joined)
    q = jnp.concatenate([jnp.zeros(3), jnp.array([1.0, 0, 0, 0]),
                         jnp.array([0.0, 0.0, -0.5]), jnp.array([1.0, 0, 0, 0])])
    _, jac = stiff_jacobian(0.0, mb.State(q, jnp.linspace(0.1, 1.4, 14), None, ()),
                            BodyDampers(jnp.asarray(500.0), system, params))
    assert jac.block_diagonal == (not joined)
    coupling = np.asarray(jac.a_v)[7:14, 0:7]  # body b's accelerations by body a's rates
    assert (np.abs(coupling).max() == 0.0) == (not joined)
