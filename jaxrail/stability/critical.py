"""The linear critical speed: where the least damped hunting mode's real part crosses
zero, found by a root solve on the speed, and its gradient with respect to named
vehicle parameters by implicit differentiation of that crossing.

``g(V, p) = Re lambda_h(V, p)``, lambda_h the hunting eigenvalue of the state matrix
``A(V, p)`` (:mod:`jaxrail.stability.linear`). The critical speed ``V_c(p)`` solves
``g(V_c, p) = 0``; by the implicit function theorem

    dV_c/dp = -(dg/dp) / (dg/dV),

and each partial of an eigenvalue is ``w^H (dA) v / (w^H v)`` with its right and left
eigenvectors ``v``, ``w``, the derivative ``dA`` of the state matrix along the speed or
a parameter taken by forward-mode differentiation of ``A`` itself.
"""

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from ..vehicles.loads import resolve_contact_model
from ..vehicles.parameters import (check_contact_follows, get_values, parameter,
                                   set_values_and_track)
from .curving import SteadyCurving
from .linear import (check_track, comoving_rhs, is_one_arc, linear_system, modes,
                     state_size, steady_motion)

SPEED_TOLERANCE = 1e-7  # the root solve stops when a step moves the speed less (relative)
MAX_ITERATIONS = 60


@dataclasses.dataclass(frozen=True)
class SpeedPoint:
    """The hunting mode at one speed: ``speed`` [m/s], ``eigenvalue`` [1/s],
    ``frequency_hz``, ``damping_ratio`` [-] and ``hunting_share`` [-]."""

    speed: float
    eigenvalue: complex
    frequency_hz: float
    damping_ratio: float
    hunting_share: float


