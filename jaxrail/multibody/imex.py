"""A linearly implicit IMEX integrator for eq. (19) with stiff body loads.

The wheel-rail creep forces act on each wheelset like a damper of time constant
about 0.4 ms at 18.3 m/s (the spin against the longitudinal creep), far shorter than
the motion of interest: an explicit method is held to steps of about 0.3 ms by
stability. :class:`IMEX` treats those loads implicitly through their Jacobian and
everything else explicitly, so its steps follow accuracy instead.

Method: an additive Runge-Kutta method (Kennedy and Carpenter's KenCarp3/4/5, the
tableaus diffrax ships) on the exact split

    f(y) = [f(y) - J (y - y0)] + J (y - y0),

explicit in the first term and implicit (ESDIRK, L-stable) in the second, with J
fixed over the step (evaluated at its start y0, or kept from an earlier step). The
split is exact, so the method keeps its order whatever J is; J decides only which
modes stay stable at long steps. The implicit term is linear, so each stage is one
solve with I - h gamma J (the same matrix for every stage, inverted once per step)
and no Newton iteration. Per step: s right-hand sides (s = 4, 6, 8 stages for
KenCarp3, 4, 5) and, every ``jacobian_every`` accepted steps, one Jacobian of the
stiff loads. A step whose matrix I - h gamma J is not finite or singular ends the
run with diffrax's result ``singular`` (the status "failed: singular implicit solve"
of a simulation).

Because the split is exact, J may be kept across steps (a W-method in the sense of
Steihaug and Wolfbrandt: the order does not depend on J). A spinning wheelset's Euler
parameters turn by about 0.04 rad per millisecond, and J in those coordinates turns
with them: a J one step old is 2 % off and doubles the steps the controller needs.
So a kept J is carried to each step's start by each stiff body's turn about its own
y axis since (:meth:`StiffJacobian.turned`, exact for a body of revolution such as a
wheelset); what then still changes J (the contact's bounce, flange contact) is slow
enough for a new J every 8 accepted steps (docs/simulation.md). A rejected attempt's
solver state is dropped, so its retry evaluates J again where the attempt did;
:class:`JacobianCounter` counts them.

J = [[0, I], [A_q, A_v]] with y = (q, qdot): the accelerations' dependence on the
positions and velocities of the bodies whose loads are stiff, through those loads
only (the term's ``linearised``, e.g. :meth:`jaxrail.vehicles.VehicleLoads.linearised`).
A_q, A_v have 7 columns per such body, so the step inverts a (7 k, 7 k) matrix
(28 x 28 for four wheelsets) instead of the whole state's. In a system without joints
each body's accelerations respond to its own loads only, so that matrix is
block-diagonal and the step inverts k (7, 7) blocks instead, in plain operations
(:mod:`.block_inverse`: no LAPACK call in the integration loop). Loads with no stiff bodies
(:class:`~jaxrail.multibody.loads.AbstractLoads`' default ``linearised``, e.g.
:class:`~jaxrail.multibody.loads.SystemLoads`) give J = 0, and the method is the
explicit KenCarp tableau.
"""

from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._when import computed_when, zeros_of
from .equations import acceleration_response, accelerations, element_rates
from .loads import AbstractLoads, FixedLoads
from .projection import project_state
from .quaternion import multiply
from .state import State
from .stiff_matrix import StiffJacobian

METHODS = {"KenCarp3": 3, "KenCarp4": 4, "KenCarp5": 5}


