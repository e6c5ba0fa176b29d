"""The one term of a multibody solve: a system, its parameters and the loads on it.

:class:`AbstractLoads` is what :func:`~jaxrail.multibody.rhs`,
:func:`~jaxrail.multibody.simulate_system` and :class:`~jaxrail.multibody.imex.IMEX`
take (diffrax's ``args``): the :class:`System`, its :class:`SystemParams` and the loads
on its bodies beyond gravity and its force elements, so that the parameters enter the
solve once. :class:`SystemLoads` is the plain one (no loads, or those of a hook, and
none stiff); :class:`jaxrail.vehicles.VehicleLoads` adds the wheel-rail contact.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp

from .system import System, SystemParams


class AbstractLoads(eqx.Module):
    """A system with the loads on its bodies: the term of eq. (19)'s solve.

    Attributes:
        system: the :class:`System` (static structure).
        system_params: its :class:`SystemParams` (traced).

    Methods (forces and torques (n, 3) [N, N m], global, at the body centres):
        __call__(t, q, qdot): ``(forces, torques)``, the ``external`` hook of
            :func:`~jaxrail.multibody.accelerations`.
        coupled(t, q, qdot, track): on a flexible track, whose rails ``track`` are
            integrated with the bodies (``State.track``): ``(forces, torques,
            track_dot)``, ``track_dot`` of ``track``'s structure.
        linearised(t, q, qdot, track=None, jacobian=True): the loads with the
            Jacobian of their stiff part, which IMEX treats implicitly
            (:func:`~jaxrail.multibody.imex.stiff_jacobian` gives the returns).

    The defaults here: no flexible track (``coupled`` and ``linearised`` with a track
    raise ValueError) and no stiff loads (``linearised``: the loads of ``__call__``,
    no stiff bodies, so IMEX's J = 0 and its method is the explicit tableau).
    """

    system: eqx.AbstractVar[System]
    system_params: eqx.AbstractVar[SystemParams]

    @abc.abstractmethod
    def __call__(self, t, q, qdot):
        """``(forces, torques)`` (n, 3) at time t [s] and state (q, qdot) (7 n,)."""

    def coupled(self, t, q, qdot, track):
        raise ValueError(f"{type(self).__name__} has no flexible track: a State with rails "
                         "(State.track) needs loads that integrate them, e.g. VehicleLoads "
                         "on a track with a support")

    def linearised(self, t, q, qdot, track=None, jacobian=True):
        """``(forces, torques, (), blocks (0, 7, 14))``: the loads of ``__call__`` and no
        body with stiff loads (``jacobian`` does not matter)."""
        if track is not None:
            raise ValueError(f"{type(self).__name__} has no flexible track to linearise: "
                             "IMEX on one needs loads whose linearised() takes the rails, "
                             "e.g. VehicleLoads")
        forces, torques = self(t, q, qdot)
        return forces, torques, (), jnp.zeros((0, 7, 14), dtype=q.dtype)


class SystemLoads(AbstractLoads):
    """A system under gravity and its force elements only, or also under the loads of
    ``external``, a callable ``(t, q, qdot) -> (forces, torques)`` (n, 3) [N, N m]
    (global, at the body centres; an equinox Module carrying its own parameters keeps
    them differentiable). None of them stiff (IMEX's J = 0)."""

    system: System
    system_params: SystemParams
    external: object = None

    def __call__(self, t, q, qdot):
        """The loads of ``external``, or zeros without one."""
        if self.external is None:
            zeros = jnp.zeros((self.system.n_bodies, 3), dtype=q.dtype)
            return zeros, zeros
        return self.external(t, q, qdot)


class FixedLoads(eqx.Module):
    """An ``external`` hook that returns loads computed beforehand: forces and torques
    (n, 3) [N, N m], global."""

    forces: jax.Array
    torques: jax.Array

    def __call__(self, t, q, qdot):
        return self.forces, self.torques
