"""The load Jacobian J of :class:`~jaxrail.multibody.imex.IMEX` and the solves with
I - h gamma J it takes (module docstring of :mod:`.imex`)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .block_inverse import block_inverses


class StiffJacobian(eqx.Module):
    """J = [[0, I], [A_q, A_v]] of y = (q, qdot) with A_q, A_v nonzero only in the
    ``columns`` (the coordinates of the bodies with stiff loads).

    Fields: columns (c,) static indices into q; a_q, a_v (7 n, c): accelerations per
    unit change of those coordinates [1/s^2] and velocities [1/s]; bodies (static): the
    number k of stiff bodies, whose columns come body by body, each body's 7
    coordinates first (its Euler parameters at 3 to 6); block_diagonal (static): whether
    each stiff body's rows of A_q, A_v are zero in the other stiff bodies' columns (a
    system without joints), so that I - hg J inverts block by block."""

    columns: tuple[int, ...] = eqx.field(static=True)
    a_q: jax.Array
    a_v: jax.Array
    bodies: int = eqx.field(static=True, default=0)
    block_diagonal: bool = eqx.field(static=True, default=False)

    def euler_index(self):
        """(k, 4) indices into q of the stiff bodies' Euler parameters."""
        k = self.bodies
        if k == 0:
            return np.zeros((0, 4), dtype=int)
        return np.asarray(self.columns, dtype=int).reshape(k, -1)[:, 3:7]

    def matvec(self, x):
        """J x for x = (x_q, x_v, x_z) (x_z: explicit states, J's rows and columns
        zero)."""
        x_q, x_v, x_z = x
        index = np.asarray(self.columns, dtype=int)
        return (x_v, self.a_q @ x_q[index] + self.a_v @ x_v[index],
                jax.tree.map(jnp.zeros_like, x_z))

    def factor(self, hg):
        """The pieces of (I - hg J)^-1: with B = hg A_v + hg^2 A_q (columns c only),
        x_v = r + B x_c and (I - B_cc) x_c = r_c, r = b_v + hg A_q b_q[c]; returns B
        and the inverse (I - B_cc)^-1, or with ``block_diagonal`` the inverses of its k
        diagonal blocks (k, c / k, c / k). One inversion per step, so that each stage's
        solve is a product (a factorisation would take two LAPACK triangular solves per
        stage inside the integration loop)."""
        index = np.asarray(self.columns, dtype=int)
        b = hg * self.a_v + hg * hg * self.a_q
        if self.block_diagonal:
            k, size = self.bodies, index.size // self.bodies
            blocks = b.reshape(-1, k, size)[index.reshape(k, size), np.arange(k)[:, None], :]
            return b, block_inverses(jnp.eye(size, dtype=b.dtype) - blocks)
        inverse = jnp.linalg.inv(jnp.eye(index.size, dtype=b.dtype) - b[index])
        return b, inverse

    @staticmethod
    def factored_ok(factored):
        """Whether :meth:`factor`'s inverse is finite (a scalar bool): a matrix that is
        not finite or is singular (a zero pivot divides by zero) gives one that is not."""
        return jnp.all(jnp.isfinite(factored[1]))

    def turned(self, turns):
        """This J carried to a state where each stiff body is turned about its own y
        axis by ``turns`` (k, 4) (Euler parameters, body frame: p -> p * turn): J' = S J
        S^-1 with S the right product by the turn on each body's Euler parameters and
        their rates. Exact for bodies of revolution about y under loads that do not
        depend on the turn (wheelsets)."""
        k = self.bodies
        if k == 0:
            return self
        half = len(self.columns) // k
        index = self.euler_index()
        r0, r1, r2, r3 = (turns[:, i] for i in range(4))
        right = jnp.stack([jnp.stack([r0, -r1, -r2, -r3], -1), jnp.stack([r1, r0, r3, -r2], -1),
                           jnp.stack([r2, -r3, r0, r1], -1), jnp.stack([r3, r2, -r1, r0], -1)],
                          axis=1)  # (k, 4, 4)
        n = self.a_q.shape[0]
        # row i of the result: row i of a, or for the stiff bodies' Euler parameters row
        # n + j of [a; turned rows]; one gather with constant indices
        source = np.arange(n)
        source[index.ravel()] = n + np.arange(4 * k)

        def carried(a):
            # 4 x 4 products as broadcast sums: XLA:CPU runs a batched dot this small as
            # a library call per batch, several times slower than one loop fusion
            a3 = a.reshape(n, k, half)
            e = jnp.sum(a3[:, :, None, 3:7] * right[None], axis=-1)
            a = jnp.concatenate([a3[:, :, :3], e, a3[:, :, 7:]], axis=-1).reshape(n, -1)
            rows = a[index.ravel()].reshape(k, 1, 4, -1)
            turned = jnp.sum(right[..., None] * rows, axis=2).reshape(4 * k, -1)
            return jnp.concatenate([a, turned])[source]
        return StiffJacobian(self.columns, carried(self.a_q), carried(self.a_v), k,
                             self.block_diagonal)

    def solve(self, hg, factored, rhs_):
        """x = (I - hg J)^-1 rhs_ for rhs_ = (b_q, b_v, b_z), with ``factored`` from
        :meth:`factor` for the same hg (x_z = b_z: J is zero on the explicit states)."""
        b_q, b_v, b_z = rhs_
        b, inverse = factored
        index = np.asarray(self.columns, dtype=int)
        r = b_v + hg * (self.a_q @ b_q[index])
        if self.block_diagonal:
            x_c = jnp.einsum("kij,kj->ki", inverse,
                             r[index].reshape(self.bodies, -1)).reshape(-1)
        else:
            x_c = inverse @ r[index]
        x_v = r + b @ x_c
        return b_q + hg * x_v, x_v, b_z
