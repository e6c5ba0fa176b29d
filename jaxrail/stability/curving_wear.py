"""The wear number of each wheel in steady curving, and its gradient in named vehicle
parameters by implicit differentiation of the steady curving state.

The wear number of a wheel is ``T gamma = sum over its patches of |T_x xi_x| + |T_y
xi_y|`` [N] (creep forces [N] times creepages [-], the spin left out), as the Monte Carlo
table reports it per run (:func:`jaxrail.montecarlo.summary.wear_number`), here at the
steady curving state ``u*(p)`` of :mod:`jaxrail.stability.curving`, which solves
``R(u*, p) = 0`` (every body at rest in the turning frame, the joints held).

By the implicit function theorem ``du*/dp = -R_u^+ R_p``, with the same minimum-norm
least-squares inverse as Newton's steps (:func:`~jaxrail.stability.curving.newton_step`):
the directions it leaves out (the whole vehicle turned about the curve's axis, a wheel
turned about its axle) change no wear number. So

    dW/dp = W_p + W_u du*/dp,

``R_p`` and ``W_p`` by forward-mode differentiation in the parameters (the rest pose
the unknowns are measured from moves with them too), ``W_u`` by reverse mode, and
``R_u`` the Jacobian Newton's method already compiled.

A Maxwell damper (a yaw damper) carries no force in the steady state, so its damping
has no effect here: the wear it influences is that of curve entry (transitions), not
of the steady arc.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..vehicles.loads import contact_loads
from ..vehicles.parameters import (check_contact_follows, get_values, parameter,
                                   set_values_and_track)
from .curving import (CurvingState, SteadyCurving, curving_residual, curving_setup,
                      curving_state, held_body, newton_step)


def wheel_wear_numbers(patch_forces) -> jax.Array:
    """``T gamma`` (W, 2) [N] of every wheel (left, right) from its patch forces
    ``(W, 2, P)`` (:class:`~jaxrail.vehicles.wheel_rail.PatchForces`); a patch without
    load (its creep forces zero) adds nothing."""
    terms = (jnp.abs(patch_forces.creep_force_x * patch_forces.creepage_x)
             + jnp.abs(patch_forces.creep_force_y * patch_forces.creepage_y))
    loaded = patch_forces.normal_force > 0.0
    return jnp.sum(jnp.where(loaded, terms, 0.0), axis=-1)


@dataclasses.dataclass(frozen=True)
class CurvingWearPoint:
    """The wear numbers at one steady curving state (host values).

    Fields: state (:class:`~jaxrail.stability.curving.CurvingState`), wear_number_n (W,
    2) [N] (leading wheelset first; left, right wheel), gradient ``{name: (W, 2)}`` [N
    per unit of the parameter]."""

    state: CurvingState
    wear_number_n: np.ndarray
    gradient: dict


class CurvingWear:
    """Wear numbers in the steady curving states of a
    :class:`~jaxrail.stability.curving.SteadyCurving` (whose compiled programs it
    shares) and their gradient in the named parameters ``names``
    (:mod:`jaxrail.vehicles.parameters`):
    ``CurvingWear(curving, names)(speed, params=None, start=None)`` ->
    :class:`CurvingWearPoint`. ``start``: as :class:`SteadyCurving`'s. ``measure``:
    what is differentiated instead of the wear numbers, ``measure(patch_forces, params,
    speed)`` -> (W, 2) (e.g. :func:`jaxrail.wear.steady.wear_per_km`'s); the point's
    ``wear_number_n`` then holds its values."""

    def __init__(self, curving: SteadyCurving, names=(), measure=None):
        self.names = names = tuple(names)
        self.curving = curving
        vehicle, params, track = curving.vehicle, curving.params, curving.track
        for name in names:
            parameter(name, vehicle, params)
        check_contact_follows(names, curving.model.name)
        self.vehicle, self.params, self.track = vehicle, params, track
        model, body = curving.model, held_body(vehicle)

        def residual_and_wear(u, x, params, speed):
            params, moved = set_values_and_track(vehicle, params, track, names, x)
            base, frame_rate, centre, _ = curving_setup(vehicle, params, moved, speed, model)
            r = curving_residual(u, vehicle, params, moved, base, frame_rate, centre, body,
                                 model)
            q, qdot = curving_state(u, vehicle, base, frame_rate, centre)
            forces = contact_loads(vehicle, params, moved, q, qdot, model)[3]
            wear = (wheel_wear_numbers(forces) if measure is None
                    else measure(forces, params, speed))
            return r, wear

        def partials(u, x, params, speed):
            wear_of = lambda u: residual_and_wear(u, x, params, speed)[1]  # noqa: E731
            wear, pullback = jax.vjp(wear_of, u)
            w_u = jax.vmap(lambda e: pullback(e.reshape(wear.shape))[0])(
                jnp.eye(wear.size, dtype=u.dtype))
            r_x, w_x = jax.jacfwd(lambda x: residual_and_wear(u, x, params, speed))(x)
            return wear, w_u, r_x, w_x

        self._partials = eqx.filter_jit(partials)

    def __call__(self, speed, params=None, start=None) -> CurvingWearPoint:
        params = self.params if params is None else params
        state = self.curving(speed, params, start=start)
        u = jnp.asarray(state.unknowns)
        x = get_values(self.vehicle, params, self.names, self.track)
        speed = jnp.asarray(state.speed, jnp.float64)
        wear, w_u, r_x, w_x = (np.asarray(a) for a in self._partials(u, x, params, speed))
        setup_values = self.curving._setup(params, self.track, speed)
        r_u = np.asarray(self.curving._linearised(u, params, self.track, setup_values)[0])
        shape = wear.shape
        gradient = {}
        for k, name in enumerate(self.names):
            du = newton_step(r_u, r_x[:, k])  # -R_u^+ R_p
            gradient[name] = w_x[..., k] + (w_u @ du).reshape(shape)
        return CurvingWearPoint(state, wear, gradient)