def stiff_jacobian(t, y: State, loads: AbstractLoads, jacobian=True):
    """(f(y) packed (:func:`_pack`), :class:`StiffJacobian`) at the :class:`State` y
    under ``loads`` (the system, its parameters and the loads on its bodies).

    ``jacobian``: a bool, which may be traced, or a tuple of them that must all hold
    (:func:`~jaxrail.multibody._when.computed_when`): where it is False, J's entries are
    zeros, not computed, so that a loop of stages of which only the first needs J
    evaluates the loads at one place (:class:`IMEX`). It is passed on as
    ``loads.linearised(..., jacobian=...)``, which may ignore it and return its blocks
    anyway.

    ``loads.linearised(t, q, qdot)`` returns ``(forces, torques, bodies, blocks)``:
    the loads as ``loads(t, q, qdot)`` does, the indices of the bodies with stiff
    loads (static; none: J = 0) and ``blocks`` (k, 7, 14), the derivative of each such
    body's generalized load with respect to its own (q, qdot) (7 + 7 coordinates). The
    contact is evaluated once for both.

    With a flexible track ``y.track = (x, xdot)`` (second order, (k, ...) per stiff
    body), ``loads.linearised(t, q, qdot, track)`` returns ``(forces, torques,
    track_dot, bodies, blocks, state_rows)``: ``blocks`` (k, 7, 2 (7 + r)) and
    ``state_rows`` (k, r, 2 (7 + r)) the derivatives of each body's load and of its r
    states' accelerations by its (q, x, qdot, xdot). The force elements' internal
    states are explicit: J is zero on them."""
    q, qdot, track = y.q, y.qdot, y.track
    system, params = loads.system, loads.system_params
    if track is None:
        forces, torques, bodies, blocks = loads.linearised(t, q, qdot, jacobian=jacobian)
        state_rows = jnp.zeros(blocks.shape[:1] + (0, 14), dtype=q.dtype)
        f_track = None
    else:
        forces, torques, f_track, bodies, blocks, state_rows = loads.linearised(
            t, q, qdot, track, jacobian=jacobian)
    qddot, _ = accelerations(system, params, t, q, qdot, FixedLoads(forces, torques),
                             y.elements)
    f_elements = element_rates(system, params, q, qdot, y.elements)
    k, r = len(bodies), state_rows.shape[1]
    n7 = q.shape[0]

    def response_of_loads():  # (7n + k r, k, m)
        response = acceleration_response(system, params, q, qdot, bodies, blocks)
        if r:  # a body's states respond to its own coordinates only
            own = jnp.einsum("jl,jrm->jrlm", jnp.eye(k, dtype=q.dtype), state_rows)
            response = jnp.concatenate([response, own.reshape(k * r, k, -1)], axis=0)
        return response

    response = computed_when(jacobian, response_of_loads)
    half = 7 + r
    columns = tuple([7 * b + i for i in range(7)] + [n7 + r * j + i for i in range(r)]
                    for j, b in enumerate(bodies))
    columns = tuple(c for block in columns for c in block)
    a_q = response[:, :, :half].reshape(n7 + k * r, -1)
    a_v = response[:, :, half:].reshape(n7 + k * r, -1)
    f = _pack(State(qdot, qddot, f_track, f_elements))
    return f, StiffJacobian(columns, a_q, a_v, k, system.jointless and k > 0)


def _euler(jac, positions):
    """The Euler parameters (k, 4) of J's stiff bodies in ``positions``."""
    return positions[jac.euler_index()]


def _twist(then, now):
    """(k, 4): the part about the body y axis (the swing-twist split) of each body's
    turn from Euler parameters ``then`` to ``now`` (k, 4), conj(then) * now."""
    conj = then * jnp.asarray([1.0, -1.0, -1.0, -1.0])
    r = jax.vmap(multiply)(conj, now)
    t = jnp.stack([r[:, 0], jnp.zeros_like(r[:, 0]), r[:, 2], jnp.zeros_like(r[:, 0])], -1)
    return t / jnp.linalg.norm(t, axis=1, keepdims=True)


def _pack(y: State):
    """A :class:`State` as (positions, velocities, elements): the track's x raveled
    after q, its xdot after qdot, and the force elements' internal states (explicit)."""
    if y.track is None:
        return y.q, y.qdot, y.elements
    x, xdot = y.track
    return (jnp.concatenate([y.q, x.ravel()]), jnp.concatenate([y.qdot, xdot.ravel()]),
            y.elements)


def _unpack(like: State, packed) -> State:
    """The inverse of :func:`_pack` for states shaped as ``like``."""
    positions, velocities, elements = packed
    if like.track is None:
        return State(positions, velocities, None, elements)
    n, shape = like.q.shape[0], like.track[0].shape
    return State(positions[:n], velocities[:n],
                 (positions[n:].reshape(shape), velocities[n:].reshape(shape)), elements)


def _dense_info(h, y0, y1, f0):
    """Cubic Hermite data for output between steps, of packed states: q from q and
    qdot at both ends (exact derivatives: a spinning wheelset's Euler parameters stay
    on their sphere to O(h^4), where linear interpolation shortens them by theta^2 / 32
    and moves its wheel points by tens of micrometres), qdot from the parabola through
    qdot0, qdot1 with slope qddot0 (``f0`` = (qdot0, qddot0, zdot0)), the elements'
    internal states linear between the ends."""
    (q0, v0, z0), (q1, v1, z1), (_, a0, _) = y0, y1, f0
    dz = jax.tree.map(jnp.subtract, z1, z0)
    k0 = (h * v0, h * a0, dz)
    k1 = (h * v1, 2.0 * (v1 - v0) - h * a0, dz)
    return dict(y0=y0, y1=y1, k0=k0, k1=k1)


def _weighted(rows, stacked):
    """sum_j rows[j] * stacked[j] over the leading (stage) axis of each leaf."""
    return jax.tree.map(lambda x: jnp.tensordot(rows, x, axes=1), stacked)


