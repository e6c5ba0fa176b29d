"""Diagnostics of a multibody system's state: constraint violation, energies, power
and angular momentum (each one compiled program, `eqx.filter_jit`)."""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from . import bodies as bd
from . import forces as fc
from .axle_frame import ElementView
from .equations import constraints
from .system import System, SystemParams, _element_states


@eqx.filter_jit
def constraint_violation(system: System, params: SystemParams, q, qdot):
    """(max |Phi|, max |Phidot|) over all constraint rows (m or -, m/s or 1/s)."""
    phi, _, phidot, _ = constraints(system, params, q, qdot)
    return jnp.max(jnp.abs(phi)), jnp.max(jnp.abs(phidot))


@eqx.filter_jit
def kinetic_energy(system: System, params: SystemParams, q, qdot) -> Array:
    """Total kinetic energy [J]."""
    _, p = bd.split_coordinates(q)
    rdot, pdot = bd.split_coordinates(qdot)
    b = params.bodies
    return jnp.sum(jax.vmap(bd.body_kinetic_energy)(b.mass, b.inertia, p, rdot, pdot))


@eqx.filter_jit
def potential_energy(system: System, params: SystemParams, q, elements=None) -> Array:
    """Gravity (-m g . r) plus the energy stored in the force elements [J];
    ``elements``: their internal states, where the system has such elements."""
    r, _ = bd.split_coordinates(q)
    v = -jnp.sum(params.bodies.mass * (r @ params.gravity))
    seen = ElementView(system.axle_bodies, q).q  # the coordinates the elements see
    for g in system.force_groups:
        v = v + fc.element_potential(g.kind, g.body_i, g.body_j, params.forces[g.kind], seen,
                                     _element_states(system, elements, g.kind))
    return v


@eqx.filter_jit
def dissipated_power(system: System, params: SystemParams, q, qdot, elements=None) -> Array:
    """The power [W] the force elements dissipate at this state (>= 0)."""
    view = ElementView(system.axle_bodies, q, qdot)
    return sum((fc.element_power(g.kind, g.body_i, g.body_j, params.forces[g.kind], view.q,
                                 view.qdot,
                                 _element_states(system, elements, g.kind))
                for g in system.force_groups), jnp.zeros((), dtype=jnp.float64))


@eqx.filter_jit
def angular_momentum(system: System, params: SystemParams, q, qdot) -> Array:
    """Total angular momentum (3,) [kg m^2/s] about the global origin, global frame."""
    r, p = bd.split_coordinates(q)
    rdot, pdot = bd.split_coordinates(qdot)
    b = params.bodies
    each = jax.vmap(bd.body_angular_momentum)(b.mass, b.inertia, r, p, rdot, pdot)
    return jnp.sum(each, axis=0)
