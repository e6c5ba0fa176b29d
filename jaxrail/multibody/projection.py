"""States moved onto the constraints of a multibody system: the projection IMEX
applies after each step and consistent initial conditions."""

import equinox as eqx
import jax
import jax.numpy as jnp

from .equations import constraints
from .system import System, SystemParams


def _minimum_norm_solution(phi_q, rhs, diagonal=False):
    """x of least Euclidean norm with ``phi_q x = rhs``: ``phi_q^T (phi_q phi_q^T)^-1 rhs``
    (``phi_q`` of full row rank, as the equations of motion need anyway).

    The normal equations take one LU solve of an m x m matrix, cheaper than the SVD
    of ``pinv``, with the same result. ``diagonal`` (static): the rows act on disjoint
    coordinates (a system without joints: each body's normalisation on its own Euler
    parameters), so phi_q phi_q^T is diagonal and the solve a division (no LAPACK call
    in the integration loop)."""
    if diagonal:
        return phi_q.T @ (rhs / jnp.sum(phi_q * phi_q, axis=1))
    return phi_q.T @ jnp.linalg.solve(phi_q @ phi_q.T, rhs)


def project_state(system: System, params: SystemParams, q, qdot):
    """(q, qdot) moved onto the constraints by one Gauss-Newton step, q - Phi_q^+ Phi,
    then qdot projected onto Phi_q qdot = 0 (minimum-norm corrections; for the small
    drift an integration step leaves, the second step would change q by about
    |Phi|^2)."""
    phi, phi_q, _, _ = constraints(system, params, q, qdot)
    q = q - _minimum_norm_solution(phi_q, phi, system.jointless)
    _, phi_q, _, _ = constraints(system, params, q, qdot)
    return q, qdot - _minimum_norm_solution(phi_q, phi_q @ qdot, system.jointless)


@eqx.filter_jit
def consistent_initial_conditions(system: System, params: SystemParams, q0, qdot0,
                                  iterations: int = 12):
    """(q, qdot) with Phi(q) = 0 and Phi_q qdot = 0, nearest to (q0, qdot0).

    A fixed number of Gauss-Newton steps with the minimum-norm correction
    q <- q - Phi_q^+ Phi, then the Euclidean projection of qdot0 onto the null
    space of Phi_q (coordinates and velocities mixed without weights, so give a good
    guess for the coordinates you care about).
    """
    zeros = jnp.zeros_like(jnp.asarray(qdot0, dtype=jnp.float64))

    def step(_, q):
        phi, phi_q, _, _ = constraints(system, params, q, zeros)
        return q - _minimum_norm_solution(phi_q, phi, system.jointless)

    q = jax.lax.fori_loop(0, iterations, step, jnp.asarray(q0, dtype=jnp.float64))
    _, phi_q, _, _ = constraints(system, params, q, zeros)
    qdot0 = jnp.asarray(qdot0, dtype=jnp.float64)
    return q, qdot0 - _minimum_norm_solution(phi_q, phi_q @ qdot0, system.jointless)