class LinearStability:
    """The linear stability of one vehicle on one straight track or one circular arc
    (about the steady curving state, :mod:`jaxrail.stability.curving`), compiled once:
    the speed and every named parameter are traced.

    ``LinearStability(vehicle, params, track, model=None)``; ``model``: the contact
    model (default the paper's search, or a :class:`~jaxrail.vehicles.TableContact`).
    """

    def __init__(self, vehicle, params, track, model=None):
        check_track(track)
        self.vehicle, self.params, self.track = vehicle, params, track
        self.model = resolve_contact_model(model)
        model = self.model
        # the steady motion and the matrices about it: on straight track one program (the
        # rest pose's solve and the Jacobian; two programs compiled the model twice); in
        # a curve the steady curving state's Newton iteration, then the matrices' program
        self.curving = None
        system = lambda params, steady: linear_system(vehicle, params, track, steady,  # noqa: E731
                                                      model)
        if is_one_arc(track):
            self.curving = SteadyCurving(vehicle, params, track, model)
            matrices = eqx.filter_jit(system)

            def about(params, speed):
                steady = self.curving(speed, params).steady
                return steady, *matrices(params, steady)
        else:
            def motion_and_matrices(params, speed):
                steady = steady_motion(vehicle, params, track, speed, model)
                return steady, *system(params, steady)

            about = eqx.filter_jit(motion_and_matrices)
        self._about = about
        self._derivatives = {}

    def matrices(self, speed, params=None):
        """``(A, C)`` at ``speed`` [m/s] (:func:`~jaxrail.stability.linear.linear_system`)."""
        return self.steady_and_matrices(speed, params)[1:]

    def steady_and_matrices(self, speed, params=None):
        """``(steady motion, A, C)`` at ``speed`` [m/s]: the
        :class:`~jaxrail.stability.linear.SteadyMotion` the matrices are taken about."""
        params = self.params if params is None else params
        return self._about(params, jnp.asarray(speed, jnp.float64))

    def modes(self, speed, params=None):
        """:class:`~jaxrail.stability.linear.Modes` at ``speed`` [m/s]."""
        params = self.params if params is None else params
        return modes(self.vehicle, params, *self.matrices(speed, params))

    def hunting(self, speed, params=None) -> SpeedPoint:
        """The least damped hunting mode at ``speed`` [m/s]."""
        m = self.modes(speed, params)
        k = m.hunting()
        return SpeedPoint(float(speed), complex(m.eigenvalues[k]), float(m.frequency_hz[k]),
                          float(m.damping_ratio[k]), float(m.hunting_share[k]))

    def sweep(self, speeds, params=None) -> list[SpeedPoint]:
        """:meth:`hunting` at each of ``speeds`` [m/s] (the root locus)."""
        return [self.hunting(v, params) for v in speeds]

    def critical_speed(self, low, high, params=None, points=None) -> SpeedPoint:
        """The speed in ``[low, high]`` [m/s] where the hunting mode's real part crosses
        zero from below: the first interval of ``points`` (a sweep over the range,
        default 5 speeds) that brackets it, narrowed by the Illinois (regula falsi)
        method until a step moves the speed by less than :data:`SPEED_TOLERANCE`. ValueError, with the damping at both ends, if the range
        does not bracket a crossing."""
        if not (math.isfinite(low) and math.isfinite(high) and 0.0 < low < high):
            raise ValueError(f"speed range: need 0 < low < high [m/s], got {low}, {high}")
        points = self.sweep(np.linspace(low, high, 5), params) if points is None else points
        if len(points) < 2:
            raise ValueError(f"critical speed: need at least 2 points, got {len(points)}")
        for left, right in zip(points[:-1], points[1:]):
            if left.eigenvalue.real < 0.0 <= right.eigenvalue.real:
                return self._refine(left, right, params)
        first, last = points[0], points[-1]
        raise ValueError(
            f"speed range {first.speed:g}-{last.speed:g} m/s does not bracket the hunting "
            f"mode's crossing: its damping ratio is {first.damping_ratio:.4g} at "
            f"{first.speed:g} m/s and {last.damping_ratio:.4g} at {last.speed:g} m/s")

    def _refine(self, a, b, params):
        """Illinois iteration on a bracket ``a`` (Re < 0), ``b`` (Re >= 0)."""
        fa, fb = a.eigenvalue.real, b.eigenvalue.real
        replaced, previous = 0, None
        for _ in range(MAX_ITERATIONS):
            speed = (a.speed * fb - b.speed * fa) / (fb - fa)
            point = self.hunting(speed, params)
            f = point.eigenvalue.real
            if f == 0.0 or (previous is not None
                            and abs(speed - previous) < SPEED_TOLERANCE * speed):
                return point
            previous = speed
            if f < 0.0:
                a, fa = point, f
                fb = 0.5 * fb if replaced == -1 else fb
                replaced = -1
            else:
                b, fb = point, f
                fa = 0.5 * fa if replaced == 1 else fa
                replaced = 1
        raise ValueError(f"critical speed: no convergence in {MAX_ITERATIONS} iterations "
                         f"between {a.speed:g} and {b.speed:g} m/s")

    def critical_speed_gradient(self, point: SpeedPoint, names, params=None) -> dict:
        """``{name: dV_c/d(value)}`` [m/s per unit of the parameter] at the crossing
        ``point`` (:meth:`critical_speed`), by implicit differentiation (module
        docstring). ``names``: named parameters (:mod:`jaxrail.vehicles.parameters`);
        ValueError lists the known ones."""
        names = tuple(names)
        for name in names:
            parameter(name, self.vehicle, self.params)
        check_contact_follows(names, self.model.name)
        if self.curving is not None:
            raise ValueError("the critical speed's gradient is implemented on straight "
                             "track only (in a curve the steady curving state would need "
                             "differentiating too)")
        params = self.params if params is None else params
        values = get_values(self.vehicle, params, names, self.track)
        x = jnp.concatenate([jnp.asarray([point.speed], jnp.float64), values])
        steady, a, c = self._about(params, x[0])
        flat_steady, unravel = ravel_pytree(steady)
        programs = self._derivatives.get(names)
        if programs is None:
            vehicle, track, model = self.vehicle, self.track, self.model
            z0 = jnp.zeros(state_size(vehicle))

            def product(x, flat_steady, params, direction):
                params, moved = set_values_and_track(vehicle, params, track, names, x[1:])
                rhs = lambda z: comoving_rhs(z, vehicle, params, moved,  # noqa: E731
                                             unravel(flat_steady), model)
                return jax.jvp(rhs, (z0,), (direction,))[1]

            def steady_of(x, params):
                params, moved = set_values_and_track(vehicle, params, track, names, x[1:])
                return ravel_pytree(steady_motion(vehicle, params, moved, x[0], model))[0]

            # two programs: the steady motion's derivative (through the rest pose's
            # solve) and the partials of A v about a given steady motion
            programs = (eqx.filter_jit(jax.jacfwd(product, argnums=(0, 1))),
                        eqx.filter_jit(jax.jacfwd(steady_of)))
            self._derivatives[names] = programs
        m = modes(self.vehicle, params, a, c)
        k = m.hunting()
        right = m.vectors[:, k]
        left = _left_vector(np.asarray(a), m.eigenvalues[k])
        steady_rate = np.asarray(programs[1](x, params))

        def total(direction):
            """d(A direction)/dx (N, 1 + k), the steady motion's change included."""
            by_x, by_steady = programs[0](x, flat_steady, params, jnp.asarray(direction))
            return np.asarray(by_x) + np.asarray(by_steady) @ steady_rate

        d_av = total(right.real) + 1j * total(right.imag)
        partials = np.real(left.conj() @ d_av / np.vdot(left, right))
        if not np.all(np.isfinite(partials)) or partials[0] == 0.0:
            raise ValueError(f"critical speed gradient: the hunting mode's real part does "
                             f"not cross zero transversally at {point.speed:g} m/s (its "
                             f"rate with speed is {partials[0]:.3g} 1/s per m/s)")
        return {name: float(-partials[1 + i] / partials[0]) for i, name in enumerate(names)}


def _left_vector(a, eigenvalue):
    """Left eigenvector w of ``a`` for ``eigenvalue`` (w^H a = eigenvalue w^H)."""
    u, _, _ = np.linalg.svd(a - eigenvalue * np.eye(a.shape[0]))
    return u[:, -1]