def _tableau(method):
    """(c (s,), explicit a (s, s), implicit a (s, s), b (s,), b - b_embedded (s,),
    gamma) of a KenCarp method as numpy arrays (a strictly lower triangular; the
    implicit diagonal is gamma from the second stage on)."""
    explicit, implicit = getattr(diffrax, method).tableau.tableaus
    s = len(explicit.b_sol)
    a_e, a_i = np.zeros((s, s)), np.zeros((s, s))
    for i in range(1, s):
        a_e[i, :i] = explicit.a_lower[i - 1]
        a_i[i, :i] = implicit.a_lower[i - 1]
    c = np.concatenate([[0.0], np.asarray(explicit.c)])
    return (c, a_e, a_i, np.asarray(explicit.b_sol), np.asarray(explicit.b_error),
            float(implicit.a_diagonal[1]))


def check_jacobian_every(value, label="jacobian_every"):
    """ValueError naming ``label`` unless ``value`` is an integer >= 1 (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{label} must be an integer >= 1, got {value!r}")


def refreshes(age, every):
    """Whether a step evaluates a new load Jacobian, its J being ``age`` accepted steps
    old (:class:`IMEX`'s ``jacobian_every``: ``every``)."""
    return age >= every


def aged(age, refreshed):
    """The age of J after an accepted step that did (or did not) refresh it."""
    return jnp.where(refreshed, 1, age + 1).astype(jnp.int32)


class JacobianCounter(diffrax.AbstractStepSizeController):
    """``controller`` counting the load Jacobians of an :class:`IMEX` that evaluates one
    every ``every`` accepted steps, rejected attempts included (its state's last item).

    A rejected attempt's solver state is dropped, so the solver cannot count; the
    controller sees every attempt and whether it was kept, and follows the same age
    (:func:`refreshes`, :func:`aged`)."""

    controller: diffrax.AbstractStepSizeController
    every: int = eqx.field(static=True)

    def wrap(self, direction):
        return JacobianCounter(self.controller.wrap(direction), self.every)

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        tnext, state = self.controller.init(terms, t0, t1, y0, dt0, args, func, error_order)
        return tnext, (state, jnp.asarray(self.every, jnp.int32), jnp.asarray(0, jnp.int32))

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order,
                        controller_state):
        state, age, count = controller_state
        refreshed = refreshes(age, self.every)
        keep, tprev, tnext, jump, state, result = self.controller.adapt_step_size(
            t0, t1, y0, y1_candidate, args, y_error, error_order, state)
        age = jnp.where(keep, aged(age, refreshed), age)
        return keep, tprev, tnext, jump, (state, age, count + refreshed), result


class IMEX(diffrax.AbstractAdaptiveSolver):
    """The linearly implicit additive Runge-Kutta method of the module docstring for
    :func:`jaxrail.multibody.rhs` (``args``: the term, an
    :class:`~jaxrail.multibody.loads.AbstractLoads`): the stiff loads of its
    ``linearised`` implicit, the rest explicit. ``method``: one of
    :data:`METHODS` (order 3, 4 or 5, with an embedded solution one order lower for
    the step-size controller). ``jacobian_every``: a new load Jacobian every this many
    accepted steps, kept and turned with the stiff bodies in between (module
    docstring; 1, the default here: every step, for bodies that are not bodies of
    revolution about y). Output between steps by cubic Hermite interpolation.
    The stages run in a loop, the first with the loads' Jacobian and the inverse of
    I - h gamma J under a ``lax.cond``, so that the loads are compiled at one place."""

    method: str = eqx.field(static=True, default="KenCarp5")
    jacobian_every: int = eqx.field(static=True, default=1)

    term_structure: ClassVar = diffrax.AbstractTerm
    interpolation_cls: ClassVar = diffrax.ThirdOrderHermitePolynomialInterpolation

    def __check_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"IMEX method must be one of {sorted(METHODS)}, got "
                             f"{self.method!r}")
        check_jacobian_every(self.jacobian_every, "IMEX jacobian_every")

    @property
    def stages(self) -> int:
        """Right-hand sides per step: the stages of the tableau."""
        return int(_tableau(self.method)[3].size)

    def order(self, terms):
        return METHODS[self.method]

    def error_order(self, terms):
        return METHODS[self.method]

    def init(self, terms, t0, t1, y0, args):
        """None, or with ``jacobian_every`` > 1 (J, its age in accepted steps, the stiff
        bodies' Euler parameters where J holds): a zero J as old as forces a new one."""
        if self.jacobian_every == 1:
            return None
        like = y0

        def jacobian_at(y):
            return stiff_jacobian(t0, _unpack(like, y), args)[1]
        jac = zeros_of(jax.eval_shape(jacobian_at, _pack(y0)))
        return jac, jnp.asarray(self.jacobian_every, jnp.int32), _euler(jac, _pack(y0)[0])

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del made_jump
        c, a_e, a_i, b, b_error, gamma = _tableau(self.method)
        s = b.size
        h = t1 - t0
        hg = h * gamma
        like, y0 = y0, _pack(y0)

        def evaluate(i, y):
            """(f(y), J) at stage i: J (computed at the first stage only) at y0."""
            return stiff_jacobian(t0 + c[i] * h, _unpack(like, y), args,
                                  jacobian=(i == 0, refresh))

        # per stage i: rows i and s + i hold the explicit part f(Y_i) - J (Y_i - y0) and
        # the implicit part J (Y_i - y0) (zero at the first stage, Y_0 = y0), so that each
        # stage's right-hand side is one weighted sum over both tableaus. The first stage
        # runs in the loop too, so that the loads are evaluated at one place in the
        # program: it also gives J and the inverse of I - hg J, which the later stages use.
        # A J kept from an earlier step is carried to y0 by the wheelsets' spin since. The
        # first stage tests its index before ``refresh``: under vmap ``refresh`` is
        # batched, and a cond on it alone would run the Jacobian at every stage.
        if solver_state is None:
            refresh, age = True, None
        else:
            kept, age, then = solver_state
            refresh = refreshes(age, self.jacobian_every)
        f_like, jac_like = jax.eval_shape(lambda y: evaluate(0, y), y0)
        parts = jax.tree.map(lambda x: jnp.zeros((2 * s,) + x.shape, x.dtype), f_like)
        jac = (zeros_of(jac_like) if solver_state is None
               else kept.turned(_twist(then, _euler(kept, y0[0]))))
        factored = zeros_of(jax.eval_shape(jac.factor, hg))  # the first stage's z is 0 with it
        rows = jnp.asarray(np.concatenate([a_e, a_i], axis=1))  # (s, 2 s)
        c = jnp.asarray(c)

        def stage(i, carry):
            parts, jac, factored = carry
            z = jac.solve(hg, factored, jax.tree.map(lambda d: h * d,
                                                     _weighted(rows[i], parts)))
            f, jac_here = evaluate(i, jax.tree.map(jnp.add, y0, z))
            # J (Y_i - y0) with the J the stage came in with: zero at the first stage,
            # whatever J it computes (a J that is not finite must not reach f0)
            stiff = jac.matvec(z)
            first = i == 0
            take = first & refresh
            jac = jax.tree.map(lambda new, old: jnp.where(take, new, old), jac_here, jac)
            factored = jax.lax.cond(first, lambda: jac.factor(hg), lambda: factored)
            parts = jax.tree.map(lambda stacked, x, w: stacked.at[i].set(x - w).at[s + i].set(w),
                                 parts, f, stiff)
            return parts, jac, factored

        parts, jac, factored = jax.lax.fori_loop(0, s, stage, (parts, jac, factored))
        f0 = jax.tree.map(lambda x: x[0], parts)
        both = lambda weights: jnp.asarray(np.concatenate([weights, weights]))  # noqa: E731
        y1 = jax.tree.map(lambda y, d: y + h * d, y0, _weighted(both(b), parts))
        # At about 1 ms Baumgarte's feedback (10 1/s) lets the joints drift by about
        # 1 um over the paper's curve (Tsit5's shorter steps: nm); one projection per
        # step keeps them at the explicit method's level.
        y1 = _unpack(like, y1)
        y1 = y1.with_bodies(*project_state(args.system, args.system_params, y1.q,
                                           y1.qdot))
        error = _unpack(like, jax.tree.map(lambda d: h * d,
                                           _weighted(both(b_error), parts)))
        # An inverse that is not finite (a non-finite or singular I - h gamma J) ends
        # the run: the step is kept with zero error so that the step-size controller
        # cannot hide it by shrinking the step without end, its state is the step's
        # start, and the result says why.
        solved = jac.factored_ok(factored)
        y1 = jax.tree.map(lambda new, old: jnp.where(solved, new, old), y1, like)
        error = jax.tree.map(lambda e: jnp.where(solved, e, 0.0), error)
        dense = {key: _unpack(like, value)
                 for key, value in _dense_info(h, y0, _pack(y1), f0).items()}
        result = diffrax.RESULTS.where(solved, diffrax.RESULTS.successful,
                                       diffrax.RESULTS.singular)
        state = None if solver_state is None else (jac, aged(age, refresh), _euler(jac, y0[0]))
        return y1, error, dense, state, result

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)
